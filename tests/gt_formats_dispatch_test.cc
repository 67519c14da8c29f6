// Ground-truth formats told by content, their names, a format registered
// from outside the library, options, load_groundtruth's dispatch and
// statistics (eval/gt_formats.h).
#include "lsgd/eval/gt_formats.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
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

using gt_formats_test_support::brute_force;
using gt_formats_test_support::contains;
using gt_formats_test_support::kTmp;
using gt_formats_test_support::Layout;
using gt_formats_test_support::Pairs;
using gt_formats_test_support::pairs_of;
using gt_formats_test_support::pose_line;
using gt_formats_test_support::write_dense_u8;
using gt_formats_test_support::write_file;

TEST(DetectGtFormat, TellsEachFormatByContent) {
  using lsgd::eval::detect_gt_format;
  EXPECT_EQ(detect_gt_format(write_file("d-pairs", "# c\n12 2\n13 3\n\n4 30\n").string()),
            std::string(lsgd::eval::kPairsGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-pairs-tab", "5\t1\n9\t2\n").string()), std::string(lsgd::eval::kPairsGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-li", "0\t-1\n1\t-1\n2\t0\n").string()),
            std::string(lsgd::eval::kLoopinfGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-li-space", "0 -1\n1 -1\n").string()),
            std::string(lsgd::eval::kLoopinfGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-li-tab", "0\t3\n1\t4\n2\t5\n").string()),
            std::string(lsgd::eval::kLoopinfGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-12", pose_line(1, 2, 3, false)).string()),
            std::string(lsgd::eval::kKittiPosesGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-13", pose_line(1, 2, 3, true)).string()),
            std::string(lsgd::eval::kKittiPosesGtFormat));
  EXPECT_EQ(detect_gt_format(write_dense_u8("d.dat", Layout::kLower, true).string()),
            std::string(lsgd::eval::kMatGtFormat));  // by the header, whatever the name
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"d-three", "1 2 3\n"},
           {"d-empty", ""},
           {"d-comments", "# only\n\n"},
           {"d-mixed", "1 2\n1 2 3\n"},
           {"d-words", "a b\n"},
           {"d-neg", "3 -1\n4 -1\n"},  // -1 but not one line per frame
           {"d-binary", std::string("\x01\x00\x02\x03", 4)}}) {
    const fs::path p = write_file(name, text);
    const std::string e = message_of<lsgd::FormatError>([&] { detect_gt_format(p.string()); });
    EXPECT_TRUE(contains(e, p.string())) << name << ": " << e;
  }
  EXPECT_THROW(detect_gt_format((kTmp / "absent").string()), lsgd::IoError);
}

TEST(GtFormatNames, RoundTripAndRejectUnknown) {
  for (const char* f : {"auto", "pairs", "mat", "kitti-poses", "loopinf"}) {
    EXPECT_EQ(lsgd::eval::parse_gt_format(f), f);
  }
  const std::vector<std::string> names = lsgd::eval::gt_format_names();
  ASSERT_GE(names.size(), 5u);
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + 5),
            (std::vector<std::string>{"auto", "pairs", "mat", "kitti-poses", "loopinf"}));
  const std::string e =
      message_of<lsgd::InvalidArgument>([] { lsgd::eval::parse_gt_format("matlab"); });
  EXPECT_TRUE(contains(e, "'matlab'")) << e;
  EXPECT_TRUE(contains(e, "auto, pairs, mat, kitti-poses")) << e;
}

// docs/design.md's recipe from outside the library: a format of one's own
// ("ranges": "q first last" per line, q revisits every frame first..last),
// registered, detected by "auto" before the built-in formats, read by name.
GroundTruth read_ranges(const std::string& path, const lsgd::eval::GtOptions& options) {
  std::ifstream in(path);
  std::string tag;
  std::getline(in, tag);  // "# ranges"
  std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
  std::int64_t q = 0, first = 0, last = 0, frames = 0;
  while (in >> q >> first >> last) {
    for (std::int64_t m = first; m <= last; ++m) pairs.emplace_back(q, m);
    frames = std::max(frames, q + 1);
  }
  GroundTruth gt(options.frames >= 0 ? options.frames : frames);
  for (const auto& [a, b] : pairs) gt.add(a, b);
  return gt;
}
bool detect_ranges(const std::string& path) {
  std::ifstream in(path);
  std::string tag;
  return std::getline(in, tag) && tag == "# ranges";
}

