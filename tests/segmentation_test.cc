// Tests of the superpixel-grid segmentation (include/lsgd/segmentation.h):
// the grid size formula, option validation, and the invariants of the
// SLIC-style k-means (every pixel labelled, counts consistent, grid identity
// kept, determinism, no state leaking between calls).
#include "lsgd/segmentation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/image.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::message_of;
using test::random_image;
using test::splitmix64;
using test::uniform_image;

// Smooth procedural pattern (sum of sinusoids), deterministic.
GrayImage smooth_image(int width, int height, double phase) {
  GrayImage g;
  g.width = width;
  g.height = height;
  g.pixels.resize(static_cast<std::size_t>(width) * height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double v = 128 + 60 * std::sin(0.11 * x + phase) + 50 * std::cos(0.07 * y - phase);
      g.pixels[static_cast<std::size_t>(y) * width + x] =
          static_cast<std::uint8_t>(std::lround(std::min(255.0, std::max(0.0, v))));
    }
  }
  return g;
}

// Checks the structural invariants every segmentation must satisfy.
void expect_valid(const GrayImage& image, const Segmentation& s, int superpixel_size) {
  const GridSize g = grid_size(image.width, image.height, superpixel_size);
  ASSERT_EQ(s.grid, g);
  ASSERT_EQ(s.width, image.width);
  ASSERT_EQ(s.height, image.height);
  ASSERT_EQ(s.labels.size(), image.pixels.size());
  ASSERT_EQ(s.centres.size(), static_cast<std::size_t>(g.cells()));
  std::vector<std::int64_t> counts(g.cells(), 0);
  int out_of_range = 0;
  for (std::int32_t label : s.labels) {
    if (label < 0 || label >= g.cells()) {
      ++out_of_range;
      continue;
    }
    ++counts[label];
  }
  ASSERT_EQ(out_of_range, 0);
  std::int64_t total = 0;
  for (int k = 0; k < g.cells(); ++k) {
    EXPECT_EQ(s.centres[k].pixels, counts[k]) << "cell " << k;
    EXPECT_TRUE(std::isfinite(s.centres[k].x)) << "cell " << k;
    EXPECT_TRUE(std::isfinite(s.centres[k].y)) << "cell " << k;
    EXPECT_TRUE(std::isfinite(s.centres[k].intensity)) << "cell " << k;
    EXPECT_GE(s.centres[k].x, 0.0f);
    EXPECT_LE(s.centres[k].x, static_cast<float>(image.width - 1));
    EXPECT_GE(s.centres[k].y, 0.0f);
    EXPECT_LE(s.centres[k].y, static_cast<float>(image.height - 1));
    EXPECT_GE(s.centres[k].intensity, 0.0f);
    EXPECT_LE(s.centres[k].intensity, 255.0f);
    total += s.centres[k].pixels;
  }
  EXPECT_EQ(total, static_cast<std::int64_t>(image.width) * image.height);
}

SegmentationOptions options_with(int superpixel_size, int iterations = 10) {
  SegmentationOptions o;
  o.superpixel_size = superpixel_size;
  o.iterations = iterations;
  return o;
}

// ---- grid_size

TEST(GridSize, DocumentedValues) {
  EXPECT_EQ(grid_size(1241, 376, 40), (GridSize{5, 16}));
  EXPECT_EQ(grid_size(1241, 376, 40).cells(), 80);
  EXPECT_EQ(grid_size(160, 120, 40), (GridSize{2, 3}));
  EXPECT_EQ(grid_size(160, 120, 50), (GridSize{2, 2}));
  EXPECT_EQ(grid_size(64, 32, 40), (GridSize{1, 1}));
}

TEST(GridSize, FormulaOverARange) {
  for (int sp : {2, 3, 7, 10, 40, 50, 100}) {
    for (int w : {1, 2, 3, 4, 5, 79, 80, 81, 159, 160, 161, 1241}) {
      for (int h : {1, 3, 4, 39, 40, 376}) {
        const GridSize g = grid_size(w, h, sp);
        EXPECT_EQ(g.rows, h / (2 * sp) + 1) << w << "x" << h << " sp " << sp;
        EXPECT_EQ(g.cols, w / (2 * sp) + 1) << w << "x" << h << " sp " << sp;
        // Never more rows/cols than pixels.
        EXPECT_LE(g.rows, h);
        EXPECT_LE(g.cols, w);
      }
    }
  }
}

