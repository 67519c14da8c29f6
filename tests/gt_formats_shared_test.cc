// The real ground-truth files of ../shared/groundtruth (eval/gt_formats.h),
// when present (skipped with a message otherwise): published MAT files equal
// their pairs twins, loopinf and KITTI pose files read, and KITTI-00's loops
// derived from its poses against the published matrices.
#include "lsgd/eval/gt_formats.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "gt_formats_test_support.h"
#include "test_util.h"

namespace fs = std::filesystem;
using lsgd::eval::GroundTruth;
using lsgd::eval::GtFormat;
using lsgd::eval::Pose;
using lsgd::test::message_of;

namespace {

using gt_formats_test_support::contains;
using gt_formats_test_support::Pairs;
using gt_formats_test_support::pairs_of;

const fs::path kGt = fs::path(LSGD_SHARED_DIR) / "groundtruth";

// Reads a "*.pairs.txt" twin: "# source X.mat var=V dims=NxN; ..." then "row col" per nonzero.
Pairs read_twin(const fs::path& path, std::int64_t& frames) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  const auto dims = line.find("dims=");
  frames = dims == std::string::npos ? -1 : std::stoll(line.substr(dims + 5));
  Pairs out;
  std::int64_t r = 0, c = 0;
  while (in >> r >> c) out.emplace(std::max(r, c), std::min(r, c));
  return out;
}

std::vector<std::string> published_mats() {
  std::vector<std::string> files;
  const fs::path dir = kGt / "published";
  if (fs::exists(dir)) {
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      if (e.path().extension() == ".mat") files.push_back(e.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) files.push_back("");  // one test that skips with a message
  return files;
}

class PublishedMat : public ::testing::TestWithParam<std::string> {};

// Every published MAT file equals its pairs twin (pairs compared unordered:
// the twin lists (row, col) as stored, and two kn-zhang files are upper-triangular).
TEST_P(PublishedMat, EqualsItsPairsTwin) {
  if (GetParam().empty()) GTEST_SKIP() << "no published ground truth under " << kGt / "published";
  const fs::path mat = GetParam();
  fs::path twin = mat;
  twin.replace_extension(".pairs.txt");
  ASSERT_TRUE(fs::exists(twin)) << twin;
  std::int64_t frames = -1;
  const Pairs expected = read_twin(twin, frames);
  EXPECT_EQ(lsgd::eval::detect_gt_format(mat.string()), std::string(lsgd::eval::kMatGtFormat));
  EXPECT_EQ(lsgd::eval::detect_gt_format(twin.string()), std::string(lsgd::eval::kPairsGtFormat));
  const GroundTruth gt = lsgd::eval::read_mat(mat.string());
  EXPECT_EQ(gt.frames(), frames);
  EXPECT_EQ(gt.pairs(), static_cast<std::int64_t>(expected.size()));
  EXPECT_TRUE(pairs_of(gt) == expected) << mat;
  std::cout << mat.filename().string() << ": " << gt.frames() << " frames, " << gt.pairs()
            << " pairs\n";
}

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = fs::path(info.param).parent_path().filename().string() + "_" +
                     fs::path(info.param).stem().string();
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return info.param.empty() ? "absent" : name;
}

INSTANTIATE_TEST_SUITE_P(Shared, PublishedMat, ::testing::ValuesIn(published_mats()), test_name);

