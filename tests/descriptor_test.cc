// Tests of the LSGD descriptor (include/lsgd/descriptor.h): one 256-bin
// histogram per superpixel-grid cell, built from a segmentation.
#include "lsgd/descriptor.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/image.h"
#include "lsgd/segmentation.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::random_image;
using test::uniform_image;

Segmentation segment(const GrayImage& image, int superpixel_size) {
  SegmentationOptions o;
  o.superpixel_size = superpixel_size;
  Segmenter s(o);
  return s.segment(image);
}

void expect_consistent(const GrayImage& image, const Segmentation& seg, const Descriptor& d) {
  const int cells = seg.grid.cells();
  ASSERT_EQ(d.grid, seg.grid);
  ASSERT_EQ(d.hist.size(), static_cast<std::size_t>(cells) * kBins);
  ASSERT_EQ(d.pixels.size(), static_cast<std::size_t>(cells));
  // Recompute by brute force from the labels.
  std::vector<Bin> hist(static_cast<std::size_t>(cells) * kBins, 0);
  std::vector<Count> pixels(cells, 0);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    ++hist[static_cast<std::size_t>(seg.labels[i]) * kBins + image.pixels[i]];
    ++pixels[seg.labels[i]];
  }
  EXPECT_EQ(d.hist, hist);
  EXPECT_EQ(d.pixels, pixels);
  std::uint64_t total = 0;
  for (int k = 0; k < cells; ++k) {
    const Bin* h = &d.hist[static_cast<std::size_t>(k) * kBins];
    const std::uint64_t sum = std::accumulate(h, h + kBins, std::uint64_t{0});
    EXPECT_EQ(sum, d.pixels[k]) << "cell " << k;
    EXPECT_EQ(static_cast<std::int64_t>(d.pixels[k]), seg.centres[k].pixels) << "cell " << k;
    total += sum;
  }
  EXPECT_EQ(total, static_cast<std::uint64_t>(image.width) * image.height);
}

TEST(Descriptor, CellSumsEqualCellPixelCounts) {
  for (const auto& wh : {std::pair{96, 64}, std::pair{97, 61}, std::pair{5, 5},
                         std::pair{1, 1}, std::pair{1, 400}}) {
    for (int sp : {2, 5, 16}) {
      SCOPED_TRACE(testing::Message() << wh.first << "x" << wh.second << " sp " << sp);
      const GrayImage img = random_image(wh.first, wh.second, wh.first * 1000 + sp);
      const Segmentation seg = segment(img, sp);
      expect_consistent(img, seg, describe(img, seg));
    }
  }
}

TEST(Descriptor, ConstantImagePutsAllMassInOneBin) {
  for (int v : {0, 1, 127, 254, 255}) {
    SCOPED_TRACE(v);
    const GrayImage img = uniform_image(96, 64, static_cast<std::uint8_t>(v));
    const Segmentation seg = segment(img, 10);
    const Descriptor d = describe(img, seg);
    expect_consistent(img, seg, d);
    for (int k = 0; k < d.grid.cells(); ++k) {
      const Bin* h = &d.hist[static_cast<std::size_t>(k) * kBins];
      EXPECT_EQ(h[v], d.pixels[k]) << "cell " << k;
      EXPECT_GT(d.pixels[k], 0u) << "cell " << k;
    }
  }
}

TEST(Descriptor, HandMadeSegmentation) {
  // 4x2 image, two cells: left half label 0, right half label 1.
  GrayImage img;
  img.width = 4;
  img.height = 2;
  img.pixels = {0, 0, 5, 255,  //
                7, 0, 5, 5};
  Segmentation seg;
  seg.grid = {1, 2};
  seg.width = 4;
  seg.height = 2;
  seg.labels = {0, 0, 1, 1,  //
                0, 0, 1, 1};
  seg.centres.resize(2);
  const Descriptor d = describe(img, seg);
  ASSERT_EQ(d.hist.size(), 2u * kBins);
  EXPECT_EQ(d.pixels, (std::vector<Count>{4, 4}));
  EXPECT_EQ(d.hist[0], 3u);
  EXPECT_EQ(d.hist[7], 1u);
  EXPECT_EQ(d.hist[kBins + 5], 3u);
  EXPECT_EQ(d.hist[kBins + 255], 1u);
  EXPECT_EQ(std::accumulate(d.hist.begin(), d.hist.end(), 0u), 8u);
  const DescriptorView v = d.view();
  EXPECT_EQ(v.cells, 2);
  EXPECT_EQ(v.hist, d.hist.data());
  EXPECT_EQ(v.pixels, d.pixels.data());
}

