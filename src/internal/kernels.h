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
// order; row_term = (dy * dy) * inv_distance for the row), and where d is
// below the smallest d so far at x the pixel takes the segment's label (ties
// keep the earlier segment). Every x in [0, width) gets a label: the segment
// with the smallest d, or -1 when no segment covers x.
//
// The SIMD kernel goes vector by vector along the row and keeps the best d
// and label of its lanes in registers while it evaluates, in order, the
// segments listed for that vector (assign_lists()). It reads the x term
// (dx * dx) * inv_distance from the segment's x_terms() table (the same for
// every row of a centre's window, +infinity outside it, so lanes outside the
// window never take its label). The scalar reference computes everything.
// One centre's span of one image row in the assignment step (implementation
// detail of Segmenter, used by the SIMD kernel in src/internal/kernels.h).
struct RowSegment {
  int x0 = 0, x1 = -1;  // inclusive
  float cx = 0, intensity = 0, row_term = 0;
  std::int32_t label = 0;
  // The centre's x-term table (internal::x_terms()): entry x - xterm_first for pixel x.
  const float* xterm = nullptr;
  int xterm_first = 0;
};

// One run of equal labels in a row (internal::label_runs in
// src/internal/kernels.h): it starts at `start` and ends where the next run
// starts.
struct LabelRun {
  std::int32_t start = 0;
  std::int32_t label = 0;
};

struct AssignRow {
  const std::uint8_t* pixels = nullptr;  // the row, width pixels
  std::int32_t* labels = nullptr;        // out: width labels
  int width = 0;
  const RowSegment* segments = nullptr;  // 0 <= x0 <= x1 < width, with x-term tables
  int count = 0;
  const std::int32_t* lists = nullptr;  // assign_lists() of these segments (SIMD only)
  int lanes = 0;                        // the vector width tables and lists were made for
  float inv_intensity = 1, inv_distance = 1;
};
void assign_row(const AssignRow& row);
void assign_row_scalar(const AssignRow& row);

// Floats per vector of the assignment kernel on the target dispatch picks now.
int assign_lanes();

// For every vector of `lanes` pixels of a row of `width` pixels, the
// segments covering it, in segment order: lists = [start of each vector's
// list (vectors + 1)][segment indices]. Vector c covers [xs, xs + lanes) with
// xs = min(c * lanes, width - lanes); the last one overlaps its neighbour
// when lanes does not divide width. Depends only on the segments' x0 and x1.
void assign_lists(const RowSegment* segments, int count, int width, int lanes,
                  std::vector<std::int32_t>& lists);

// The x-term table of a window [x0, x1] around cx for vectors of `lanes`
// floats: it covers x in [first, first + size) with
// first = (x0 / lanes - 1) * lanes and size = x_terms_size(x0, x1, lanes)
// (a multiple of lanes), and holds (x - cx)^2 * inv_distance for x in
// [x0, x1], +infinity elsewhere.
inline int x_terms_first(int x0, int lanes) { return (x0 / lanes - 1) * lanes; }
inline int x_terms_size(int x0, int x1, int lanes) {
  return (x1 / lanes + 2) * lanes - x_terms_first(x0, lanes);
}
void x_terms(float cx, int x0, int x1, float inv_distance, int lanes, float* out);

// The fuse distance of pixel x against one segment, in the order above.
inline float fuse_distance(const AssignRow& r, const RowSegment& seg, int x) {
  const float dx = static_cast<float>(x) - seg.cx;
  const float dI = static_cast<float>(r.pixels[x]) - seg.intensity;
  return ((dI * dI) * r.inv_intensity + (dx * dx) * r.inv_distance) + seg.row_term;
}

// The k-means update sums of one image row from pixel `start` on: for every
// run of equal labels k >= 0, sums[4k + 0] += sum of x, [4k + 1] += y * run
// length, [4k + 2] += sum of pixels, [4k + 3] += run length. Stops at the
// first negative label (an unreached pixel) and returns its x, or width.
int row_sums(const std::int32_t* labels, const std::uint8_t* pixels, int width, int y,
             std::int64_t* sums, int start = 0);
int row_sums_scalar(const std::int32_t* labels, const std::uint8_t* pixels, int width, int y,
                    std::int64_t* sums, int start = 0);

// The runs of equal labels of one row: runs[i] starts at runs[i].start and
// ends where runs[i + 1] starts (the last one at width). Returns the number
// of runs; `runs` has room for width runs.
int label_runs(const std::int32_t* labels, int width, LabelRun* runs);
int label_runs_scalar(const std::int32_t* labels, int width, LabelRun* runs);

// Per-cell L1 distances of two cell-major histograms of `cells` x kBins bins:
// out[k] = sum_b |a[k][b] - b[k][b]| (at most kBins * 65535, fits 32 bits).
void cell_l1(const Bin* a, const Bin* b, int cells, std::uint32_t* out);
void cell_l1_scalar(const Bin* a, const Bin* b, int cells, std::uint32_t* out);

// Per-cell L1 distances of two cell-major compact histograms of `cells` x
// kCompactBins 8-bit bins: out[k] = sum_b |a[k][b] - b[k][b]| (sum of
// absolute differences, at most kCompactBins * 255).
void cell_sad(const CompactBin* a, const CompactBin* b, int cells, std::uint32_t* out);
void cell_sad_scalar(const CompactBin* a, const CompactBin* b, int cells, std::uint32_t* out);

// The reference metric's per-cell distances: out[k] = sqrt(l1[k] * scale) /
// kBins (scale 1 for exact histograms; compact ones scale SADs to pixels).
// The SIMD kernel computes vectors of them with the same correctly rounded
// operations, so every value is identical to the scalar one.
void cell_distances(const std::uint32_t* l1, int cells, double scale, double* out);
void cell_distances_scalar(const std::uint32_t* l1, int cells, double scale, double* out);

// For tests and benchmarks: the SIMD targets compiled in and supported by
// this CPU (Highway target bits, best first), their names, and a way to
// restrict dispatch to one of them (0 restores the default choice).
std::vector<std::int64_t> simd_targets();
std::string simd_target_name(std::int64_t target);
void force_simd_target(std::int64_t target);
// The target dispatch picks now (e.g. "AVX3", "AVX2", "SSE4", "EMU128").
std::string active_simd_target();

}  // namespace lsgd::internal
