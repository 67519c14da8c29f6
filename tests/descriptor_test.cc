// Tests of the LSGD descriptor (include/lsgd/descriptor.h): one 256-bin
// histogram per superpixel-grid cell, built from a segmentation.
#include "lsgd/descriptor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/image.h"
#include "lsgd/segmentation.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::random_image;
using test::splitmix64;
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
  for (const auto& wh : {std::pair{96, 64}, std::pair{97, 61}, std::pair{5, 5}, std::pair{1, 1},
                         std::pair{1, 400}}) {
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
  for (std::size_t i = 0; i < img.pixels.size(); ++i)
    img.pixels[i] = static_cast<std::uint8_t>(i % 256);
  Segmentation seg;
  seg.grid = {1, 1};
  seg.width = img.width;
  seg.height = img.height;
  seg.labels.assign(img.pixels.size(), 0);
  seg.centres.resize(1);
  Descriptor d = describe(img, seg);
  EXPECT_EQ(d.pixels[0], 90000u);
  EXPECT_EQ(d.hist[0], 352u);  // 90000 = 351 * 256 + 144: bins 0..143 hold 352
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

// ---- segment_and_describe: the fused path against segment() + describe()

// Expects segment_and_describe() to give exactly what segment() then
// describe() give: labels, centres (bit for bit) and histograms. `out` and
// `seg` may hold a previous result (reuse).
void expect_fused_equals_reference(const GrayImage& image, const SegmentationOptions& o,
                                   Segmentation& seg, Descriptor& out) {
  const Segmentation ref_seg = Segmenter(o).segment(image);
  const Descriptor ref = describe(image, ref_seg);
  Segmenter segmenter(o);
  segment_and_describe(segmenter, image, seg, out);
  test::expect_same_segmentation(seg, ref_seg);
  EXPECT_EQ(out.grid, ref.grid);
  EXPECT_EQ(out.storage, HistogramStorage::kExact);
  EXPECT_EQ(out.hist, ref.hist);
  EXPECT_EQ(out.pixels, ref.pixels);
  EXPECT_TRUE(out.compact.empty());
  EXPECT_EQ(out.cell_pixels, 0.0);
  EXPECT_NO_THROW(out.check_consistent("fused"));
}

void expect_fused_equals_reference(const GrayImage& image, const SegmentationOptions& o) {
  Segmentation seg;
  Descriptor out;
  expect_fused_equals_reference(image, o, seg, out);
}

SegmentationOptions fused_options(int superpixel_size, int iterations,
                                  double intensity_scale = 20.0) {
  SegmentationOptions o;
  o.superpixel_size = superpixel_size;
  o.iterations = iterations;
  o.intensity_scale = intensity_scale;
  o.working_side = 0;  // at the image's own size (the working size: working_side_test.cc)
  return o;
}

// Gradient: intensity (a x + b y) mod 256, long runs of equal neighbours in x
// when a is 0.
GrayImage gradient_image(int width, int height, int a, int b) {
  GrayImage g = uniform_image(width, height, 0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      g.pixels[static_cast<std::size_t>(y) * width + x] =
          static_cast<std::uint8_t>((a * x + b * y) & 0xFF);
    }
  }
  return g;
}

// A street-like frame: a sky gradient, facades of flat shades with darker
// windows on both sides, a flat road, and sensor noise of +-3 (seeded).
GrayImage street_image(int width, int height, std::uint64_t seed) {
  GrayImage g = uniform_image(width, height, 0);
  std::uint64_t s = seed;
  std::vector<int> facade(static_cast<std::size_t>(width)), top(static_cast<std::size_t>(width));
  for (int x = 0; x < width;) {  // buildings 40..200 pixels wide
    const int w = 40 + static_cast<int>(splitmix64(s) % 160);
    const int shade = 60 + static_cast<int>(splitmix64(s) % 150);
    const int roof = height / 10 + static_cast<int>(splitmix64(s) % (height / 3 + 1));
    for (int i = x; i < std::min(width, x + w); ++i) facade[i] = shade, top[i] = roof;
    x += w;
  }
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      int v;
      if (y > height * 3 / 4) {
        v = 90;  // road
      } else if (y < top[x]) {
        v = 200 + 40 * y / height;  // sky
      } else {
        const bool window = (x / 7) % 3 == 1 && (y / 9) % 3 == 1;
        v = window ? facade[x] / 3 : facade[x];
      }
      v += static_cast<int>(splitmix64(s) % 7) - 3;
      g.pixels[static_cast<std::size_t>(y) * width + x] =
          static_cast<std::uint8_t>(std::clamp(v, 0, 255));
    }
  }
  return g;
}

