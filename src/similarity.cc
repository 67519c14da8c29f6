#include "lsgd/similarity.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "internal/check.h"
#include "lsgd/limits.h"
#include "internal/kernels.h"

namespace lsgd {
namespace {

double normalized_cell_l1(const Bin* a, Count na, const Bin* b, Count nb) {
  if (na == 0 || nb == 0) return na == nb ? 0.0 : 2.0;
  const double sa = 1.0 / na, sb = 1.0 / nb;
  double sum = 0;
  for (int i = 0; i < kBins; ++i) sum += std::fabs(a[i] * sa - b[i] * sb);
  return sum;
}

constexpr int kBlock = 128;  // cells per call of a per-cell L1 kernel

// Calls f(k, L1 of cell k) for every cell of two cell-major histograms of
// `bins` bins per cell, the L1s computed by `kernel` (cell_l1 or cell_sad) a
// block of cells at a time.
template <typename T, typename Kernel, typename F>
void for_each_cell(const T* a, const T* b, int cells, int bins, Kernel kernel, F&& f) {
  std::uint32_t l1[kBlock];
  for (int k0 = 0; k0 < cells; k0 += kBlock) {
    const int n = std::min(kBlock, cells - k0);
    const std::size_t off = static_cast<std::size_t>(k0) * bins;
    kernel(a + off, b + off, n, l1);
    for (int i = 0; i < n; ++i) f(k0 + i, l1[i]);
  }
}

template <typename F>
void for_each_cell_l1(const DescriptorView& a, const DescriptorView& b, F&& f) {
  for_each_cell(a.hist, b.hist, a.cells, kBins, internal::cell_l1, f);
}

// SADs of the compact bins (HistogramStorage::kCompact).
template <typename F>
void for_each_cell_sad(const DescriptorView& a, const DescriptorView& b, F&& f) {
  for_each_cell(a.compact, b.compact, a.cells, kCompactBins, internal::cell_sad,
                [&](int, std::uint32_t sad) { f(sad); });
}

// What turns a cell's L1 into pixels for the reference metric: 1 for exact
// histograms; for compact ones the mean cell size over kCompactMass (so
// compact scores and thresholds match the exact ones).
double reference_scale(const DescriptorView& a, const DescriptorView& b) {
  return a.compact != nullptr ? 0.5 * (a.cell_pixels + b.cell_pixels) / kCompactMass : 1.0;
}

// The reference metric of the query against `count` <= kGroup frames:
// sum_k sqrt(L1_k * scale) / kBins, added in cell order, then
// 1 / (1 + sum / cells). A block of cells at a time, SIMD kernels give the
// per-cell L1s and distances (identical to the scalar expressions); the
// frames' sums are independent chains of additions, interleaved so the CPU
// overlaps them. Each is still added in cell order, so every score is
// bit-identical to scoring its frame alone.
constexpr int kGroup = 8;

void reference_scores(const DescriptorView& query, const DescriptorView* frames, int count,
                      double* out) {
  const int cells = query.cells;
  std::uint32_t l1[kGroup][kBlock];
  double d[kGroup][kBlock];
  double sums[kGroup] = {};
  for (int k0 = 0; k0 < cells; k0 += kBlock) {
    const int n = std::min(kBlock, cells - k0);
    for (int g = 0; g < count; ++g) {
      if (query.compact != nullptr) {
        const std::size_t off = static_cast<std::size_t>(k0) * kCompactBins;
        internal::cell_sad(query.compact + off, frames[g].compact + off, n, l1[g]);
      } else {
        const std::size_t off = static_cast<std::size_t>(k0) * kBins;
        internal::cell_l1(query.hist + off, frames[g].hist + off, n, l1[g]);
      }
    }
    for (int g = 0; g < count; ++g) {
      internal::cell_distances(l1[g], n, reference_scale(query, frames[g]), d[g]);
    }
    if (count == kGroup) {
      double s0 = sums[0], s1 = sums[1], s2 = sums[2], s3 = sums[3];
      double s4 = sums[4], s5 = sums[5], s6 = sums[6], s7 = sums[7];
      for (int i = 0; i < n; ++i) {
        s0 += d[0][i];
        s1 += d[1][i];
        s2 += d[2][i];
        s3 += d[3][i];
        s4 += d[4][i];
        s5 += d[5][i];
        s6 += d[6][i];
        s7 += d[7][i];
      }
      sums[0] = s0, sums[1] = s1, sums[2] = s2, sums[3] = s3;
      sums[4] = s4, sums[5] = s5, sums[6] = s6, sums[7] = s7;
    } else {
      for (int g = 0; g < count; ++g) {
        double s = sums[g];
        for (int i = 0; i < n; ++i) s += d[g][i];
        sums[g] = s;
      }
    }
  }
  for (int g = 0; g < count; ++g) out[g] = 1.0 / (1.0 + sums[g] / cells);
}

// The mass-normalised metrics of compact storage, where l1 and normalized_l1
// coincide (every cell has mass kCompactMass).
double compact_l1_similarity(const DescriptorView& a, const DescriptorView& b) {
  std::uint64_t sad = 0;
  for_each_cell_sad(a, b, [&](std::uint32_t cell) { sad += cell; });
  const double score = 1.0 - static_cast<double>(sad) / (2.0 * kCompactMass * a.cells);
  return std::max(0.0, score);  // rounding can add a little mass
}

// The type a view knows (DescriptorView::type), or nullptr.
const char* known_type(const DescriptorView& v) {
  return v.type != nullptr && *v.type != '\0' ? v.type : nullptr;
}

// Throws InvalidArgument when both views know what they count and it differs
// (a gradient descriptor scored against an intensity one gave 0.77).
void check_same_type(const DescriptorView& a, const DescriptorView& b, const char* what) {
  const char* ta = known_type(a);
  const char* tb = known_type(b);
  if (ta == nullptr || tb == nullptr || ta == tb || std::strcmp(ta, tb) == 0) return;
  internal::throw_invalid(what, ": the descriptors count different things (", ta, " and ", tb,
                          "): describe both with the same descriptor options");
}

void check_comparable(const DescriptorView& a, const DescriptorView& b, const char* what) {
  check_same_type(a, b, what);
  if (a.cells != b.cells || a.cells <= 0) {
    internal::throw_invalid(what, ": descriptors have ", a.cells, " and ", b.cells,
                            " cells; frames must have the same size and superpixel_size");
  }
  if (a.storage() != b.storage()) {
    internal::throw_invalid(what, ": one descriptor is ", to_string(a.storage()), " and the other ",
                            to_string(b.storage()), "; both must have the same descriptor.storage");
  }
}

}  // namespace

const char* to_string(SimilarityMetric metric) {
  switch (metric) {
    case SimilarityMetric::kReference:
      return "reference";
    case SimilarityMetric::kL1:
      return "l1";
    case SimilarityMetric::kNormalizedL1:
      return "normalized_l1";
  }
  return "unknown";
}

SimilarityMetric parse_similarity_metric(const char* name) {
  for (auto m :
       {SimilarityMetric::kReference, SimilarityMetric::kL1, SimilarityMetric::kNormalizedL1}) {
    if (std::strcmp(name, to_string(m)) == 0) return m;
  }
  internal::throw_invalid("similarity metric '", internal::shown_value(name),
                          "' is unknown: expected reference, l1 or normalized_l1");
}

const OptionTable<SimilarityOptions>& SimilarityOptions::fields() {
  using S = SimilarityOptions;
  static const OptionTable<S> table = {
      enum_option("metric", &S::metric,
                  {SimilarityMetric::kReference, SimilarityMetric::kL1,
                   SimilarityMetric::kNormalizedL1},
                  parse_similarity_metric,
                  "reference: the authors' formula; l1: histogram L1; normalized_l1: L1 of "
                  "histograms normalised per cell"),
  };
  return table;
}

void SimilarityOptions::check() const {
  if (metric != SimilarityMetric::kReference && metric != SimilarityMetric::kL1 &&
      metric != SimilarityMetric::kNormalizedL1) {
    internal::throw_invalid("similarity.metric = ", static_cast<int>(metric), " is unknown");
  }
}

double similarity(const DescriptorView& a, const DescriptorView& b, SimilarityMetric metric) {
  check_comparable(a, b, "similarity");
  const int cells = a.cells;
  switch (metric) {
    case SimilarityMetric::kReference: {
      double score = 0;
      reference_scores(a, &b, 1, &score);
      return score;
    }
    case SimilarityMetric::kL1: {
      if (a.compact != nullptr) return compact_l1_similarity(a, b);
      std::uint64_t l1 = 0, mass = 0;
      for_each_cell_l1(a, b, [&](int k, std::uint32_t cell) {
        l1 += cell;
        mass += static_cast<std::uint64_t>(a.pixels[k]) + b.pixels[k];
      });
      return mass == 0 ? 1.0 : 1.0 - static_cast<double>(l1) / static_cast<double>(mass);
    }
    case SimilarityMetric::kNormalizedL1: {
      if (a.compact != nullptr) return compact_l1_similarity(a, b);
      double sum = 0;
      for (int k = 0; k < cells; ++k) {
        const std::size_t off = static_cast<std::size_t>(k) * kBins;
        sum += normalized_cell_l1(a.hist + off, a.pixels[k], b.hist + off, b.pixels[k]);
      }
      return 1.0 - sum / (2.0 * cells);
    }
  }
  internal::throw_invalid("similarity: unknown metric ", static_cast<int>(metric));
}

void similarities(const DescriptorView& query, const DescriptorView* frames, std::size_t count,
                  SimilarityMetric metric, double* out) {
  for (std::size_t i = 0; i < count; ++i) check_comparable(query, frames[i], "similarities");
  if (metric != SimilarityMetric::kReference) {
    for (std::size_t i = 0; i < count; ++i) out[i] = similarity(query, frames[i], metric);
    return;
  }
  for (std::size_t i = 0; i < count; i += kGroup) {
    const int n = static_cast<int>(std::min<std::size_t>(kGroup, count - i));
    reference_scores(query, frames + i, n, out + i);
  }
}

std::vector<TopMatch> match_top_k(const std::vector<DescriptorView>& reference,
                                  const std::vector<DescriptorView>& queries, int top_k,
                                  SimilarityMetric metric, std::int64_t query_offset) {
  if (top_k < 1 || top_k > kMaxTopK) {
    internal::throw_invalid("match: top_k ", top_k, " must be in [1, ", kMaxTopK, "]");
  }
  if (reference.empty()) internal::throw_invalid("match: the reference holds no frame");
  // Query ids are frame ids: query_offset + the last index stays within them.
  if (query_offset < 0 || query_offset > kMaxFrameId - static_cast<std::int64_t>(queries.size())) {
    internal::throw_invalid("match: query_offset ", query_offset, " must be in [0, ", kMaxFrameId,
                            " - the ", queries.size(), " queries]");
  }
  // Every descriptor counts what the first that knows it counts (views of
  // unknown type, from arrays, are taken as they come): a query compared only
  // with each reference would let a reference mix two kinds.
  const DescriptorView* known = nullptr;
  for (const std::vector<DescriptorView>* list : {&reference, &queries}) {
    for (const DescriptorView& v : *list) {
      if (known == nullptr && known_type(v) != nullptr) known = &v;
      if (known != nullptr) check_same_type(*known, v, "match");
    }
  }
  const std::size_t k = std::min(static_cast<std::size_t>(top_k), reference.size());
  std::vector<TopMatch> out;
  out.reserve(k * queries.size());
  std::vector<double> scores(reference.size());
  std::vector<std::size_t> order(reference.size());
  for (std::size_t q = 0; q < queries.size(); ++q) {
    similarities(queries[q], reference.data(), reference.size(), metric, scores.data());
    // Standardised against the query's own distribution over the reference.
    double mean = 0;
    for (const double v : scores) mean += v;
    mean /= static_cast<double>(scores.size());
    double var = 0;
    for (const double v : scores) var += (v - mean) * (v - mean);
    const double sd = std::sqrt(var / static_cast<double>(scores.size()));
    for (std::size_t j = 0; j < order.size(); ++j) order[j] = j;
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(k), order.end(),
                      [&](std::size_t a, std::size_t b) {
                        return scores[a] > scores[b] || (scores[a] == scores[b] && a < b);
                      });
    for (std::size_t r = 0; r < k; ++r) {
      const std::size_t j = order[r];
      out.push_back({query_offset + static_cast<std::int64_t>(q), static_cast<std::int64_t>(j),
                     sd > 0 ? (scores[j] - mean) / sd : 0.0, scores[j], static_cast<int>(r + 1)});
    }
  }
  return out;
}

}  // namespace lsgd