// Bins are 16-bit: a cell of more than 65535 pixels is still counted exactly
// while no bin passes 65535, and a fuller bin saturates instead of wrapping.
TEST(Descriptor, LargeCellsCountExactlyAndSaturate) {
  GrayImage img;
  img.width = 300;
  img.height = 300;  // 90000 pixels in one cell
  img.pixels.resize(90000);
  for (std::size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = static_cast<std::uint8_t>(i % 256);
  Segmentation seg;
  seg.grid = {1, 1};
  seg.width = img.width;
  seg.height = img.height;
  seg.labels.assign(img.pixels.size(), 0);
  seg.centres.resize(1);
  Descriptor d = describe(img, seg);
  EXPECT_EQ(d.pixels[0], 90000u);
  EXPECT_EQ(d.hist[0], 352u);    // 90000 = 351 * 256 + 144: bins 0..143 hold 352
  EXPECT_EQ(d.hist[255], 351u);
  std::fill(img.pixels.begin(), img.pixels.end(), 7);
  d = describe(img, seg);
  EXPECT_EQ(d.pixels[0], 90000u);
  EXPECT_EQ(d.hist[7], 65535u);  // saturated, not 90000 mod 65536
  EXPECT_EQ(d.hist[6], 0u);
}

TEST(Descriptor, ReusesOutputAndResets) {
  const GrayImage a = random_image(96, 64, 1);
  const GrayImage b = random_image(40, 30, 2);
  const Segmentation sa = segment(a, 8), sb = segment(b, 8);
  Descriptor out;
  describe(a, sa, out);
  describe(b, sb, out);  // smaller grid: must not keep counts of a
  expect_consistent(b, sb, out);
  describe(a, sa, out);
  EXPECT_EQ(out.hist, describe(a, sa).hist);
  EXPECT_EQ(out.pixels, describe(a, sa).pixels);
}

TEST(Descriptor, MismatchedSegmentationThrows) {
  const GrayImage a = random_image(96, 64, 3);
  const GrayImage b = random_image(64, 96, 4);  // same pixel count, other size
  const GrayImage c = random_image(96, 63, 5);
  const Segmentation sb = segment(b, 8);
  const Segmentation sc = segment(c, 8);
  EXPECT_THROW(describe(a, sb), InvalidArgument);
  EXPECT_THROW(describe(a, sc), InvalidArgument);
  Descriptor out;
  EXPECT_THROW(describe(a, sc, out), InvalidArgument);
  // Labels of the wrong length with the right nominal size.
  Segmentation broken = segment(a, 8);
  broken.labels.pop_back();
  EXPECT_THROW(describe(a, broken), InvalidArgument);
}

}  // namespace
}  // namespace lsgd

TEST(DescribeLabels, OutOfRangeLabelThrowsInsteadOfWritingPastTheHistogram) {
  lsgd::GrayImage image;
  image.width = 4;
  image.height = 2;
  image.pixels.assign(8, 100);
  lsgd::Segmentation seg;
  seg.width = 4;
  seg.height = 2;
  seg.grid = {1, 2};
  seg.labels = {0, 0, 1, 1, 0, 0, 1, 2};  // 2 is outside the 2 cells
  EXPECT_THROW(lsgd::describe(image, seg), lsgd::InvalidArgument);
  seg.labels.back() = -1;
  EXPECT_THROW(lsgd::describe(image, seg), lsgd::InvalidArgument);
  seg.labels.back() = 1;
  const lsgd::Descriptor d = lsgd::describe(image, seg);
  EXPECT_EQ(d.pixels[0], 4u);
  EXPECT_EQ(d.pixels[1], 4u);
}
