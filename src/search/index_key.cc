#include "search/index_key.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>

namespace lsgd::internal {

void make_key(const DescriptorView& d, std::uint8_t* key) {
  for (int c = 0; c < d.cells; ++c) {
    std::uint32_t pooled[kKeyBins] = {};
    double mass = 0;
    if (d.compact != nullptr) {
      const CompactBin* h = d.compact + static_cast<std::size_t>(c) * kCompactBins;
      constexpr int per = kCompactBins / kKeyBins;
      for (int b = 0; b < kCompactBins; ++b) pooled[b / per] += h[b];
      for (const std::uint32_t v : pooled) mass += v;
    } else {
      const Bin* h = d.hist + static_cast<std::size_t>(c) * kBins;
      constexpr int per = kBins / kKeyBins;
      for (int b = 0; b < kBins; ++b) pooled[b / per] += h[b];
      mass = d.pixels[c];
    }
    for (int b = 0; b < kKeyBins; ++b) {
      const double v = mass > 0 ? std::round(pooled[b] * kKeyMass / mass) : 0.0;
      key[static_cast<std::size_t>(c) * kKeyBins + b] = static_cast<std::uint8_t>(std::min(v, 255.0));
    }
  }
}

namespace {

// A cell's key SAD, its cost under the metric.
float cell_cost(const std::uint8_t* x, const std::uint8_t* y, bool root) {
  int sad = 0;
  for (int i = 0; i < kKeyBins; ++i) sad += std::abs(int{x[i]} - int{y[i]});
  return root ? std::sqrt(static_cast<float>(sad)) : static_cast<float>(sad);
}

}  // namespace

// The graph's distance, most of an insertion's time (an insertion computes
// thousands of them): four cells at a time, one psadbw per cell, the four
// SADs gathered into one vector, their square roots (sqrtps rounds as
// std::sqrt) summed in four lanes. Against one cell at a time through a
// table of square roots (one dependent addition per cell): the 10^5-frame
// graph built in 62 s instead of 82 (docs/performance.md).
float key_distance(const void* a, const void* b, const void* param) {
  const auto& p = *static_cast<const KeySpaceParam*>(param);
  const auto* x = static_cast<const std::uint8_t*>(a);
  const auto* y = static_cast<const std::uint8_t*>(b);
  int c = 0;
  float sum = 0;
#if defined(__SSE2__)
  // SSE2 is the x86-64 baseline: no dispatch needed.
  const auto sad = [&](int cell) {
    const std::size_t at = static_cast<std::size_t>(cell) * kKeyBins;
    return _mm_sad_epu8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(x + at)),
                        _mm_loadu_si128(reinterpret_cast<const __m128i*>(y + at)));
  };
  __m128 acc = _mm_setzero_ps();
  for (; c + 4 <= p.cells; c += 4) {
    // psadbw leaves a cell's SAD in two 64-bit halves; add them per cell.
    const __m128i s0 = sad(c), s1 = sad(c + 1), s2 = sad(c + 2), s3 = sad(c + 3);
    const __m128i t01 = _mm_add_epi32(_mm_unpacklo_epi64(s0, s1), _mm_unpackhi_epi64(s0, s1));
    const __m128i t23 = _mm_add_epi32(_mm_unpacklo_epi64(s2, s3), _mm_unpackhi_epi64(s2, s3));
    const __m128 v = _mm_cvtepi32_ps(_mm_castps_si128(_mm_shuffle_ps(
        _mm_castsi128_ps(t01), _mm_castsi128_ps(t23), _MM_SHUFFLE(2, 0, 2, 0))));
    acc = _mm_add_ps(acc, p.sqrt ? _mm_sqrt_ps(v) : v);
  }
  alignas(16) float lanes[4];
  _mm_store_ps(lanes, acc);
  sum = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
#endif
  for (; c < p.cells; ++c) {
    sum += cell_cost(x + static_cast<std::size_t>(c) * kKeyBins, y + static_cast<std::size_t>(c) * kKeyBins, p.sqrt);
  }
  return sum;
}

}  // namespace lsgd::internal