TEST(GtFormatRegistry, AFormatRegisteredFromOutsideIsDetectedAndRead) {
  static const bool registered = [] {
    lsgd::eval::register_gt_format({"ranges", "'q first last' per line", read_ranges, detect_ranges});
    return true;
  }();
  ASSERT_TRUE(registered);
  // Three integers a line would fit no built-in format; "auto" asks "ranges" first.
  const fs::path p = write_file("ranges.txt", "# ranges\n9 2 4\n12 5 5\n");
  EXPECT_EQ(lsgd::eval::detect_gt_format(p.string()), "ranges");
  const GroundTruth gt = lsgd::eval::load_groundtruth(p.string());
  EXPECT_EQ(gt.frames(), 13);
  EXPECT_EQ(gt.pairs(), 4);
  EXPECT_TRUE(gt.is_loop(9, 3));
  lsgd::eval::GtOptions by_name;
  by_name.format = lsgd::eval::parse_gt_format("ranges");
  by_name.frames = 20;
  EXPECT_EQ(lsgd::eval::load_groundtruth(p.string(), by_name).frames(), 20);
  // A built-in file is still told apart as before.
  EXPECT_EQ(lsgd::eval::detect_gt_format(write_file("r-pairs", "5 1\n").string()), "pairs");
  const std::vector<std::string> names = lsgd::eval::gt_format_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "ranges"), names.end());
  EXPECT_TRUE(contains(message_of<lsgd::InvalidArgument>([] {
                         lsgd::eval::register_gt_format({"ranges", "again", read_ranges});
                       }),
                       "already registered"));
  EXPECT_TRUE(contains(message_of<lsgd::InvalidArgument>([] {
                         lsgd::eval::register_gt_format({"auto", "no", read_ranges});
                       }),
                       "'auto' is not a ground-truth format name"));
}

TEST(GtOptions, CheckNamesTheField) {
  lsgd::eval::GtOptions o;
  EXPECT_NO_THROW(o.check());
  o.frames = -2;
  EXPECT_TRUE(contains(message_of<lsgd::InvalidArgument>([&] { o.check(); }), "frames"));
  o = {};
  o.poses_distance = 0;
  EXPECT_TRUE(contains(message_of<lsgd::InvalidArgument>([&] { o.check(); }), "poses_distance"));
  o = {};
  o.poses_min_gap = -1;
  EXPECT_TRUE(contains(message_of<lsgd::InvalidArgument>([&] { o.check(); }), "poses_min_gap"));
}

TEST(LoadGroundtruth, DispatchesAndTakesFramesFromTheFile) {
  lsgd::eval::GtOptions o;
  const fs::path pairs = write_file("l-pairs.txt", "12 2\n3 13\n");
  GroundTruth gt = lsgd::eval::load_groundtruth(pairs.string(), o);
  EXPECT_EQ(gt.frames(), 14);  // max id + 1
  EXPECT_EQ(pairs_of(gt), (Pairs{{12, 2}, {13, 3}}));
  o.frames = 20;
  EXPECT_EQ(lsgd::eval::load_groundtruth(pairs.string(), o).frames(), 20);
  o.frames = 10;
  EXPECT_THROW(lsgd::eval::load_groundtruth(pairs.string(), o), lsgd::FormatError);

  std::string walk;
  for (int i = 0; i < 30; ++i) walk += pose_line(i < 15 ? i : 29 - i, 0, 0, true, i);
  const fs::path poses = write_file("l-poses.txt", walk);
  o = {};
  o.poses_distance = 0.5;
  o.poses_min_gap = 2;
  gt = lsgd::eval::load_groundtruth(poses.string(), o);
  EXPECT_EQ(pairs_of(gt), brute_force(lsgd::eval::read_kitti_poses(poses.string()), 0.5, 2));
  EXPECT_EQ(gt.pairs(), 14);  // i and 29 - i, i < 14 (14 and 15 are 1 frame apart)
  o.frames = 31;
  EXPECT_THROW(lsgd::eval::load_groundtruth(poses.string(), o), lsgd::FormatError);

  o = {};
  o.format = std::string(lsgd::eval::kLoopinfGtFormat);  // forced: the detector would say pairs
  const fs::path li = write_file("l-li.txt", "0\t2\n1\t3\n2\t0\n3\t1\n");
  EXPECT_EQ(pairs_of(lsgd::eval::load_groundtruth(li.string(), o)), (Pairs{{2, 0}, {3, 1}}));
  o.format = std::string(lsgd::eval::kMatGtFormat);
  EXPECT_THROW(lsgd::eval::load_groundtruth(li.string(), o), lsgd::FormatError);
  o = {};
  o.poses_distance = -1;
  EXPECT_THROW(lsgd::eval::load_groundtruth(li.string(), o), lsgd::InvalidArgument);
}

