// The SIMD kernels (src/internal/kernels.h) against their scalar references,
// on every SIMD target this CPU supports: results must be identical.
#include "internal/kernels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <vector>

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

// Random segments on a row of `width` pixels: spans of 0 .. max_span pixels
// (one empty, one at either end of the row), labels in order; rows of 64 or
// more pixels get a few pixels no segment covers.
std::vector<RowSegment> random_segments(int width, int count, int max_span, std::uint64_t seed) {
  std::uint64_t s = seed;
  std::vector<RowSegment> segments;
  for (int k = 0; k < count; ++k) {
    RowSegment seg;
    seg.x0 = static_cast<int>(splitmix64(s) % width);
    seg.x1 = std::min(width - 1, seg.x0 + static_cast<int>(splitmix64(s) % max_span));
    if (k == 2) seg.x1 = std::min(width - 1, seg.x1 - seg.x0), seg.x0 = 0;
    if (k == 3) seg.x0 = std::max(0, width - 1 - (seg.x1 - seg.x0)), seg.x1 = width - 1;
    if (k == 7) seg.x1 = seg.x0 - 1;  // an empty span
    seg.cx = static_cast<float>(splitmix64(s) % (100 * width)) / 100.0f;
    seg.intensity = static_cast<float>(splitmix64(s) % 25600) / 100.0f;
    seg.row_term = static_cast<float>(splitmix64(s) % 5000) / 7.0f;
    seg.label = k;
    segments.push_back(seg);
  }
  if (width >= 64) {  // pixels no segment covers: [hole0, hole1]
    const int hole0 = width * 2 / 3, hole1 = hole0 + 4;
    for (RowSegment& seg : segments) {
      if (seg.x1 < hole0 || seg.x0 > hole1) continue;
      if (seg.x0 < hole0) {
        seg.x1 = hole0 - 1;
      } else {
        seg.x0 = hole1 + 1;  // may leave an empty span
      }
    }
  }
  return segments;
}

// Tables and lists for the SIMD kernel on the dispatched target, as the
// Segmenter builds them.
struct KernelInputs {
  std::vector<float> xterms;
  std::vector<std::int32_t> lists;
  KernelInputs(std::vector<RowSegment>& segments, AssignRow& r) {
    const int lanes = assign_lanes();
    std::size_t n = 0;
    for (const RowSegment& seg : segments) n += x_terms_size(seg.x0, seg.x1, lanes);
    xterms.assign(n, 0.0f);
    n = 0;
    for (RowSegment& seg : segments) {
      seg.xterm = xterms.data() + n;
      seg.xterm_first = x_terms_first(seg.x0, lanes);
      x_terms(seg.cx, seg.x0, seg.x1, r.inv_distance, lanes, xterms.data() + n);
      n += x_terms_size(seg.x0, seg.x1, lanes);
    }
    assign_lists(segments.data(), static_cast<int>(segments.size()), r.width, lanes, lists);
    r.lists = lists.data();
    r.lanes = lanes;
  }
};

TEST(Kernels, XTermsHoldTheFuseDistanceXTermInsideTheWindow) {
  for (const int lanes : {1, 4, 8, 16}) {
    SCOPED_TRACE(lanes);
    const int x0 = 8, x1 = 12;
    const int first = x_terms_first(x0, lanes), size = x_terms_size(x0, x1, lanes);
    EXPECT_EQ(first % lanes, 0);
    EXPECT_EQ(size % lanes, 0);
    EXPECT_LE(first, x0 - lanes);             // a vector may start a vector before x0 ...
    EXPECT_GE(first + size, x1 + lanes + 1);  // ... and end a vector after x1
    std::vector<float> out(size);
    x_terms(10.25f, x0, x1, 0.5f, lanes, out.data());
    const float inside[] = {2.53125f, 0.78125f, 0.03125f, 0.28125f, 1.53125f};
    for (int i = 0; i < size; ++i) {
      const int x = first + i;
      if (x < x0 || x > x1) {
        EXPECT_EQ(out[i], std::numeric_limits<float>::infinity()) << x;
      } else {
        EXPECT_EQ(out[i], inside[x - x0]) << x;
      }
    }
  }
}