TEST(GridSize, BoundaryAtTwiceTheScale) {
  EXPECT_EQ(grid_size(79, 79, 40), (GridSize{1, 1}));
  EXPECT_EQ(grid_size(80, 80, 40), (GridSize{2, 2}));
  EXPECT_EQ(grid_size(159, 80, 40), (GridSize{2, 2}));
  EXPECT_EQ(grid_size(160, 80, 40), (GridSize{2, 3}));
}

TEST(GridSize, ImageSmallerThanTwiceScaleIsOneCell) {
  EXPECT_EQ(grid_size(1, 1, 40), (GridSize{1, 1}));
  EXPECT_EQ(grid_size(79, 10, 40), (GridSize{1, 1}));
  EXPECT_EQ(grid_size(1000, 1000, 600), (GridSize{1, 1}));
  EXPECT_EQ(grid_size(kMaxImageSide, kMaxImageSide, 4096), (GridSize{3, 3}));
  EXPECT_EQ(grid_size(100, 100, 4096), (GridSize{1, 1}));
}

// grid_size is public and documents only non-positive S_p as invalid; a huge
// S_p must give one cell, not overflow 2 * S_p (signed overflow).
TEST(GridSize, HugeScaleIsOneCell) {
  EXPECT_EQ(grid_size(100, 100, 1 << 30), (GridSize{1, 1}));
  EXPECT_EQ(grid_size(100, 100, std::numeric_limits<int>::max()), (GridSize{1, 1}));
}

TEST(GridSize, InvalidArgumentsThrow) {
  EXPECT_THROW(grid_size(0, 10, 40), InvalidArgument);
  EXPECT_THROW(grid_size(10, 0, 40), InvalidArgument);
  EXPECT_THROW(grid_size(-5, 10, 40), InvalidArgument);
  EXPECT_THROW(grid_size(10, -5, 40), InvalidArgument);
  EXPECT_THROW(grid_size(10, 10, 0), InvalidArgument);
  EXPECT_THROW(grid_size(10, 10, -1), InvalidArgument);
}

// ---- options

TEST(SegmentationOptions, DefaultsAreValid) {
  SegmentationOptions o;
  EXPECT_NO_THROW(o.check());
  EXPECT_NO_THROW(Segmenter{o});
}

TEST(SegmentationOptions, EachFieldOutOfRangeNamesTheField) {
  struct Case {
    const char* field;
    void (*mutate)(SegmentationOptions&);
  };
  const Case cases[] = {
      {"superpixel_size", [](SegmentationOptions& o) { o.superpixel_size = 1; }},
      {"superpixel_size", [](SegmentationOptions& o) { o.superpixel_size = 0; }},
      {"superpixel_size", [](SegmentationOptions& o) { o.superpixel_size = -40; }},
      {"superpixel_size", [](SegmentationOptions& o) { o.superpixel_size = 4097; }},
      {"iterations", [](SegmentationOptions& o) { o.iterations = 0; }},
      {"iterations", [](SegmentationOptions& o) { o.iterations = 101; }},
      {"intensity_scale", [](SegmentationOptions& o) { o.intensity_scale = 0.0; }},
      {"intensity_scale", [](SegmentationOptions& o) { o.intensity_scale = -1.0; }},
      {"intensity_scale", [](SegmentationOptions& o) { o.intensity_scale = 2e6; }},
      {"intensity_scale",
       [](SegmentationOptions& o) {
         o.intensity_scale = std::numeric_limits<double>::quiet_NaN();
       }},
      {"intensity_scale",
       [](SegmentationOptions& o) { o.intensity_scale = std::numeric_limits<double>::infinity(); }},
      {"distance_scale", [](SegmentationOptions& o) { o.distance_scale = 0.0; }},
      {"distance_scale", [](SegmentationOptions& o) { o.distance_scale = -0.5; }},
      {"distance_scale", [](SegmentationOptions& o) { o.distance_scale = 1e7; }},
      {"distance_scale",
       [](SegmentationOptions& o) { o.distance_scale = std::numeric_limits<double>::quiet_NaN(); }},
  };
  for (const Case& c : cases) {
    SegmentationOptions o;
    c.mutate(o);
    SCOPED_TRACE(c.field);
    EXPECT_THROW(o.check(), InvalidArgument);
    const std::string msg = message_of<InvalidArgument>([&] { o.check(); });
    EXPECT_NE(msg.find(c.field), std::string::npos) << msg;
    // The Segmenter validates its options at construction.
    EXPECT_THROW(Segmenter{o}, InvalidArgument);
  }
}

