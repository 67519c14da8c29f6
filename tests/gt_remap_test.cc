// Tests of ground truth remapping (eval/gt_remap.h): subsampling and the
// FAB-MAP side choices, on small ground truths checked by hand.
#include "lsgd/eval/gt_remap.h"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "lsgd/error.h"
#include "test_util.h"

namespace lsgd::eval {
namespace {

using Pairs = std::vector<std::pair<std::int64_t, std::int64_t>>;

// Every pair (q, m), q > m, ascending.
Pairs pairs_of(const GroundTruth& gt) {
  Pairs out;
  for (std::int64_t q = 0; q < gt.frames(); ++q) {
    for (std::int64_t m : gt.matches(q)) out.emplace_back(q, m);
  }
  return out;
}

GroundTruth make(std::int64_t frames, const Pairs& pairs) {
  GroundTruth gt(frames);
  for (const auto& [a, b] : pairs) gt.add(a, b);
  return gt;
}

TEST(SelectRows, NewFramesInheritTheirRowsLoops) {
  const GroundTruth gt = make(6, {{4, 0}, {5, 1}, {3, 2}});
  // frames: 0 <- row 4, 1 <- row 0, 2 <- row 1, 3 <- row 5, 4 <- row 4
  const GroundTruth out = select_rows(gt, {4, 0, 1, 5, 4});
  EXPECT_EQ(out.frames(), 5);
  // 4~0: (0,1), (4,1); 5~1: (3,2); row 4 twice: (4,0) the same place.
  EXPECT_EQ(pairs_of(out), (Pairs{{1, 0}, {3, 2}, {4, 0}, {4, 1}}));
  EXPECT_NE(test::message_of<InvalidArgument>([&] {
              select_rows(gt, {0, 6});
            }).find("row 6"),
            std::string::npos);
}

TEST(Subsample, ExactKeepsLoopsBetweenKeptFramesOnly) {
  // 12 frames; loops 8~0, 9~1 (odd: not kept with every 2), 10~2, 11~4, 6~5.
  const GroundTruth gt = make(12, {{8, 0}, {9, 1}, {10, 2}, {11, 4}, {6, 5}});
  const GroundTruth every2 = subsample(gt, 2);
  EXPECT_EQ(every2.frames(), 6);  // old 0, 2, 4, 6, 8, 10
  EXPECT_EQ(pairs_of(every2), (Pairs{{4, 0}, {5, 1}}));
  const GroundTruth odd = subsample(gt, 2, 1);  // old 1, 3, 5, 7, 9, 11
  EXPECT_EQ(odd.frames(), 6);
  EXPECT_EQ(pairs_of(odd), (Pairs{{4, 0}}));          // 9~1
  const GroundTruth window = subsample(gt, 1, 4, 8);  // old 4..8
  EXPECT_EQ(window.frames(), 5);
  EXPECT_EQ(pairs_of(window), (Pairs{{2, 1}}));  // 6~5
  const GroundTruth all = subsample(gt, 1);
  EXPECT_EQ(pairs_of(all), pairs_of(gt));
}

TEST(Subsample, BlockCountsAnyFrameOfEachBlock) {
  // every 3: blocks {0,1,2} {3,4,5} {6,7,8} {9,10,11}
  const GroundTruth gt = make(12, {{9, 1}, {10, 2}, {7, 5}, {4, 3}});
  const GroundTruth block = subsample(gt, 3, 0, -1, SubsampleMatch::kBlock);
  EXPECT_EQ(block.frames(), 4);
  EXPECT_EQ(pairs_of(block), (Pairs{{2, 1}, {3, 0}}));  // 4~3 is inside one block
  EXPECT_EQ(pairs_of(subsample(gt, 3)), (Pairs{}));     // exact: none of 0, 3, 6, 9 match
  // Blocks stop at `last` and start at `first`: 2..7 -> {2,3,4} {5,6,7}.
  const GroundTruth clipped = subsample(gt, 3, 2, 7, SubsampleMatch::kBlock);
  EXPECT_EQ(clipped.frames(), 2);
  EXPECT_EQ(pairs_of(clipped), (Pairs{}));  // 7~5 in one block, 4~3 in one block
  const GroundTruth shifted = subsample(gt, 2, 3, -1, SubsampleMatch::kBlock);
  // blocks {3,4} {5,6} {7,8} {9,10} {11}: 9~1 and 10~2 fall before first; 7~5 -> (2,1)
  EXPECT_EQ(shifted.frames(), 5);
  EXPECT_EQ(pairs_of(shifted), (Pairs{{2, 1}}));
}

TEST(Subsample, RejectsSelectionsBeyondTheGroundTruth) {
  const GroundTruth gt = make(10, {});
  EXPECT_NE(test::message_of<InvalidArgument>([&] { subsample(gt, 0); }).find("every"),
            std::string::npos);
  EXPECT_NE(test::message_of<InvalidArgument>([&] { subsample(gt, 1, 10); }).find("10 frames"),
            std::string::npos);
  EXPECT_NE(test::message_of<InvalidArgument>([&] { subsample(gt, 1, 0, 10); }).find("last = 10"),
            std::string::npos);
  EXPECT_EQ(to_string(parse_subsample_match("block")), "block");
  EXPECT_THROW(parse_subsample_match("any"), InvalidArgument);
}

// Three pairs (six images); pair 2 revisits pair 0.
TEST(FabmapGroundTruth, PerPairRowsWithEachSide) {
  const GroundTruth per_pair = make(3, {{2, 0}});
  EXPECT_EQ(pairs_of(fabmap_groundtruth(per_pair, 3, io::Side::kLeft)), (Pairs{{2, 0}}));
  EXPECT_EQ(pairs_of(fabmap_groundtruth(per_pair, 3, io::Side::kRight)), (Pairs{{2, 0}}));
  const GroundTruth both = fabmap_groundtruth(per_pair, 3, io::Side::kBoth);
  EXPECT_EQ(both.frames(), 6);
  // frames 2k, 2k+1 -> row k: 4,5 ~ 0,1, and each pair's two images are one place.
  EXPECT_EQ(pairs_of(both), (Pairs{{1, 0}, {3, 2}, {4, 0}, {4, 1}, {5, 0}, {5, 1}, {5, 4}}));
}

TEST(FabmapGroundTruth, PerImageRowsWithEachSide) {
  // Image rows: 4 (pair 2 left) ~ 0 (pair 0 left), 5 (pair 2 right) ~ 1 and ~ 0.
  const GroundTruth per_image = make(6, {{4, 0}, {5, 1}, {5, 0}});
  EXPECT_EQ(pairs_of(fabmap_groundtruth(per_image, 3, io::Side::kLeft)), (Pairs{{2, 0}}));
  EXPECT_EQ(pairs_of(fabmap_groundtruth(per_image, 3, io::Side::kRight)), (Pairs{{2, 0}}));
  EXPECT_EQ(pairs_of(fabmap_groundtruth(per_image, 3, io::Side::kBoth)), pairs_of(per_image));
  const GroundTruth left_only = make(6, {{4, 0}});
  EXPECT_EQ(pairs_of(fabmap_groundtruth(left_only, 3, io::Side::kRight)), (Pairs{}));
  EXPECT_EQ(fabmap_gt_frames(1237, GtRows::kPair), 1237);
  EXPECT_EQ(fabmap_gt_frames(1073, GtRows::kImage), 2146);
}

TEST(FabmapGroundTruth, OtherRowCountsAreFormatErrors) {
  const GroundTruth gt = make(7, {});
  const std::string message =
      test::message_of<FormatError>([&] { fabmap_groundtruth(gt, 3, io::Side::kLeft); });
  EXPECT_NE(message.find("7 rows"), std::string::npos) << message;
  EXPECT_NE(message.find("3 left/right pairs"), std::string::npos) << message;
  EXPECT_THROW(parse_gt_rows("images"), InvalidArgument);
}

}  // namespace
}  // namespace lsgd::eval