// A UTF-8 byte-order mark (Windows editors) at the start of a text ground
// truth is not part of its first number, in every text format.
TEST(LoadGroundtruth, AByteOrderMarkIsSkippedInEveryTextFormat) {
  const std::string bom = "\xEF\xBB\xBF";
  lsgd::eval::GtOptions o;
  const fs::path pairs = write_file("bom-pairs.txt", bom + "12 2\n13 3\n");
  EXPECT_EQ(lsgd::eval::detect_gt_format(pairs.string()), std::string(lsgd::eval::kPairsGtFormat));
  EXPECT_EQ(pairs_of(lsgd::eval::load_groundtruth(pairs.string(), o)), (Pairs{{12, 2}, {13, 3}}));
  EXPECT_EQ(pairs_of(lsgd::eval::read_pairs(pairs.string(), 20)), (Pairs{{12, 2}, {13, 3}}));
  const fs::path li = write_file("bom-li.txt", bom + "0\t2\n1\t3\n2\t0\n3\t1\n");
  o.format = std::string(lsgd::eval::kLoopinfGtFormat);
  EXPECT_EQ(pairs_of(lsgd::eval::load_groundtruth(li.string(), o)), (Pairs{{2, 0}, {3, 1}}));
  const fs::path poses = write_file("bom-poses.txt", bom + pose_line(1, 2, 3, false));
  const auto p = lsgd::eval::read_kitti_poses(poses.string());
  ASSERT_EQ(p.size(), 1u);
  EXPECT_DOUBLE_EQ(p[0].x, 1);
}

// A frame id or count from a file is bounded before memory is committed: a
// 12-byte file naming frame 199,999,999 is a FormatError naming the file and
// the id, not an allocation of gigabytes; a pipe is refused, not waited on.
TEST(LoadGroundtruth, HugeIdsAndSpecialFilesAreRefused) {
  lsgd::eval::GtOptions o;
  const fs::path huge = write_file("huge.txt", "199999999 0\n");
  const std::string m = message_of<lsgd::FormatError>(
      [&] { lsgd::eval::load_groundtruth(huge.string(), o); });
  EXPECT_NE(m.find(huge.string()), std::string::npos) << m;
  EXPECT_NE(m.find("199999999"), std::string::npos) << m;
  o.frames = lsgd::kMaxFrames + 1;
  EXPECT_THROW(lsgd::eval::load_groundtruth(huge.string(), o), lsgd::InvalidArgument);
  // Up to the limit a ground truth costs what its pairs cost, not its frames.
  const fs::path far = write_file("far.txt", "9999999 3\n");
  o = {};
  const GroundTruth gt = lsgd::eval::load_groundtruth(far.string(), o);
  EXPECT_EQ(gt.frames(), lsgd::kMaxFrames);
  EXPECT_EQ(gt.queries(), (std::vector<std::int64_t>{9999999}));
  EXPECT_EQ(lsgd::eval::gt_stats(gt, 0).frames_in_loops, 2);
  const fs::path fifo = fs::path(write_file("dummy", "")).parent_path() / "pipe.txt";
  fs::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(message_of<lsgd::IoError>([&] { lsgd::eval::load_groundtruth(fifo.string(), o); })
                .find("not a regular file"),
            std::string::npos);
}

TEST(GtStats, CountsPairsPositivesAndGaps) {
  GroundTruth gt(100);
  gt.add(60, 5);   // gap 55
  gt.add(60, 50);  // gap 10
  gt.add(90, 10);  // gap 80
  gt.add(91, 89);  // gap 2
  auto s = lsgd::eval::gt_stats(gt, 50);
  EXPECT_EQ(s.frames, 100);
  EXPECT_EQ(s.pairs, 4);
  EXPECT_EQ(s.positives, 3);
  EXPECT_EQ(s.frames_in_loops, 7);
  EXPECT_EQ(s.gap_min, 2);
  EXPECT_DOUBLE_EQ(s.gap_median, 32.5);
  EXPECT_EQ(s.gap_max, 80);
  EXPECT_EQ(s.min_gap, 50);
  EXPECT_EQ(s.window_pairs, 2);
  EXPECT_EQ(s.window_positives, 2);
  gt.add(99, 0);  // gap 99: odd count, median 55
  EXPECT_DOUBLE_EQ(lsgd::eval::gt_stats(gt).gap_median, 55.0);
  EXPECT_EQ(lsgd::eval::gt_stats(gt).window_positives, 4);
  const auto empty = lsgd::eval::gt_stats(GroundTruth(3), 10);
  EXPECT_EQ(empty.pairs + empty.positives + empty.gap_max + empty.frames_in_loops, 0);
  EXPECT_THROW(lsgd::eval::gt_stats(gt, -1), lsgd::InvalidArgument);
}

}  // namespace
