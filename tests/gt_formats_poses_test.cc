// KITTI poses, the loops they give (eval/gt_formats.h read_kitti_poses,
// groundtruth_from_poses) and loopinf files (read_loopinf).
#include "lsgd/eval/gt_formats.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
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

using gt_formats_test_support::brute_force;
using gt_formats_test_support::contains;
using gt_formats_test_support::kTmp;
using gt_formats_test_support::Pairs;
using gt_formats_test_support::pairs_of;
using gt_formats_test_support::pose_line;
using gt_formats_test_support::write_file;

TEST(ReadKittiPoses, TwelveAndThirteenColumns) {
  std::string twelve, thirteen;
  for (int i = 0; i < 5; ++i) {
    twelve += pose_line(i, -0.5 * i, 2.0 * i, false);
    thirteen += pose_line(i, -0.5 * i, 2.0 * i, true, 0.1 * i);
  }
  const auto a = lsgd::eval::read_kitti_poses(write_file("p12.txt", twelve).string());
  const auto b =
      lsgd::eval::read_kitti_poses(write_file("p13.txt", "# c\n" + thirteen + "\n").string());
  ASSERT_EQ(a.size(), 5u);
  ASSERT_EQ(b.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_DOUBLE_EQ(a[i].x, i);
    EXPECT_DOUBLE_EQ(a[i].y, -0.5 * i);
    EXPECT_DOUBLE_EQ(a[i].z, 2.0 * i);
    EXPECT_DOUBLE_EQ(b[i].x, a[i].x);
    EXPECT_DOUBLE_EQ(b[i].y, a[i].y);
    EXPECT_DOUBLE_EQ(b[i].z, a[i].z);
  }
}

TEST(ReadKittiPoses, ErrorsNameFileAndLine) {
  const auto expect_line = [](const std::string& name, const std::string& text, int line) {
    const fs::path p = write_file(name, text);
    const std::string e =
        message_of<lsgd::FormatError>([&] { lsgd::eval::read_kitti_poses(p.string()); });
    EXPECT_TRUE(contains(e, p.string() + ":" + std::to_string(line))) << e;
  };
  const std::string ok = pose_line(1, 2, 3, false);
  expect_line("p11.txt", ok + "1 2 3 4 5 6 7 8 9 10 11\n", 2);
  expect_line("pmix.txt", ok + ok + pose_line(1, 2, 3, true), 3);
  expect_line("pword.txt", "\n" + ok + "1 0 0 x 0 1 0 2 0 0 1 3\n", 3);
  expect_line("pinf.txt", "1 0 0 inf 0 1 0 2 0 0 1 3\n", 1);
  EXPECT_THROW(lsgd::eval::read_kitti_poses(write_file("pnone.txt", "# nothing\n").string()),
               lsgd::FormatError);
  EXPECT_THROW(lsgd::eval::read_kitti_poses((kTmp / "absent.txt").string()), lsgd::IoError);
}

TEST(GroundTruthFromPoses, MatchesBruteForceOnALoopingWalk) {
  // A walk around a 60 m square, three laps with lateral noise: many revisits.
  std::vector<Pose> poses;
  std::uint64_t seed = 3;
  for (int k = 0; k < 720; ++k) {
    const double s = std::fmod(k * 1.0, 240.0), side = std::floor(s / 60), t = s - 60 * side;
    const double noise = (static_cast<double>(lsgd::test::splitmix64(seed) % 1000) / 1000 - 0.5);
    double x = side == 0 ? t : side == 1 ? 60 : side == 2 ? 60 - t : 0;
    double z = side == 0 ? 0 : side == 1 ? t : side == 2 ? 60 : 60 - t;
    poses.push_back(
        {x + noise, 0.3 * noise - 1000, z - noise});  // far from the origin: negative cells
  }
  for (double d : {0.7, 3.0, 10.0, 25.0}) {
    for (std::int64_t gap : {0, 50, 300}) {
      const Pairs expected = brute_force(poses, d, gap);
      EXPECT_EQ(pairs_of(lsgd::eval::groundtruth_from_poses(poses, d, gap)), expected)
          << "d " << d << " gap " << gap;
      if (d == 3.0 && gap == 50) {
        EXPECT_GT(expected.size(), 1000u);
      }
    }
  }
}

TEST(GroundTruthFromPoses, BoundsAreStrict) {
  const std::vector<Pose> poses = {{0, 0, 0}, {5, 0, 0}, {0, 0, 2}, {0, 0, 0.5}};
  const auto gt = lsgd::eval::groundtruth_from_poses(poses, 2.0, 1);
  EXPECT_EQ(pairs_of(gt), (Pairs{{3, 0}}));  // (2, 0): distance 2 is not < 2; (3, 2): gap 1
  EXPECT_EQ(lsgd::eval::groundtruth_from_poses({}, 1.0, 0).frames(), 0);
  EXPECT_THROW(lsgd::eval::groundtruth_from_poses(poses, 0.0, 1), lsgd::InvalidArgument);
  EXPECT_THROW(lsgd::eval::groundtruth_from_poses(poses, std::nan(""), 1), lsgd::InvalidArgument);
  EXPECT_THROW(lsgd::eval::groundtruth_from_poses(poses, 1.0, -1), lsgd::InvalidArgument);
  EXPECT_THROW(lsgd::eval::groundtruth_from_poses({{1e300, 0, 0}}, 1.0, 0), lsgd::InvalidArgument);
}

