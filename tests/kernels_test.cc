// The SIMD kernels (src/internal/kernels.h) against their scalar references,
// on every SIMD target this CPU supports: results must be identical.
#include "internal/kernels.h"

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "lsgd/segmentation.h"
#include "test_util.h"

namespace lsgd::internal {
namespace {

using test::splitmix64;

// Runs `body` once per supported SIMD target, dispatch forced to it.
template <typename F>
void for_each_target(F&& body) {
  const auto targets = simd_targets();
  ASSERT_FALSE(targets.empty());
  for (const std::int64_t t : targets) {
    force_simd_target(t);
    SCOPED_TRACE(simd_target_name(t));
    EXPECT_EQ(active_simd_target(), simd_target_name(t));
    body();
  }
  force_simd_target(0);
}

TEST(Kernels, AssignRowMatchesScalarOnEveryTarget) {
  const int width = 203;  // odd: vector tails everywhere
  const GrayImage image = test::random_image(width, 1, 5);
  std::uint64_t s = 99;
  std::vector<RowSegment> segments;
  for (int k = 0; k < 40; ++k) {
    RowSegment seg;
    seg.x0 = static_cast<int>(splitmix64(s) % width);
    seg.x1 = std::min(width - 1, seg.x0 + static_cast<int>(splitmix64(s) % 90));
    if (k == 7) seg.x1 = seg.x0 - 1;  // an empty span
    seg.cx = static_cast<float>(splitmix64(s) % 20000) / 100.0f;
    seg.intensity = static_cast<float>(splitmix64(s) % 25600) / 100.0f;
    seg.row_term = static_cast<float>(splitmix64(s) % 5000) / 7.0f;
    seg.label = k;
    segments.push_back(seg);
  }
  for_each_target([&] {
    std::vector<float> dist_simd(width, std::numeric_limits<float>::infinity()), dist_ref = dist_simd;
    std::vector<std::int32_t> lab_simd(width, -1), lab_ref = lab_simd;
    AssignRow r;
    r.pixels = image.pixels.data();
    r.segments = segments.data();
    r.count = static_cast<int>(segments.size());
    r.inv_intensity = 1.0f / 20.0f;
    r.inv_distance = 1.0f / 1.3f;
    r.distance = dist_simd.data();
    r.labels = lab_simd.data();
    assign_row(r);
    r.distance = dist_ref.data();
    r.labels = lab_ref.data();
    assign_row_scalar(r);
    EXPECT_EQ(lab_simd, lab_ref);
    EXPECT_EQ(dist_simd, dist_ref);  // bit-identical floats
    EXPECT_GT(std::count(lab_ref.begin(), lab_ref.end(), -1), 0);  // some pixels unreached
    EXPECT_LT(std::count(lab_ref.begin(), lab_ref.end(), -1), width);
  });
}

TEST(Kernels, RowSumsMatchScalarOnEveryTarget) {
  const int width = 211;
  const GrayImage image = test::random_image(width, 1, 8);
  std::vector<std::int32_t> labels(width);
  std::uint64_t s = 4;
  int x = 0, label = 0;
  while (x < width) {  // runs of 1 .. 60 pixels, labels revisited
    const int run = 1 + static_cast<int>(splitmix64(s) % 60);
    for (int i = 0; i < run && x < width; ++i) labels[x++] = label;
    label = static_cast<int>(splitmix64(s) % 5);
  }
  std::vector<std::int64_t> ref(5 * 4, 0);
  EXPECT_EQ(row_sums_scalar(labels.data(), image.pixels.data(), width, 17, ref.data()), width);
  std::int64_t n = 0, intensity = 0;
  for (int k = 0; k < 5; ++k) n += ref[k * 4 + 3], intensity += ref[k * 4 + 2];
  EXPECT_EQ(n, width);
  std::int64_t expected = 0;
  for (std::uint8_t p : image.pixels) expected += p;
  EXPECT_EQ(intensity, expected);
  for_each_target([&] {
    std::vector<std::int64_t> got(5 * 4, 0);
    EXPECT_EQ(row_sums(labels.data(), image.pixels.data(), width, 17, got.data()), width);
    EXPECT_EQ(got, ref);
    // An unreached pixel (-1) stops both at its position; going on from
    // there after labelling it gives the same sums as labelling it first.
    std::vector<std::int32_t> holed = labels;
    holed[100] = -1;
    std::vector<std::int64_t> a(5 * 4, 0), b(5 * 4, 0);
    EXPECT_EQ(row_sums(holed.data(), image.pixels.data(), width, 17, a.data()), 100);
    EXPECT_EQ(row_sums_scalar(holed.data(), image.pixels.data(), width, 17, b.data()), 100);
    EXPECT_EQ(a, b);
    holed[100] = labels[100];
    EXPECT_EQ(row_sums(holed.data(), image.pixels.data(), width, 17, a.data(), 100), width);
    EXPECT_EQ(a, ref);
  });
}

TEST(Kernels, CellL1MatchesScalarOnEveryTargetIncludingExtremes) {
  const int cells = 7;
  std::vector<Bin> a(static_cast<std::size_t>(cells) * kBins), b(a.size());
  std::uint64_t s = 3;
  for (std::size_t i = 0; i < a.size(); ++i) {
    a[i] = static_cast<Bin>(splitmix64(s));
    b[i] = static_cast<Bin>(splitmix64(s) % 300);
  }
  std::fill(a.begin(), a.begin() + kBins, Bin{65535});  // cell 0: the largest distance
  std::fill(b.begin(), b.begin() + kBins, Bin{0});
  std::vector<std::uint32_t> ref(cells);
  cell_l1_scalar(a.data(), b.data(), cells, ref.data());
  EXPECT_EQ(ref[0], 65535u * kBins);
  for_each_target([&] {
    std::vector<std::uint32_t> got(cells, 1);
    cell_l1(a.data(), b.data(), cells, got.data());
    EXPECT_EQ(got, ref);
    cell_l1(b.data(), a.data(), cells, got.data());  // symmetric
    EXPECT_EQ(got, ref);
  });
}

TEST(Kernels, CellSadMatchesScalarOnEveryTargetIncludingExtremes) {
  const int cells = 9;
  std::vector<CompactBin> a(static_cast<std::size_t>(cells) * kCompactBins), b(a.size());
  std::uint64_t s = 5;
  for (std::size_t i = 0; i < a.size(); ++i) {
    a[i] = static_cast<CompactBin>(splitmix64(s));
    b[i] = static_cast<CompactBin>(splitmix64(s) % 40);
  }
  std::fill(a.begin(), a.begin() + kCompactBins, CompactBin{255});  // cell 0: the largest distance
  std::fill(b.begin(), b.begin() + kCompactBins, CompactBin{0});
  std::fill(a.begin() + kCompactBins, a.begin() + 2 * kCompactBins, CompactBin{7});  // cell 1: 0
  std::fill(b.begin() + kCompactBins, b.begin() + 2 * kCompactBins, CompactBin{7});
  std::vector<std::uint32_t> ref(cells);
  cell_sad_scalar(a.data(), b.data(), cells, ref.data());
  EXPECT_EQ(ref[0], 255u * kCompactBins);
  EXPECT_EQ(ref[1], 0u);
  std::uint32_t by_hand = 0;  // cell 2, independently
  for (int i = 2 * kCompactBins; i < 3 * kCompactBins; ++i) by_hand += std::abs(a[i] - b[i]);
  EXPECT_EQ(ref[2], by_hand);
  for_each_target([&] {
    std::vector<std::uint32_t> got(cells, 1);
    cell_sad(a.data(), b.data(), cells, got.data());
    EXPECT_EQ(got, ref);
    cell_sad(b.data(), a.data(), cells, got.data());  // symmetric
    EXPECT_EQ(got, ref);
  });
}

TEST(Kernels, SegmentationIsIdenticalOnEveryTarget) {
  const GrayImage image = test::random_image(333, 129, 11);
  SegmentationOptions o;
  o.superpixel_size = 17;
  force_simd_target(simd_targets().back());  // the plainest target as reference
  const Segmentation ref = Segmenter(o).segment(image);
  for_each_target([&] {
    const Segmentation seg = Segmenter(o).segment(image);
    EXPECT_EQ(seg.labels, ref.labels);
  });
}

}  // namespace
}  // namespace lsgd::internal