// Every loopinf file: detected, and each line's loop present; a loop frame
// beyond the sequence (loopinf-kitti-09.txt has two) must be named by line.
TEST(SharedLoopinf, EveryFileReadsOrNamesTheBadLine) {
  const fs::path dir = kGt / "lsgddn-loopinf";
  if (!fs::exists(dir)) GTEST_SKIP() << "LSGDDN loopinf files not found at " << dir;
  int files = 0, rejected = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string path = entry.path().string();
    std::vector<std::int64_t> loop;
    std::ifstream in(path);
    std::int64_t k = 0, j = 0;
    while (in >> k >> j) loop.push_back(j);
    const auto n = static_cast<std::int64_t>(loop.size());
    std::int64_t bad_line = 0;
    for (std::int64_t i = 0; i < n && !bad_line; ++i) bad_line = loop[i] >= n ? i + 1 : 0;
    EXPECT_EQ(lsgd::eval::detect_gt_format(path), std::string(lsgd::eval::kLoopinfGtFormat)) << path;
    ++files;
    if (bad_line) {
      ++rejected;
      const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_loopinf(path); });
      EXPECT_TRUE(contains(e, path + ":" + std::to_string(bad_line))) << e;
      std::cout << entry.path().filename().string() << ": rejected: " << e << "\n";
      continue;
    }
    const GroundTruth gt = lsgd::eval::read_loopinf(path);
    EXPECT_EQ(gt.frames(), n) << path;
    std::int64_t with_loop = 0;
    for (std::int64_t i = 0; i < n; ++i) {
      if (loop[i] < 0 || loop[i] == i) continue;
      ++with_loop;
      EXPECT_TRUE(gt.is_loop(i, loop[i])) << path << " frame " << i;
    }
    EXPECT_LE(gt.pairs(), with_loop) << path;
    EXPECT_GT(gt.pairs(), 0) << path;
  }
  EXPECT_GE(files, 5);
  EXPECT_LE(rejected, 1);
}

TEST(SharedKittiPoses, EveryFileReads) {
  const fs::path dir = kGt / "kitti-poses";
  if (!fs::exists(dir)) GTEST_SKIP() << "KITTI poses not found at " << dir;
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string path = entry.path().string();
    std::ifstream in(path);
    const auto lines = std::count(std::istreambuf_iterator<char>(in), {}, '\n');
    EXPECT_EQ(lsgd::eval::detect_gt_format(path), std::string(lsgd::eval::kKittiPosesGtFormat)) << path;
    EXPECT_EQ(static_cast<std::int64_t>(lsgd::eval::read_kitti_poses(path).size()), lines) << path;
    ++files;
  }
  EXPECT_EQ(files, 11);
  const fs::path p00 = dir / "00.txt";
  if (!fs::exists(p00)) return;
  // Line 2 of 00.txt: "0.1037359 <r00 r01 r02> -0.04690294 ... -0.02839928 ... 0.8586941".
  const auto poses = lsgd::eval::read_kitti_poses(p00.string());
  EXPECT_DOUBLE_EQ(poses[1].x, -0.04690294);
  EXPECT_DOUBLE_EQ(poses[1].y, -0.02839928);
  EXPECT_DOUBLE_EQ(poses[1].z, 0.8586941);
}

// ---- KITTI-00: loops derived from the poses vs the published matrices ------------------------

struct Overlap {
  double pair_recall = 0;      // published pairs that are derived pairs
  double pair_precision = 0;   // derived pairs that are published pairs
  double query_recall = 0;     // published positive queries that are derived positives
  double query_precision = 0;  // derived positive queries that are published positives
  double median_distance = 0;  // camera distance of the published pairs, metres
  double p95_distance = 0, max_distance = 0;
};

Overlap overlap(const Pairs& published, const Pairs& derived, const std::vector<Pose>& poses) {
  std::size_t common = 0;
  std::set<std::int64_t> qp, qd;
  std::vector<double> dist;
  for (const auto& [q, m] : published) {
    common += derived.count({q, m});
    qp.insert(q);
    const Pose &a = poses[static_cast<std::size_t>(q)], &b = poses[static_cast<std::size_t>(m)];
    dist.push_back(std::hypot(a.x - b.x, a.y - b.y, a.z - b.z));
  }
  for (const auto& pair : derived) qd.insert(pair.first);
  std::size_t qcommon = 0;
  for (std::int64_t q : qp) qcommon += qd.count(q);
  std::sort(dist.begin(), dist.end());
  return {static_cast<double>(common) / published.size(),
          static_cast<double>(common) / derived.size(),
          static_cast<double>(qcommon) / qp.size(),
          static_cast<double>(qcommon) / qd.size(),
          dist[dist.size() / 2],
          dist[dist.size() * 95 / 100],
          dist.back()};
}

