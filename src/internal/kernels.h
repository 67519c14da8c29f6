// Hot-path kernels with SIMD versions chosen at run time (Highway dynamic
// dispatch: the best of AVX-512, AVX2, SSE4, ... this CPU supports) and the
// scalar reference each one is tested against. SIMD and scalar results are
// identical: the kernels use the same float operations in the same order
// (this file's sources are compiled without floating-point contraction) and
// exact integer sums.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lsgd/descriptor.h"

namespace lsgd::internal {

// The SLIC assignment step on one image row: for each segment in order (one
// per centre whose window covers the row) and every x in [x0, x1],
//   d = (di * di) * inv_intensity + (dx * dx) * inv_distance + row_term
// with di = pixels[x] - intensity and dx = x - cx (floats, evaluated in that
// order; row_term = (dy * dy) * inv_distance for the row), and where
// d < distance[x] the pixel takes the segment's label (ties keep the earlier).
// (RowSegment is defined in lsgd/segmentation.h.)
struct AssignRow {
  const std::uint8_t* pixels = nullptr;  // the row
  float* distance = nullptr;             // per pixel of the row
  std::int32_t* labels = nullptr;        // per pixel of the row
  const RowSegment* segments = nullptr;
  int count = 0;
  float inv_intensity = 1, inv_distance = 1;
};
void assign_row(const AssignRow& row);
void assign_row_scalar(const AssignRow& row);

// The scalar step of both: pixel x against one segment.
inline void assign_pixel(const AssignRow& r, const RowSegment& seg, int x) {
  const float dx = static_cast<float>(x) - seg.cx;
  const float dI = static_cast<float>(r.pixels[x]) - seg.intensity;
  const float d = ((dI * dI) * r.inv_intensity + (dx * dx) * r.inv_distance) + seg.row_term;
  if (d < r.distance[x]) {
    r.distance[x] = d;
    r.labels[x] = seg.label;
  }
}

// The k-means update sums of one image row from pixel `start` on: for every
// run of equal labels k >= 0, sums[4k + 0] += sum of x, [4k + 1] += y * run
// length, [4k + 2] += sum of pixels, [4k + 3] += run length. Stops at the
// first negative label (an unreached pixel) and returns its x, or width.
int row_sums(const std::int32_t* labels, const std::uint8_t* pixels, int width, int y,
             std::int64_t* sums, int start = 0);
int row_sums_scalar(const std::int32_t* labels, const std::uint8_t* pixels, int width, int y,
                    std::int64_t* sums, int start = 0);

// Per-cell L1 distances of two cell-major histograms of `cells` x kBins bins:
// out[k] = sum_b |a[k][b] - b[k][b]| (at most kBins * 65535, fits 32 bits).
void cell_l1(const Bin* a, const Bin* b, int cells, std::uint32_t* out);
void cell_l1_scalar(const Bin* a, const Bin* b, int cells, std::uint32_t* out);

// Per-cell L1 distances of two cell-major compact histograms of `cells` x
// kCompactBins 8-bit bins: out[k] = sum_b |a[k][b] - b[k][b]| (sum of
// absolute differences, at most kCompactBins * 255).
void cell_sad(const CompactBin* a, const CompactBin* b, int cells, std::uint32_t* out);
void cell_sad_scalar(const CompactBin* a, const CompactBin* b, int cells, std::uint32_t* out);

// For tests and benchmarks: the SIMD targets compiled in and supported by
// this CPU (Highway target bits, best first), their names, and a way to
// restrict dispatch to one of them (0 restores the default choice).
std::vector<std::int64_t> simd_targets();
std::string simd_target_name(std::int64_t target);
void force_simd_target(std::int64_t target);
// The target dispatch picks now (e.g. "AVX3", "AVX2", "SSE4", "EMU128").
std::string active_simd_target();

}  // namespace lsgd::internal
