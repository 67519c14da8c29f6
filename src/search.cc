#include "lsgd/search.h"

#include <algorithm>
#include <cstring>

#include "internal/check.h"

namespace lsgd {
namespace {

// Sorts `pool` best first and keeps at most top_n of it in `out`.
void keep_best(std::vector<Candidate>& pool, int top_n, std::vector<Candidate>& out) {
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

}  // namespace

const char* to_string(SearchMode mode) {
  switch (mode) {
    case SearchMode::kExhaustive:
      return "exhaustive";
    case SearchMode::kDynamicNodes:
      return "nodes";
  }
  return "unknown";
}

SearchMode parse_search_mode(const char* name) {
  if (std::strcmp(name, "exhaustive") == 0) return SearchMode::kExhaustive;
  if (std::strcmp(name, "nodes") == 0) return SearchMode::kDynamicNodes;
  internal::throw_invalid("search mode '", name, "' is unknown: expected exhaustive or nodes");
}

void DynamicNodeOptions::check() const {
  internal::check_range_open_low("search.nodes.threshold_0", threshold_0, 0.0, 10.0);
  internal::check_range("search.nodes.alpha", alpha, 0.0, 10.0);
  internal::check_range("search.nodes.beta", beta, 0.0, 10.0);
}

void SearchOptions::check() const {
  if (mode != SearchMode::kExhaustive && mode != SearchMode::kDynamicNodes) {
    internal::throw_invalid("search.mode = ", static_cast<int>(mode), " is unknown");
  }
  internal::check_range<std::int64_t>("search.min_gap", min_gap, 0, 1000000000, "frames");
  internal::check_range("search.top_n", top_n, 1, 1000);
  nodes.check();
}

bool better(const Candidate& a, const Candidate& b) {
  if (a.score != b.score) return a.score > b.score;
  return a.frame < b.frame;
}

void search_exhaustive(const FrameStore& store, const DescriptorView& query, std::int64_t query_id,
                       const SearchOptions& options, SimilarityMetric metric,
                       std::vector<Candidate>& scratch, std::vector<Candidate>& out,
                       std::vector<double>* row) {
  scratch.clear();
  const std::int64_t limit = std::max<std::int64_t>(0, std::min(store.size(), query_id - options.min_gap));
  if (row != nullptr) row->resize(static_cast<std::size_t>(limit));
  score_frames(
      store, query, metric, limit, [](std::int64_t j) { return j; },
      [&](std::int64_t, std::int64_t j, double score) {
        scratch.push_back({j, score});
        if (row != nullptr) (*row)[static_cast<std::size_t>(j)] = score;
      });
  keep_best(scratch, options.top_n, out);
}

DynamicNodes::Outcome DynamicNodes::assign(const FrameStore& store, const DescriptorView& query,
                                           std::int64_t query_id, const SearchOptions& options,
                                           SimilarityMetric metric, std::vector<Candidate>& scratch,
                                           std::vector<Candidate>& out) {
  if (query_id != store.size()) {
    internal::throw_invalid("DynamicNodes::assign: query ", query_id, " must be the next frame (",
                            store.size(), ")");
  }
  Outcome outcome;
  out.clear();
  // Thresholds relative to how similar the query is to its previous frame
  // (reference implementation; the first frame compares with itself: 1).
  const double previous = query_id > 0 ? similarity(query, store.view(query_id - 1), metric) : 1.0;
  outcome.similarities += query_id > 0 ? 1 : 0;
  const double base = options.nodes.threshold_0 * previous;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    std::vector<std::int64_t>& node = nodes_[i];
    if (query_id - node.front() <= options.min_gap) continue;  // first frame too recent
    const double first = similarity(query, store.view(node.front()), metric);
    ++outcome.similarities;
    if (!(first > options.nodes.alpha * base)) continue;
    scratch.resize(node.size());
    scratch[0] = {node.front(), first};
    score_frames(
        store, query, metric, static_cast<std::int64_t>(node.size()) - 1,
        [&node](std::int64_t m) { return node[static_cast<std::size_t>(m) + 1]; },
        [&](std::int64_t m, std::int64_t frame, double s) {
          scratch[static_cast<std::size_t>(m) + 1] = {frame, s};
        });
    double sum = 0;  // first, then the members in order
    for (const Candidate& c : scratch) sum += c.score;
    outcome.similarities += static_cast<std::int64_t>(node.size()) - 1;
    if (!(sum / static_cast<double>(node.size()) > options.nodes.beta * base)) continue;
    node.push_back(query_id);
    // Members inside the temporal window are never candidates.
    const std::int64_t limit = query_id - options.min_gap;
    scratch.erase(std::remove_if(scratch.begin(), scratch.end(),
                                 [limit](const Candidate& c) { return c.frame >= limit; }),
                  scratch.end());
    keep_best(scratch, options.top_n, out);
    outcome.node = static_cast<std::int64_t>(i);
    return outcome;
  }
  nodes_.push_back({query_id});
  outcome.node = static_cast<std::int64_t>(nodes_.size()) - 1;
  outcome.created = true;
  return outcome;
}

const std::vector<std::int64_t>& DynamicNodes::members(std::int64_t node) const {
  if (node < 0 || node >= size()) {
    internal::throw_invalid("DynamicNodes::members: node ", node, " does not exist (", size(),
                            " nodes)");
  }
  return nodes_[static_cast<std::size_t>(node)];
}

void DynamicNodes::restore(std::vector<std::vector<std::int64_t>> nodes) {
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    if (nodes[k].empty()) internal::throw_invalid("DynamicNodes::restore: node ", k, " is empty");
    for (std::size_t i = 0; i < nodes[k].size(); ++i) {
      if (nodes[k][i] < 0 || (i > 0 && nodes[k][i] <= nodes[k][i - 1])) {
        internal::throw_invalid("DynamicNodes::restore: node ", k, " member ", i, " is frame ",
                                nodes[k][i], ": ids must be >= 0 and increasing");
      }
    }
  }
  nodes_ = std::move(nodes);
}

}  // namespace lsgd