TEST(SegmentAndDescribe, EqualsSegmentThenDescribeOnRandomImagesOfManySizes) {
  const int sizes[][2] = {{1, 1},  {2, 3},  {3, 1},  {1, 3},   {5, 5},   {7, 2},   {17, 13},
                          {31, 9}, {1, 50}, {50, 1}, {96, 64}, {97, 61}, {33, 47}, {257, 129}};
  std::uint64_t seed = 500;
  for (int sp : {2, 3, 5, 8, 40}) {
    for (int iterations : {1, 3}) {
      for (const auto& wh : sizes) {
        SCOPED_TRACE(testing::Message()
                     << wh[0] << "x" << wh[1] << " sp " << sp << " it " << iterations);
        expect_fused_equals_reference(random_image(wh[0], wh[1], ++seed),
                                      fused_options(sp, iterations));
      }
    }
  }
}

TEST(SegmentAndDescribe, EqualsSegmentThenDescribeOnStructuredImages) {
  for (const auto& [w, h, sp] : {std::tuple{1241, 376, 40}, std::tuple{320, 240, 40},
                                 std::tuple{640, 480, 25}, std::tuple{161, 97, 8}}) {
    SCOPED_TRACE(testing::Message() << w << "x" << h << " sp " << sp);
    expect_fused_equals_reference(street_image(w, h, w + h), fused_options(sp, 3));
    expect_fused_equals_reference(street_image(w, h, 7), fused_options(sp, 10, 2.3));
    expect_fused_equals_reference(gradient_image(w, h, 0, 1), fused_options(sp, 3));
    expect_fused_equals_reference(gradient_image(w, h, 3, 2), fused_options(sp, 3));
    expect_fused_equals_reference(uniform_image(w, h, 77), fused_options(sp, 3));
  }
  // Windows covering the whole image: one or a few cells.
  expect_fused_equals_reference(street_image(60, 40, 3), fused_options(40, 3));
  expect_fused_equals_reference(street_image(90, 20, 4), fused_options(40, 3));
}

// Images where some pixels lie outside every window in the last iteration
// and join the nearest centre (test::kUnreachedPixelCases, shared with segmentation_test.cc,
// checked here to still have such pixels): their counts must be in the
// histograms too.
TEST(SegmentAndDescribe, EqualsSegmentThenDescribeWithUnreachedPixels) {
  int unreached = 0;
  for (const test::UnreachedPixelCase& c : test::kUnreachedPixelCases) {
    SCOPED_TRACE(testing::Message() << c.w << "x" << c.h << " sp " << c.sp);
    const GrayImage img = test::two_level_image(c.w, c.h);
    const SegmentationOptions o = fused_options(c.sp, c.iterations, c.intensity_scale);
    expect_fused_equals_reference(img, o);
    // Count the pixels outside every window of the last iteration's centres
    // (those of a run with one iteration fewer).
    const Segmentation prev =
        Segmenter(fused_options(c.sp, c.iterations - 1, c.intensity_scale)).segment(img);
    const int half_w = c.w / prev.grid.cols, half_h = c.h / prev.grid.rows;
    for (int y = 0; y < c.h; ++y) {
      for (int x = 0; x < c.w; ++x) {
        bool reached = false;
        for (const Centre& ctr : prev.centres) {
          reached |= std::abs(x - std::lround(ctr.x)) <= half_w &&
                     std::abs(y - std::lround(ctr.y)) <= half_h;
        }
        unreached += !reached;
      }
    }
  }
  EXPECT_GT(unreached, 0) << "the cases no longer exercise unreached pixels";
}

