// Tests of the working size (segmentation.working_side): a frame whose
// shorter side is longer is scaled down before it is segmented and
// described, so a camera's resolution does not change the grid.
#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/image.h"
#include "lsgd/segmentation.h"
#include "test_util.h"

namespace lsgd {
namespace {

SegmentationOptions side(int working_side) {
  SegmentationOptions o;
  o.working_side = working_side;
  return o;
}

void expect_size(FrameSize s, int width, int height) {
  EXPECT_EQ(s.width, width);
  EXPECT_EQ(s.height, height);
}

TEST(WorkingSide, TheShorterSideIsScaledToItAndTheLongerInProportion) {
  expect_size(working_size(640, 480, side(240)), 320, 240);
  expect_size(working_size(480, 640, side(240)), 240, 320);  // portrait
  expect_size(working_size(960, 540, side(240)), 427, 240);  // 426.67 rounded
  expect_size(working_size(1241, 376, side(240)), 792, 240);
  expect_size(working_size(16384, 17, side(16)), 15420, 16);  // 15420.2
  expect_size(working_size(300, 300, side(240)), 240, 240);
  // Frames at or below it, and the paper's 0, keep their own size.
  expect_size(working_size(320, 240, side(240)), 320, 240);
  expect_size(working_size(240, 192, side(240)), 240, 192);
  expect_size(working_size(4000, 3000, side(0)), 4000, 3000);
  // The grid is the working size's.
  SegmentationOptions o = side(240);
  o.superpixel_size = 40;
  EXPECT_EQ(frame_grid(640, 480, o), (GridSize{4, 5}));
  EXPECT_EQ(frame_grid(640, 480, side(0)), grid_size(640, 480, 40));
  EXPECT_EQ(SegmentationOptions{}.working_side, 240);  // the default (docs/results.md)
}

TEST(WorkingSide, ZeroOrAtLeastSixteen) {
  EXPECT_NO_THROW(side(0).check());
  EXPECT_NO_THROW(side(kMinWorkingSide).check());
  EXPECT_NO_THROW(side(kMaxImageSide).check());
  for (const int bad : {-1, 1, kMinWorkingSide - 1, kMaxImageSide + 1}) {
    try {
      side(bad).check();
      ADD_FAILURE() << bad << " accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("working_side"), std::string::npos) << e.what();
    }
  }
}

// A smooth random scene (blocks of random gray, blurred), so the scaled-down
// frame has structure at every grid size.
cv::Mat scene(int width, int height, std::uint64_t seed) {
  cv::Mat blocks(height / 16 + 1, width / 16 + 1, CV_8UC1);
  std::uint64_t s = seed;
  for (int y = 0; y < blocks.rows; ++y) {
    for (int x = 0; x < blocks.cols; ++x) blocks.at<std::uint8_t>(y, x) = test::splitmix64(s) & 0xff;
  }
  cv::Mat out;
  cv::resize(blocks, out, cv::Size(width, height), 0, 0, cv::INTER_LINEAR);
  return out;
}

void expect_same(const Descriptor& a, const Descriptor& b) {
  EXPECT_EQ(a.grid, b.grid);
  EXPECT_EQ(a.storage, b.storage);
  EXPECT_EQ(a.hist, b.hist);
  EXPECT_EQ(a.pixels, b.pixels);
  EXPECT_EQ(a.compact, b.compact);
  EXPECT_EQ(a.cell_pixels, b.cell_pixels);
}

// A 640x480 frame is described as its INTER_AREA copy at 320x240 is at its
// own size, in both storages; a frame below the working side as it is.
TEST(WorkingSide, ALargeFrameIsDescribedAsItsScaledCopy) {
  for (const HistogramStorage storage : {HistogramStorage::kExact, HistogramStorage::kCompact}) {
    DetectorOptions scaled;
    scaled.descriptor.storage = storage;
    DetectorOptions own = scaled;
    own.segmentation.working_side = 0;
    Detector a(scaled), b(own);
    const cv::Mat big = scene(640, 480, 7);
    cv::Mat small;
    cv::resize(big, small, cv::Size(320, 240), 0, 0, cv::INTER_AREA);
    const Descriptor da = a.describe(big);
    expect_same(da, b.describe(small));
    EXPECT_EQ(da.grid, (GridSize{4, 5}));
    // The paper's setting describes the frame itself: 7 x 9 cells.
    EXPECT_EQ(b.describe(big).grid, (GridSize{7, 9}));
    // At or below the working side nothing changes.
    expect_same(a.describe(small), b.describe(small));
  }
}

// A described frame carries the scaled descriptor and the frame's own size
// (what the size checks and the stages go by), as a processed one.
TEST(WorkingSide, ADescribedFrameKeepsItsOwnSize) {
  DetectorOptions o;
  o.search.min_gap = 0;
  Detector d(o);
  const cv::Mat big = scene(640, 480, 11);
  d.process(big);
  const FrameDescription described = d.describe_frame(big);
  expect_same(described.descriptor, d.describe(big));
  EXPECT_EQ(described.width, 640);
  EXPECT_EQ(described.height, 480);
  EXPECT_EQ(d.width(), 640);
  EXPECT_EQ(d.height(), 480);
  EXPECT_DOUBLE_EQ(d.similarity(0, 0), 1.0);
}

}  // namespace
}  // namespace lsgd