// The lists name, for each vector, exactly the segments overlapping it, in order.
TEST(Kernels, AssignListsNameTheSegmentsOfEachVector) {
  for (const int width : {203, 16, 17, 5}) {
    const std::vector<RowSegment> segments = random_segments(width, 12, width / 2 + 2, width);
    for (const int lanes : {1, 4, 8, 16}) {
      SCOPED_TRACE(testing::Message() << "width " << width << " lanes " << lanes);
      std::vector<std::int32_t> lists;
      assign_lists(segments.data(), static_cast<int>(segments.size()), width, lanes, lists);
      const int chunks = (width + lanes - 1) / lanes;
      ASSERT_GE(lists.size(), static_cast<std::size_t>(chunks) + 1);
      EXPECT_EQ(lists[0], 0);
      EXPECT_EQ(lists.size(), static_cast<std::size_t>(chunks + 1 + lists[chunks]));
      for (int c = 0; c < chunks; ++c) {
        const int xs = std::max(0, std::min(c * lanes, width - lanes));
        const int xe = std::min(width, xs + lanes) - 1;
        std::vector<std::int32_t> expected;
        for (int s = 0; s < static_cast<int>(segments.size()); ++s) {
          if (segments[s].x0 <= segments[s].x1 && segments[s].x0 <= xe && segments[s].x1 >= xs) {
            expected.push_back(s);
          }
        }
        const std::vector<std::int32_t> got(lists.begin() + chunks + 1 + lists[c],
                                            lists.begin() + chunks + 1 + lists[c + 1]);
        EXPECT_EQ(got, expected) << "vector " << c;
      }
    }
  }
}

TEST(Kernels, AssignRowMatchesScalarOnEveryTarget) {
  // Odd widths (vector tails everywhere), rows narrower than one vector, and
  // rows that are exact multiples of every vector width.
  for (const int width : {203, 1, 3, 7, 15, 16, 17, 31, 64, 100}) {
    SCOPED_TRACE(testing::Message() << "width " << width);
    const GrayImage image = test::random_image(width, 1, 5 + width);
    const int count = width == 203 ? 40 : 6;
    std::vector<RowSegment> segments =
        random_segments(width, count, std::max(2, width * 9 / 20), 99 + width);
    AssignRow r;
    r.pixels = image.pixels.data();
    r.width = width;
    r.segments = segments.data();
    r.count = static_cast<int>(segments.size());
    r.inv_intensity = 1.0f / 20.0f;
    r.inv_distance = 1.0f / 1.3f;
    std::vector<std::int32_t> ref(width, 1234);
    r.labels = ref.data();
    assign_row_scalar(r);
    if (width >= 64) {  // unreached pixels, and reached ones
      EXPECT_GE(std::count(ref.begin(), ref.end(), -1), 5);
      EXPECT_EQ(ref[width * 2 / 3], -1);
      EXPECT_LT(std::count(ref.begin(), ref.end(), -1), width / 2);
    }
    for_each_target([&] {
      const KernelInputs inputs(segments, r);
      std::vector<std::int32_t> got(width, 1234);
      r.labels = got.data();
      assign_row(r);
      EXPECT_EQ(got, ref);
      // Tables made for another vector width: the kernel goes pixel by pixel.
      std::fill(got.begin(), got.end(), 1234);
      r.lanes = 0;
      assign_row(r);
      EXPECT_EQ(got, ref);
    });
  }
}