TEST(SegmentationOptions, BoundaryValuesAccepted) {
  SegmentationOptions o;
  o.superpixel_size = 2;
  o.iterations = 1;
  o.intensity_scale = 1e6;
  o.distance_scale = 1e-9;
  EXPECT_NO_THROW(o.check());
  o.superpixel_size = 4096;
  o.iterations = 100;
  o.intensity_scale = 1e-9;
  o.distance_scale = 1e6;
  EXPECT_NO_THROW(o.check());
}

TEST(Segmenter, RejectsEmptyOrInconsistentImage) {
  Segmenter s;
  GrayImage empty;
  EXPECT_THROW(s.segment(empty), InvalidArgument);
  GrayImage bad = uniform_image(10, 10, 3);
  bad.pixels.resize(50);
  EXPECT_THROW(s.segment(bad), InvalidArgument);
}

// ---- segmentation invariants

TEST(Segmenter, EveryPixelLabelledForManySizes) {
  const int sizes[][2] = {{1, 1},   {2, 3},  {3, 1},   {1, 3},   {5, 5},  {4, 4}, {7, 2},
                          {17, 13}, {31, 9}, {96, 64}, {97, 61}, {1, 50}, {50, 1}};
  std::uint64_t seed = 100;
  for (int sp : {2, 3, 5, 40}) {
    Segmenter segmenter(options_with(sp));
    for (const auto& wh : sizes) {
      SCOPED_TRACE(testing::Message() << wh[0] << "x" << wh[1] << " sp " << sp);
      const GrayImage img = random_image(wh[0], wh[1], ++seed);
      const Segmentation s = segmenter.segment(img);
      expect_valid(img, s, sp);
    }
  }
}

TEST(Segmenter, SmoothImagesValid) {
  Segmenter segmenter(options_with(8));
  for (int i = 0; i < 3; ++i) {
    const GrayImage img = smooth_image(96 + i * 7, 64 - i * 5, 0.3 * i);
    expect_valid(img, segmenter.segment(img), 8);
  }
}

TEST(Segmenter, OneIterationValid) {
  Segmenter segmenter(options_with(4, 1));
  const GrayImage img = random_image(45, 33, 7);
  expect_valid(img, segmenter.segment(img), 4);
}

TEST(Segmenter, ExtremeScalesValid) {
  // Intensity dominating and distance dominating.
  SegmentationOptions a = options_with(5);
  a.intensity_scale = 1e-6;
  SegmentationOptions b = options_with(5);
  b.distance_scale = 1e-6;
  SegmentationOptions c = options_with(5);
  c.distance_scale = 1e6;
  const GrayImage img = random_image(60, 40, 8);
  for (const auto& o : {a, b, c}) {
    Segmenter segmenter(o);
    expect_valid(img, segmenter.segment(img), 5);
  }
}

TEST(Segmenter, EmptyClustersDoNotCrash) {
  // A 1-pixel-wide image with many cells (101 rows x 1 col).
  Segmenter segmenter(options_with(2));
  const GrayImage tall = random_image(1, 400, 9);
  const Segmentation s = segmenter.segment(tall);
  EXPECT_EQ(s.grid, (GridSize{101, 1}));
  expect_valid(tall, s, 2);
  const GrayImage wide = random_image(400, 1, 10);
  expect_valid(wide, segmenter.segment(wide), 2);
  // Intensity-dominated distances on noise make clusters wander and empty.
  SegmentationOptions o = options_with(2, 20);
  o.intensity_scale = 1e-6;
  Segmenter harsh(o);
  const GrayImage noise = random_image(41, 37, 11);
  expect_valid(noise, harsh.segment(noise), 2);
  const GrayImage tall2 = random_image(1, 400, 12);
  expect_valid(tall2, harsh.segment(tall2), 2);
}

