// Similarity of two LSGD descriptors, compared cell by cell (same grid index).
// All metrics return a score in [0, 1], 1 for identical descriptors, larger
// meaning more similar, so thresholds and dynamic nodes work with any of them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "lsgd/descriptor.h"

namespace lsgd {

enum class SimilarityMetric {
  // The reference implementation (what the paper's numbers come from):
  // d_k = sqrt(L1(h_k, h'_k)) / 256 per cell, score = 1 / (1 + mean_k d_k).
  kReference,
  // The paper's formula: the plain L1 distance summed over cells, mapped to a
  // score by 1 - sum_k L1_k / sum_k (n_k + n'_k) (n = pixels in the cell).
  // For frames of one size this is 1 - L1 / (2 * pixels): same ranking as L1.
  kL1,
  // Beyond the paper: L1 of histograms normalised to unit mass per cell, so
  // cells of different pixel counts weigh the same:
  // score = 1 - mean_k L1(h_k / n_k, h'_k / n'_k) / 2. An empty cell counts as
  // identical to an empty cell and as maximally different from a non-empty one.
  kNormalizedL1,
};

const char* to_string(SimilarityMetric metric);
// Parses "reference", "l1" or "normalized_l1"; throws InvalidArgument otherwise.
SimilarityMetric parse_similarity_metric(const char* name);

struct SimilarityOptions {
  // Which formula turns two descriptors into a score.
  SimilarityMetric metric = SimilarityMetric::kReference;
  void check() const;
  static const OptionTable<SimilarityOptions>& fields();  // lsgd/options.h
};

// Per-cell L1 by a SIMD kernel chosen at run time (identical to the scalar
// reference, see src/internal/kernels.h). Both descriptors must have the same number of
// cells and the same storage, and count the same thing when both views know
// it (DescriptorView::type; throws InvalidArgument otherwise).
//
// Compact descriptors (HistogramStorage::kCompact): the per-cell L1 is the sum
// of absolute differences of the 8-bit bins, in units of 1/kCompactMass of a
// cell. The reference metric scales it to pixels with the mean cell size
// (L1 ~ SAD * cell_pixels / kCompactMass), so scores and thresholds stay
// comparable to the exact ones; l1 and normalized_l1 both become
// 1 - sum_k SAD_k / (2 * kCompactMass * cells), clamped to [0, 1].
double similarity(const DescriptorView& a, const DescriptorView& b, SimilarityMetric metric);

// out[i] = similarity(query, frames[i], metric) for i < count, bit for bit,
// and faster for the reference metric: several frames are scored at once so
// that their in-order sums over cells overlap. Throws like similarity() when
// a frame does not match the query (before writing anything).
void similarities(const DescriptorView& query, const DescriptorView* frames, std::size_t count,
                  SimilarityMetric metric, double* out);

// One of a query's best reference frames (match_top_k).
struct TopMatch {
  std::int64_t query = 0;  // query_offset + the query's index
  std::int64_t match = 0;  // the reference frame's index
  // The similarity in standard deviations of the query's similarities to the
  // whole reference (comparable across queries, as the detector's
  // single-frame evidence; 0 when they are all equal).
  double score = 0;
  double similarity = 0;  // the metric's own value
  int rank = 1;           // 1 for the best
};

// Place recognition between two traverses (lsgd match, Python lsgd.match):
// the top_k (at most the reference's size) reference frames of every query,
// best first, equal similarities by lower index; queries in order.
// InvalidArgument for top_k outside [1, kMaxTopK], a query_offset that is
// negative or puts a query id beyond kMaxFrameId, an empty reference or
// descriptors that do not match (grid, storage, or what they count: every
// view that knows its type must name the first one's).
constexpr int kMaxTopK = 1000;
std::vector<TopMatch> match_top_k(const std::vector<DescriptorView>& reference,
                                  const std::vector<DescriptorView>& queries, int top_k,
                                  SimilarityMetric metric, std::int64_t query_offset = 0);

}  // namespace lsgd
