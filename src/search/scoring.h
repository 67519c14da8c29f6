// Helpers shared by the search modes (src/search/).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "lsgd/frame_store.h"
#include "lsgd/search.h"
#include "lsgd/similarity.h"

namespace lsgd::internal {

// Sorts `pool` best first and keeps at most top_n of it in `out`.
inline void keep_best(std::vector<Candidate>& pool, int top_n, std::vector<Candidate>& out) {
  const std::size_t n = std::min(pool.size(), static_cast<std::size_t>(top_n));
  std::partial_sort(pool.begin(), pool.begin() + static_cast<std::ptrdiff_t>(n), pool.end(),
                    better);
  out.assign(pool.begin(), pool.begin() + static_cast<std::ptrdiff_t>(n));
}

// Scores the stored frames id(0), ..., id(count - 1) against the query and
// calls f(i, frame, score) for each, in order. similarities() takes them
// kBatch at a time, which overlaps their reference-metric sums.
template <typename Id, typename F>
void score_frames(const FrameStore& store, const DescriptorView& query, SimilarityMetric metric,
                  std::int64_t count, Id&& id, F&& f) {
  constexpr std::int64_t kBatch = 16;
  DescriptorView views[kBatch];
  double scores[kBatch];
  for (std::int64_t i0 = 0; i0 < count; i0 += kBatch) {
    const std::int64_t n = std::min(kBatch, count - i0);
    for (std::int64_t i = 0; i < n; ++i) views[i] = store.view(id(i0 + i));
    similarities(query, views, static_cast<std::size_t>(n), metric, scores);
    for (std::int64_t i = 0; i < n; ++i) f(i0 + i, id(i0 + i), scores[i]);
  }
}

}  // namespace lsgd::internal