// Real frames (corridor, nordland) when ../shared/datasets is present.
TEST(SegmentAndDescribe, EqualsSegmentThenDescribeOnDatasetFrames) {
  namespace fs = std::filesystem;
  const fs::path root = fs::path(LSGD_SHARED_DIR) / "datasets";
  int frames = 0;
  for (const char* dir : {"corridor/images", "nordland-trimmed/summer"}) {
    if (!fs::is_directory(root / dir)) continue;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(root / dir)) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (std::size_t i = 0; i < files.size(); i += std::max<std::size_t>(1, files.size() / 4)) {
      const cv::Mat m = cv::imread(files[i].string(), cv::IMREAD_GRAYSCALE);
      if (m.empty()) continue;
      SCOPED_TRACE(files[i].string());
      expect_fused_equals_reference(to_gray(m), fused_options(40, 3));
      ++frames;
    }
  }
  if (frames == 0) GTEST_SKIP() << "no dataset frames under " << root << " (../shared is absent)";
}

// Cells of more than 65535 pixels: counted exactly while no bin passes 65535,
// saturated beyond, as describe() does.
TEST(SegmentAndDescribe, LargeCellsCountExactlyAndSaturate) {
  GrayImage img = uniform_image(300, 300, 0);  // S_p 200: one cell of 90000 pixels
  for (std::size_t i = 0; i < img.pixels.size(); ++i)
    img.pixels[i] = static_cast<std::uint8_t>(i % 256);
  Segmentation seg;
  Descriptor d;
  expect_fused_equals_reference(img, fused_options(200, 3), seg, d);
  EXPECT_EQ(d.pixels[0], 90000u);
  EXPECT_EQ(d.hist[0], 352u);
  std::fill(img.pixels.begin(), img.pixels.end(), 7);
  expect_fused_equals_reference(img, fused_options(200, 3), seg, d);
  EXPECT_EQ(d.hist[7], 65535u);  // saturated, not 90000 mod 65536
  EXPECT_EQ(d.hist[6], 0u);
}

TEST(SegmentAndDescribe, ReusesOutputsAndResets) {
  Segmentation seg;
  Descriptor out;
  compact(describe(random_image(96, 64, 40), segment(random_image(96, 64, 40), 8)), out);
  ASSERT_EQ(out.storage, HistogramStorage::kCompact);
  // A compact descriptor, then a larger grid, then a smaller one, then the first again.
  expect_fused_equals_reference(random_image(96, 64, 41), fused_options(8, 3), seg, out);
  expect_fused_equals_reference(random_image(200, 150, 42), fused_options(8, 3), seg, out);
  expect_fused_equals_reference(random_image(40, 30, 43), fused_options(8, 3), seg, out);
  expect_fused_equals_reference(random_image(96, 64, 41), fused_options(8, 3), seg, out);
  // One Segmenter and one scratch for many frames of changing sizes, as the
  // detector does (the scratch keeps the previous frame's histograms and runs).
  Segmenter segmenter(fused_options(8, 3));
  DescribeScratch scratch;
  for (std::uint64_t i = 0; i < 6; ++i) {
    const GrayImage img = street_image(i % 2 ? 160 + 10 * static_cast<int>(i) : 90, 90, i);
    segment_and_describe(segmenter, img, seg, out, scratch);
    const Segmentation ref_seg = Segmenter(fused_options(8, 3)).segment(img);
    EXPECT_EQ(seg.labels, ref_seg.labels);
    EXPECT_EQ(out.hist, describe(img, ref_seg).hist);
  }
}

TEST(SegmentAndDescribe, InvalidImageThrows) {
  Segmenter segmenter;
  Segmentation seg;
  Descriptor out;
  EXPECT_THROW(segment_and_describe(segmenter, GrayImage{}, seg, out), InvalidArgument);
  GrayImage bad = uniform_image(10, 10, 3);
  bad.pixels.resize(50);
  EXPECT_THROW(segment_and_describe(segmenter, bad, seg, out), InvalidArgument);
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