// Two-level patterns where k-means moves centres so far that, in the last
// iteration, some pixels lie outside every centre's search window (+- W/cols x
// +- H/rows around the rounded centre, algorithm.md section 2; cases found by
// instrumenting the segmenter). Such a pixel must join the centre nearest in
// position (segmentation.h), never keep label -1. The centres used by the last
// assignment are those of a run with one iteration fewer (k-means is a
// deterministic prefix).
TEST(Segmenter, PixelsOutsideEveryWindowJoinTheNearestCentre) {
  int unreached_total = 0;
  for (const test::UnreachedPixelCase& c : test::kUnreachedPixelCases) {
    SCOPED_TRACE(testing::Message() << c.w << "x" << c.h << " sp " << c.sp);
    const GrayImage img = test::two_level_image(c.w, c.h);
    SegmentationOptions o = options_with(c.sp, c.iterations);
    o.intensity_scale = c.intensity_scale;
    Segmenter segmenter(o);
    const Segmentation s = segmenter.segment(img);
    expect_valid(img, s, c.sp);
    Segmenter again(o);
    EXPECT_EQ(again.segment(img).labels, s.labels);

    SegmentationOptions before = o;
    before.iterations = c.iterations - 1;
    const Segmentation prev = Segmenter(before).segment(img);
    const GridSize g = s.grid;
    const int half_w = c.w / g.cols, half_h = c.h / g.rows;
    for (int y = 0; y < c.h; ++y) {
      for (int x = 0; x < c.w; ++x) {
        bool reached = false;
        for (const Centre& ctr : prev.centres) {
          const long cx = std::lround(ctr.x), cy = std::lround(ctr.y);
          if (std::abs(x - cx) <= half_w && std::abs(y - cy) <= half_h) reached = true;
        }
        if (reached) continue;
        ++unreached_total;
        int nearest = -1;
        float best = std::numeric_limits<float>::infinity();
        for (int k = 0; k < g.cells(); ++k) {
          const float dx = x - prev.centres[k].x, dy = y - prev.centres[k].y;
          if (dx * dx + dy * dy < best) best = dx * dx + dy * dy, nearest = k;
        }
        EXPECT_EQ(s.labels[static_cast<std::size_t>(y) * c.w + x], nearest)
            << "unreached pixel (" << x << ", " << y << ")";
      }
    }
  }
  EXPECT_GT(unreached_total, 0) << "the cases no longer exercise unreached pixels";
}

// Tiny two-level images where a cluster ends up empty (found by search). An
// empty cluster keeps its previous centre (segmentation.h): its centre after
// n iterations equals its centre after n - 1 iterations.
TEST(Segmenter, EmptyClusterKeepsItsPreviousCentre) {
  struct Case {
    int w, h, sp;
    double intensity_scale;
  };
  const Case cases[] = {{3, 28, 2, 2.3}, {3, 38, 3, 20.0}, {4, 4, 2, 2.3}, {4, 9, 2, 0.001}};
  int empty_total = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(testing::Message() << c.w << "x" << c.h << " sp " << c.sp);
    const GrayImage img = test::two_level_image(c.w, c.h);
    // Check every iteration count, so the iteration where a cluster first
    // empties is covered.
    SegmentationOptions o = options_with(c.sp, 1);
    o.intensity_scale = c.intensity_scale;
    Segmentation prev = Segmenter(o).segment(img);
    for (int n = 2; n <= 10; ++n) {
      o.iterations = n;
      const Segmentation s = Segmenter(o).segment(img);
      expect_valid(img, s, c.sp);
      for (std::size_t k = 0; k < s.centres.size(); ++k) {
        if (s.centres[k].pixels != 0) continue;
        ++empty_total;
        EXPECT_EQ(s.centres[k].x, prev.centres[k].x) << "cell " << k << " iterations " << n;
        EXPECT_EQ(s.centres[k].y, prev.centres[k].y) << "cell " << k << " iterations " << n;
        EXPECT_EQ(s.centres[k].intensity, prev.centres[k].intensity)
            << "cell " << k << " iterations " << n;
      }
      prev = s;
    }
  }
  EXPECT_GT(empty_total, 0) << "the cases no longer produce an empty cluster";
}

