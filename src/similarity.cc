#include "lsgd/similarity.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "internal/check.h"
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

// Calls f(k, L1 of cell k) for every cell of two cell-major histograms of
// `bins` bins per cell, the L1s computed by `kernel` (cell_l1 or cell_sad) a
// block of cells at a time.
template <typename T, typename Kernel, typename F>
void for_each_cell(const T* a, const T* b, int cells, int bins, Kernel kernel, F&& f) {
  constexpr int kBlock = 128;
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

// Compact storage: each cell's SAD is an L1 distance in units of
// 1 / kCompactMass of a cell, turned into pixels with the mean cell size for
// the reference metric (so its scores and thresholds match the exact ones'),
// and used as is for the mass-normalised metrics, for which l1 and
// normalized_l1 coincide (every cell has mass kCompactMass).
double compact_similarity(const DescriptorView& a, const DescriptorView& b,
                          SimilarityMetric metric) {
  const int cells = a.cells;
  if (metric == SimilarityMetric::kReference) {
    const double scale = 0.5 * (a.cell_pixels + b.cell_pixels) / kCompactMass;
    double sum = 0;
    for_each_cell_sad(a, b, [&](std::uint32_t sad) { sum += std::sqrt(sad * scale) / kBins; });
    return 1.0 / (1.0 + sum / cells);
  }
  std::uint64_t sad = 0;
  for_each_cell_sad(a, b, [&](std::uint32_t cell) { sad += cell; });
  const double score = 1.0 - static_cast<double>(sad) / (2.0 * kCompactMass * cells);
  return std::max(0.0, score);  // rounding can add a little mass
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
  internal::throw_invalid("similarity metric '", name,
                          "' is unknown: expected reference, l1 or normalized_l1");
}

void SimilarityOptions::check() const {
  if (metric != SimilarityMetric::kReference && metric != SimilarityMetric::kL1 &&
      metric != SimilarityMetric::kNormalizedL1) {
    internal::throw_invalid("similarity.metric = ", static_cast<int>(metric), " is unknown");
  }
}

double similarity(const DescriptorView& a, const DescriptorView& b, SimilarityMetric metric) {
  if (a.cells != b.cells || a.cells <= 0) {
    internal::throw_invalid("similarity: descriptors have ", a.cells, " and ", b.cells,
                            " cells; frames must have the same size and superpixel_size");
  }
  if (a.storage() != b.storage()) {
    internal::throw_invalid("similarity: one descriptor is ", to_string(a.storage()),
                            " and the other ", to_string(b.storage()),
                            "; both must have the same descriptor.storage");
  }
  if (a.storage() == HistogramStorage::kCompact) return compact_similarity(a, b, metric);
  const int cells = a.cells;
  switch (metric) {
    case SimilarityMetric::kReference: {
      double sum = 0;
      for_each_cell_l1(
          a, b, [&](int, std::uint32_t l1) { sum += std::sqrt(static_cast<double>(l1)) / kBins; });
      return 1.0 / (1.0 + sum / cells);
    }
    case SimilarityMetric::kL1: {
      std::uint64_t l1 = 0, mass = 0;
      for_each_cell_l1(a, b, [&](int k, std::uint32_t cell) {
        l1 += cell;
        mass += static_cast<std::uint64_t>(a.pixels[k]) + b.pixels[k];
      });
      return mass == 0 ? 1.0 : 1.0 - static_cast<double>(l1) / static_cast<double>(mass);
    }
    case SimilarityMetric::kNormalizedL1: {
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

}  // namespace lsgd