// Ties: segments with identical parameters give identical distances, and the
// earlier segment must keep the pixel on every target.
TEST(Kernels, AssignRowTiesKeepTheEarlierSegment) {
  const int width = 77;
  const GrayImage image = test::random_image(width, 1, 21);
  std::vector<RowSegment> segments(3);
  for (int k = 0; k < 3; ++k) {
    segments[k].x0 = k == 1 ? 0 : 10 + k;
    segments[k].x1 = k == 2 ? width - 1 : 60;
    segments[k].cx = 33.5f;
    segments[k].intensity = 100.0f;
    segments[k].row_term = 4.0f;
    segments[k].label = 5 - k;
  }
  AssignRow r;
  r.pixels = image.pixels.data();
  r.width = width;
  r.segments = segments.data();
  r.count = 3;
  std::vector<std::int32_t> expected(width);
  for (int x = 0; x < width; ++x) expected[x] = x < 10 ? 4 : x <= 60 ? 5 : 3;
  for_each_target([&] {
    const KernelInputs inputs(segments, r);
    std::vector<std::int32_t> got(width);
    r.labels = got.data();
    assign_row(r);
    EXPECT_EQ(got, expected);
  });
  std::vector<std::int32_t> ref(width);
  r.labels = ref.data();
  assign_row_scalar(r);
  EXPECT_EQ(ref, expected);
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

TEST(Kernels, LabelRunsMatchScalarOnEveryTarget) {
  for (const int width : {211, 1, 2, 15, 16, 17, 64}) {
    SCOPED_TRACE(testing::Message() << "width " << width);
    std::vector<std::int32_t> labels(width);
    std::uint64_t s = 6 + width;
    int x = 0, label = 0;
    while (x < width) {  // runs of 1 .. 40 pixels, labels revisited
      const int run = 1 + static_cast<int>(splitmix64(s) % 40);
      for (int i = 0; i < run && x < width; ++i) labels[x++] = label;
      label = (label + 1 + static_cast<int>(splitmix64(s) % 4)) % 5;  // never the same twice
    }
    std::vector<LabelRun> ref(width);
    const int n = label_runs_scalar(labels.data(), width, ref.data());
    ref.resize(n);
    // The runs rebuild the labels.
    std::vector<std::int32_t> rebuilt(width, -1);
    for (int i = 0; i < n; ++i) {
      const int end = i + 1 < n ? ref[i + 1].start : width;
      std::fill(rebuilt.begin() + ref[i].start, rebuilt.begin() + end, ref[i].label);
      if (i > 0) {
        EXPECT_NE(ref[i].label, ref[i - 1].label);
      }
    }
    EXPECT_EQ(rebuilt, labels);
    for_each_target([&] {
      std::vector<LabelRun> got(width);
      ASSERT_EQ(label_runs(labels.data(), width, got.data()), n);
      for (int i = 0; i < n; ++i) {
        EXPECT_EQ(got[i].start, ref[i].start) << i;
        EXPECT_EQ(got[i].label, ref[i].label) << i;
      }
    });
  }
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
  // 11 cells: two groups of the four cells the kernel sums at once, and a
  // tail. Cells 0-3 all have the largest distance, so every 16-bit field of
  // the packed group holds its maximum (a carry would show).
  const int cells = 11;
  std::vector<CompactBin> a(static_cast<std::size_t>(cells) * kCompactBins), b(a.size());
  std::uint64_t s = 5;
  for (std::size_t i = 0; i < a.size(); ++i) {
    a[i] = static_cast<CompactBin>(splitmix64(s));
    b[i] = static_cast<CompactBin>(splitmix64(s) % 40);
  }
  std::fill(a.begin(), a.begin() + 4 * kCompactBins, CompactBin{255});  // cells 0-3: the largest
  std::fill(b.begin(), b.begin() + 4 * kCompactBins, CompactBin{0});
  std::fill(a.begin() + 4 * kCompactBins, a.begin() + 5 * kCompactBins,
            CompactBin{7});  // cell 4: 0
  std::fill(b.begin() + 4 * kCompactBins, b.begin() + 5 * kCompactBins, CompactBin{7});
  std::vector<std::uint32_t> ref(cells);
  cell_sad_scalar(a.data(), b.data(), cells, ref.data());
  for (int k = 0; k < 4; ++k) EXPECT_EQ(ref[k], 255u * kCompactBins);
  EXPECT_EQ(ref[4], 0u);
  std::uint32_t by_hand = 0;  // cell 5, independently
  for (int i = 5 * kCompactBins; i < 6 * kCompactBins; ++i) by_hand += std::abs(a[i] - b[i]);
  EXPECT_EQ(ref[5], by_hand);
  for_each_target([&] {
    for (int n = 0; n <= cells; ++n) {  // every group / tail split
      std::vector<std::uint32_t> got(cells, 1);
      cell_sad(a.data(), b.data(), n, got.data());
      EXPECT_TRUE(std::equal(got.begin(), got.begin() + n, ref.begin())) << n << " cells";
      EXPECT_TRUE(std::all_of(got.begin() + n, got.end(), [](std::uint32_t v) { return v == 1; }));
    }
    std::vector<std::uint32_t> got(cells, 1);
    cell_sad(b.data(), a.data(), cells, got.data());  // symmetric
    EXPECT_EQ(got, ref);
  });
}

// The reference metric's per-cell distances: the SIMD kernel must give the
// scalar expression's exact doubles (same correctly rounded operations), for
// every count (vector bodies and tails), L1s from 0 to the largest exact
// cell L1, and the scales exact (1) and compact storage use.
TEST(Kernels, CellDistancesMatchScalarBitForBitOnEveryTarget) {
  std::vector<std::uint32_t> l1(37);
  std::uint64_t s = 9;
  for (std::uint32_t& v : l1) v = static_cast<std::uint32_t>(splitmix64(s) % (kBins * 65535u + 1));
  l1[0] = 0;
  l1[1] = kBins * 65535u;
  l1[2] = 1;
  for (const double scale : {1.0, 0.5 * (5832.7 + 5831.9) / kCompactMass, 1e-3}) {
    std::vector<double> ref(l1.size());
    cell_distances_scalar(l1.data(), static_cast<int>(l1.size()), scale, ref.data());
    for (std::size_t k = 0; k < l1.size(); ++k) {
      EXPECT_EQ(ref[k], std::sqrt(static_cast<double>(l1[k]) * scale) / kBins) << k;
    }
    EXPECT_EQ(ref[0], 0.0);
    for_each_target([&] {
      for (int n : {0, 1, 7, 8, 9, 16, 37}) {
        std::vector<double> got(l1.size(), -1.0);
        cell_distances(l1.data(), n, scale, got.data());
        for (int k = 0; k < n; ++k) EXPECT_EQ(got[k], ref[k]) << "scale " << scale << " k " << k;
        for (std::size_t k = n; k < got.size(); ++k) EXPECT_EQ(got[k], -1.0) << "wrote past " << n;
      }
    });
  }
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