TEST(Segmenter, UniformImageCoversEachCellsSeedRegion) {
  for (const auto& [w, h, sp] : std::vector<std::tuple<int, int, int>>{
           {96, 64, 10}, {160, 120, 20}, {97, 61, 8}, {1241, 376, 40}}) {
    SCOPED_TRACE(testing::Message() << w << "x" << h << " sp " << sp);
    Segmenter segmenter(options_with(sp));
    const GrayImage img = uniform_image(w, h, 128);
    const Segmentation s = segmenter.segment(img);
    expect_valid(img, s, sp);
    const GridSize g = s.grid;
    const double cw = static_cast<double>(w) / g.cols, ch = static_cast<double>(h) / g.rows;
    int wrong = 0;
    for (int r = 0; r < g.rows; ++r) {
      for (int c = 0; c < g.cols; ++c) {
        const int k = r * g.cols + c;
        EXPECT_GT(s.centres[k].pixels, 0) << "cell " << k;
        // The central half of the grid cell (around its seed) carries label k.
        const int x0 = static_cast<int>(std::ceil((c + 0.25) * cw));
        const int x1 = static_cast<int>(std::floor((c + 0.75) * cw));
        const int y0 = static_cast<int>(std::ceil((r + 0.25) * ch));
        const int y1 = static_cast<int>(std::floor((r + 0.75) * ch));
        for (int y = y0; y < y1; ++y) {
          for (int x = x0; x < x1; ++x) {
            if (s.labels[static_cast<std::size_t>(y) * w + x] != k) ++wrong;
          }
        }
        // The centre stays near its grid cell's centre.
        EXPECT_NEAR(s.centres[k].x, (c + 0.5) * cw, 0.25 * cw) << "cell " << k;
        EXPECT_NEAR(s.centres[k].y, (r + 0.5) * ch, 0.25 * ch) << "cell " << k;
        EXPECT_FLOAT_EQ(s.centres[k].intensity, 128.0f);
      }
    }
    EXPECT_EQ(wrong, 0);
  }
}

TEST(Segmenter, CentreCountsSumToPixelCount) {
  Segmenter segmenter(options_with(6));
  const GrayImage img = random_image(83, 59, 13);
  const Segmentation s = segmenter.segment(img);
  std::int64_t total = 0;
  for (const Centre& c : s.centres) total += c.pixels;
  EXPECT_EQ(total, 83 * 59);
}

// Flat blocks aligned with the grid, strong contrast between neighbours (four
// levels tiled 2x2, so any two touching blocks differ by >= 80) plus mild
// noise: the segmentation must recover exactly the blocks.
TEST(Segmenter, FlatBlocksSegmentIntoTheBlocks) {
  for (const auto& [w, h, sp] :
       std::vector<std::tuple<int, int, int>>{{160, 120, 20}, {96, 64, 10}, {200, 90, 25}}) {
    SCOPED_TRACE(testing::Message() << w << "x" << h << " sp " << sp);
    const GridSize g = grid_size(w, h, sp);
    ASSERT_GT(g.cells(), 1);
    const double cw = static_cast<double>(w) / g.cols, ch = static_cast<double>(h) / g.rows;
    const std::uint8_t levels[4] = {10, 90, 170, 250};
    GrayImage img;
    img.width = w;
    img.height = h;
    img.pixels.resize(static_cast<std::size_t>(w) * h);
    std::vector<std::int32_t> expected(img.pixels.size());
    std::uint64_t state = 77;
    for (int y = 0; y < h; ++y) {
      const int r = std::min(g.rows - 1, static_cast<int>(y / ch));
      for (int x = 0; x < w; ++x) {
        const int c = std::min(g.cols - 1, static_cast<int>(x / cw));
        const int noise = static_cast<int>(splitmix64(state) % 9) - 4;  // [-4, 4]
        img.pixels[static_cast<std::size_t>(y) * w + x] =
            static_cast<std::uint8_t>(levels[(r % 2) * 2 + (c % 2)] + noise);
        expected[static_cast<std::size_t>(y) * w + x] = r * g.cols + c;
      }
    }
    SegmentationOptions o = options_with(sp);
    o.intensity_scale = 2.3;  // the reference's weighting
    Segmenter segmenter(o);
    const Segmentation s = segmenter.segment(img);
    expect_valid(img, s, sp);
    int wrong = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) wrong += s.labels[i] != expected[i];
    EXPECT_EQ(wrong, 0);
    for (int k = 0; k < g.cells(); ++k) {
      const int r = k / g.cols, c = k % g.cols;
      EXPECT_NEAR(s.centres[k].intensity, levels[(r % 2) * 2 + (c % 2)], 1.0) << "cell " << k;
    }
  }
}

TEST(Segmenter, Deterministic) {
  const GrayImage img = random_image(96, 64, 14);
  Segmenter a(options_with(7)), b(options_with(7));
  const Segmentation sa = a.segment(img);
  const Segmentation sb = b.segment(img);
  const Segmentation sa2 = a.segment(img);
  EXPECT_EQ(sa.labels, sb.labels);
  EXPECT_EQ(sa.labels, sa2.labels);
  ASSERT_EQ(sa.centres.size(), sb.centres.size());
  for (std::size_t k = 0; k < sa.centres.size(); ++k) {
    EXPECT_EQ(sa.centres[k].x, sb.centres[k].x);
    EXPECT_EQ(sa.centres[k].y, sb.centres[k].y);
    EXPECT_EQ(sa.centres[k].intensity, sb.centres[k].intensity);
    EXPECT_EQ(sa.centres[k].pixels, sb.centres[k].pixels);
  }
}