// Any distance in range works, however small against the poses' extent
// (1e-15 m was refused blaming a valid coordinate: its cell index passed 1e15).
TEST(GroundTruthFromPoses, ATinyDistanceFindsTheFramesAtTheSamePlace) {
  std::vector<Pose> poses;
  for (int k = 0; k < 100; ++k) poses.push_back({1000.0 + 3.7 * k, -2.0, 250.0 + 0.1 * k});
  poses.push_back(poses[10]);  // frame 100 at frame 10's place exactly
  poses.push_back({1000.0 + 3.7 * 20 + 1e-9, -2.0, 250.0 + 0.1 * 20});  // 1e-9 m from frame 20
  for (double d : {1e-15, 1e-12, 1e-6}) {
    const Pairs expected = brute_force(poses, d, 5);
    EXPECT_EQ(pairs_of(lsgd::eval::groundtruth_from_poses(poses, d, 5)), expected) << d;
    EXPECT_EQ(expected, (d < 1e-9 ? Pairs{{100, 10}} : Pairs{{100, 10}, {101, 20}})) << d;
  }
}

// Poses of a robot standing still give every pair of frames: refused while
// they are added (10,000 poses were 49 M pairs, 1.3 GB), the file named;
// a coordinate beyond the range names the file too.
TEST(GroundTruthFromPoses, ABombOfPairsIsRefusedNamingTheFile) {
  std::string text;
  for (int i = 0; i < 3000; ++i) text += pose_line(1, 2, 3, false);  // 4.5 M pairs
  const fs::path p = write_file("still.txt", text);
  lsgd::eval::GtOptions o;
  o.format = lsgd::eval::kKittiPosesGtFormat;
  o.poses_min_gap = 0;
  const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::load_groundtruth(p.string(), o); });
  EXPECT_TRUE(contains(e, p.string())) << e;
  EXPECT_TRUE(contains(e, "more than 4194304 pairs")) << e;
  o.poses_min_gap = 200;  // 3.9 M pairs: held
  EXPECT_EQ(lsgd::eval::load_groundtruth(p.string(), o).pairs(), 2799 * 2800 / 2);
  const fs::path far = write_file("far.txt", "1 0 0 1e308 0 1 0 0 0 0 1 0\n");
  const std::string f = message_of<lsgd::FormatError>([&] { lsgd::eval::load_groundtruth(far.string(), o); });
  EXPECT_TRUE(contains(f, far.string()) && contains(f, "not finite or beyond 1e12 metres")) << f;
}

// ---- loopinf -------------------------------------------------------------------------

TEST(ReadLoopinf, ReadsLoopsBothWays) {
  const fs::path p = write_file("li.txt", "0\t5\n1\t-1\n2\t-1\n3\t-1\n4\t-1\n5\t0\n6\t1\n7\t-1");
  const GroundTruth gt = lsgd::eval::read_loopinf(p.string());
  EXPECT_EQ(gt.frames(), 8);
  EXPECT_EQ(pairs_of(gt), (Pairs{{5, 0}, {6, 1}}));
  EXPECT_EQ(lsgd::eval::read_loopinf(p.string(), 8).pairs(), 2);
  const std::string e =
      message_of<lsgd::FormatError>([&] { lsgd::eval::read_loopinf(p.string(), 9); });
  EXPECT_TRUE(contains(e, p.string()) && contains(e, "8") && contains(e, "9")) << e;
}

TEST(ReadLoopinf, ErrorsNameFileAndLine) {
  const auto expect_line = [](const std::string& name, const std::string& text, int line) {
    const fs::path p = write_file(name, text);
    const std::string e =
        message_of<lsgd::FormatError>([&] { lsgd::eval::read_loopinf(p.string()); });
    EXPECT_TRUE(contains(e, p.string() + ":" + std::to_string(line))) << e;
  };
  expect_line("li-order.txt", "0\t-1\n2\t-1\n", 2);
  expect_line("li-range.txt", "0\t-1\n1\t-1\n2\t3\n", 3);
  expect_line("li-neg.txt", "0\t-2\n", 1);
  expect_line("li-word.txt", "0\t-1\n1\tx\n", 2);
  expect_line("li-three.txt", "0\t-1\t4\n", 1);
  EXPECT_THROW(lsgd::eval::read_loopinf((kTmp / "absent.txt").string()), lsgd::IoError);
}

}  // namespace