TEST(Kitti00, PosesAgreeWithThePublishedMatrices) {
  const fs::path poses_file = kGt / "kitti-poses" / "00.txt";
  const std::vector<fs::path> published = {kGt / "published/kn-zhang/groundTruth_KITTI00.mat",
                                           kGt / "published/tsintotas-botw/groundTruthKITTI00.mat"};
  for (const auto& p : std::vector<fs::path>{poses_file, published[0], published[1]}) {
    if (!fs::exists(p)) GTEST_SKIP() << p << " not found (../shared is absent)";
  }
  const auto poses = lsgd::eval::read_kitti_poses(poses_file.string());
  const auto start = std::chrono::steady_clock::now();
  const GroundTruth derived_gt = lsgd::eval::groundtruth_from_poses(poses, 10.0, 100);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::cout << "KITTI-00 from poses (d = 10 m, gap = 100): " << derived_gt.pairs() << " pairs, "
            << lsgd::eval::gt_stats(derived_gt).positives << " positive queries, " << ms << " ms\n";
  EXPECT_EQ(derived_gt.pairs(), 29698);  // the figure of ../shared/docs/evaluation.md
  EXPECT_LT(ms, 1000.0);
  const Pairs derived = pairs_of(derived_gt);

  // Controls: poses 5 frames late change the count; 50 frames late must fail
  // the overlap thresholds below.
  const auto late_by = [&](std::size_t s) {
    std::vector<Pose> late(poses.begin() + static_cast<std::ptrdiff_t>(s), poses.end());
    late.resize(poses.size(), poses.back());
    return pairs_of(lsgd::eval::groundtruth_from_poses(late, 10.0, 100));
  };
  const std::size_t late5 = late_by(5).size();
  std::cout << "control: poses 5 frames late give " << late5 << " pairs\n";
  EXPECT_NE(late5, 29698u);
  const Pairs shifted = late_by(50);

  const double min_pair_recall[] = {0.62, 0.58}, min_query_recall[] = {0.95, 0.90};
  for (std::size_t k = 0; k < published.size(); ++k) {
    const GroundTruth pub = lsgd::eval::read_mat(published[k].string(), 4541);
    const Overlap o = overlap(pairs_of(pub), derived, poses);
    const Overlap c = overlap(pairs_of(pub), shifted, poses);
    std::cout << published[k].parent_path().filename().string() << "/"
              << published[k].filename().string() << ": " << pub.pairs()
              << " pairs, camera distance of its pairs: median " << o.median_distance << " m, p95 "
              << o.p95_distance << " m, max " << o.max_distance << " m; pairs: recall "
              << o.pair_recall << " precision " << o.pair_precision << "; positive queries: recall "
              << o.query_recall << " precision " << o.query_precision
              << " | control (poses 50 frames late): pair recall " << c.pair_recall << " precision "
              << c.pair_precision << "\n";
    EXPECT_GE(o.pair_recall, min_pair_recall[k]);
    EXPECT_GE(o.pair_precision, 0.68);
    EXPECT_GE(o.query_recall, min_query_recall[k]);
    EXPECT_GE(o.query_precision, 0.82);
    EXPECT_GT(o.median_distance, 4.0);
    EXPECT_LT(o.median_distance, 10.0);
    EXPECT_TRUE(c.pair_recall < min_pair_recall[k] && c.pair_precision < 0.68)
        << "the control passed: the thresholds cannot catch misaligned poses";
    // For docs/evaluation.md: how the agreement moves with the distance d.
    for (double d : {5.0, 7.5, 10.0, 12.5, 15.0, 20.0}) {
      const Pairs at_d = pairs_of(lsgd::eval::groundtruth_from_poses(poses, d, 100));
      const Overlap od = overlap(pairs_of(pub), at_d, poses);
      std::cout << "  d = " << d << " m: " << at_d.size() << " pairs; pair recall "
                << od.pair_recall << " precision " << od.pair_precision << "; query recall "
                << od.query_recall << " precision " << od.query_precision << "\n";
    }
  }
}

}  // namespace