void expect_same(const Segmentation& a, const Segmentation& b) {
  test::expect_same_segmentation(a, b);
}

TEST(Segmenter, ResultDependsOnlyOnTheImage) {
  const GrayImage a = smooth_image(96, 64, 0.0);
  const GrayImage b = random_image(96, 64, 15);
  const GrayImage c = random_image(50, 120, 16);  // another size
  Segmenter fresh(options_with(6));
  const Segmentation expected = fresh.segment(a);

  // Reusing one Segmenter and one output object across images.
  Segmenter reused(options_with(6));
  Segmentation out;
  reused.segment(a, out);
  expect_same(out, expected);
  reused.segment(b, out);
  reused.segment(c, out);
  reused.segment(a, out);
  expect_same(out, expected);
  // And a fresh output object from the reused segmenter.
  expect_same(reused.segment(a), expected);
}

TEST(Segmenter, SmallerImageAfterLargerReusesOutput) {
  Segmenter s(options_with(3));
  Segmentation out;
  s.segment(random_image(90, 70, 17), out);
  const GrayImage small = random_image(5, 4, 18);
  s.segment(small, out);
  expect_valid(small, out, 3);
  Segmenter fresh(options_with(3));
  expect_same(out, fresh.segment(small));
}

// Records every row a RowSink gets.
class RecordingSink final : public RowSink {
 public:
  void row(int y, const std::uint8_t* pixels, const std::int32_t* labels, int width) override {
    ys.push_back(y);
    widths.push_back(width);
    row_labels.insert(row_labels.end(), labels, labels + width);
    row_pixels.insert(row_pixels.end(), pixels, pixels + width);
  }
  std::vector<int> ys, widths;
  std::vector<std::int32_t> row_labels;
  std::vector<std::uint8_t> row_pixels;
};

// The sink gets every row once, in order, with its final labels (including
// a pixel no window reached: two-level 26x15, S_p 4, 8 iterations, from the
// cases above), and the segmentation is the same as without a sink.
TEST(Segmenter, RowSinkGetsEveryFinalRowOnceInOrder) {
  struct Case {
    GrayImage image;
    int sp, iterations;
  };
  const Case cases[] = {
      {random_image(96, 64, 30), 7, 3},      {smooth_image(203, 77, 0.4), 13, 1},
      {test::two_level_image(31, 25), 4, 8}, {test::two_level_image(26, 15), 4, 8},
      {random_image(1, 1, 31), 40, 3},       {random_image(5, 3, 32), 2, 2},
      {random_image(1, 50, 33), 3, 3},       {uniform_image(17, 13, 9), 40, 3}};
  for (const Case& c : cases) {
    SCOPED_TRACE(testing::Message() << c.image.width << "x" << c.image.height << " sp " << c.sp);
    const SegmentationOptions o = options_with(c.sp, c.iterations);
    const Segmentation expected = Segmenter(o).segment(c.image);
    Segmenter segmenter(o);
    Segmentation out;
    for (int pass = 0; pass < 2; ++pass) {  // the second reuses segmenter and output
      RecordingSink sink;
      segmenter.segment(c.image, out, sink);
      expect_same(out, expected);
      std::vector<int> rows(c.image.height);
      for (int y = 0; y < c.image.height; ++y) rows[y] = y;
      EXPECT_EQ(sink.ys, rows);
      EXPECT_EQ(sink.widths, std::vector<int>(c.image.height, c.image.width));
      EXPECT_EQ(sink.row_labels, expected.labels);
      EXPECT_EQ(sink.row_pixels, c.image.pixels);
    }
  }
}

TEST(Segmenter, RowSinkIsNotCalledForAnInvalidImage) {
  Segmenter segmenter;
  Segmentation out;
  RecordingSink sink;
  EXPECT_THROW(segmenter.segment(GrayImage{}, out, sink), InvalidArgument);
  EXPECT_TRUE(sink.ys.empty());
}

TEST(Segmenter, OptionsAccessor) {
  SegmentationOptions o = options_with(13, 4);
  o.intensity_scale = 5.0;
  Segmenter s(o);
  EXPECT_EQ(s.options().superpixel_size, 13);
  EXPECT_EQ(s.options().iterations, 4);
  EXPECT_DOUBLE_EQ(s.options().intensity_scale, 5.0);
}

}  // namespace
}  // namespace lsgd
