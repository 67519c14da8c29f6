#include "lsgd/search.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>

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

}  // namespace

const char* to_string(SearchMode mode) {
  switch (mode) {
    case SearchMode::kExhaustive: return "exhaustive";
    case SearchMode::kDynamicNodes: return "nodes";
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
                       std::vector<Candidate>& scratch, std::vector<Candidate>& out) {
  scratch.clear();
  const std::int64_t limit = std::min(store.size(), query_id - options.min_gap);
  for (std::int64_t j = 0; j < limit; ++j) {
    scratch.push_back({j, similarity(query, store.view(j), metric)});
  }
  keep_best(scratch, options.top_n, out);
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Widened distance intervals get this relative slack, and bound-based
// decisions keep this margin: both far above the rounding error of the
// distances and scores (sums of at most a few thousand terms in double
// precision), so a bound never decides what the exact scores would decide
// otherwise.
constexpr double kSlack = 1e-9;
constexpr double kMargin = 1e-9;

std::size_t view_bytes(const DescriptorView& d) {
  const std::size_t cells = static_cast<std::size_t>(d.cells);
  return d.storage() == HistogramStorage::kCompact
             ? cells * kCompactBins + sizeof(double)
             : cells * (kBins * sizeof(Bin) + sizeof(Count));
}

// The bytes that define a descriptor (bins, and pixel counts or cell size).
void copy_view(const DescriptorView& d, std::vector<unsigned char>& out) {
  out.resize(view_bytes(d));
  unsigned char* p = out.data();
  const std::size_t cells = static_cast<std::size_t>(d.cells);
  if (d.storage() == HistogramStorage::kCompact) {
    std::memcpy(p, d.compact, cells * kCompactBins);
    std::memcpy(p + cells * kCompactBins, &d.cell_pixels, sizeof(double));
  } else {
    std::memcpy(p, d.hist, cells * kBins * sizeof(Bin));
    std::memcpy(p + cells * kBins * sizeof(Bin), d.pixels, cells * sizeof(Count));
  }
}

bool same_view(const DescriptorView& d, const std::vector<unsigned char>& bytes) {
  if (bytes.size() != view_bytes(d)) return false;
  const std::size_t cells = static_cast<std::size_t>(d.cells);
  const unsigned char* p = bytes.data();
  if (d.storage() == HistogramStorage::kCompact) {
    return std::memcmp(p, d.compact, cells * kCompactBins) == 0 &&
           std::memcmp(p + cells * kCompactBins, &d.cell_pixels, sizeof(double)) == 0;
  }
  return std::memcmp(p, d.hist, cells * kBins * sizeof(Bin)) == 0 &&
         std::memcmp(p + cells * kBins * sizeof(Bin), d.pixels, cells * sizeof(Count)) == 0;
}

}  // namespace

bool DynamicNodes::follows_last_query(const FrameStore& store, std::int64_t query_id) const {
  return query_id > 0 && last_query_ == query_id - 1 &&
         same_view(store.view(query_id - 1), last_bytes_);
}

void DynamicNodes::forget_bounds() {
  known_.clear();
  to_first_.clear();
  last_query_ = -1;
  valid_from_ = call_ + 1;
}

void DynamicNodes::distance_bounds(std::int64_t f, double& lo, double& hi) const {
  lo = 0;
  hi = kInf;
  if (f >= static_cast<std::int64_t>(known_.size())) return;
  const Known& k = known_[static_cast<std::size_t>(f)];
  if (k.call < valid_from_) return;
  const double now = path_[static_cast<std::size_t>(call_)];
  const double widen = now - path_[static_cast<std::size_t>(k.call)];
  const double slack = kSlack * (1.0 + now + k.lo);
  lo = std::max(0.0, k.lo - widen - slack);
  hi = k.hi + widen + slack;
}

void DynamicNodes::record(std::int64_t f, double lo, double hi) {
  if (f >= static_cast<std::int64_t>(known_.size())) known_.resize(static_cast<std::size_t>(f) + 1);
  known_[static_cast<std::size_t>(f)] = {lo, hi, call_};
}

DynamicNodes::Outcome DynamicNodes::assign(const FrameStore& store, const DescriptorView& query,
                                           std::int64_t query_id, const SearchOptions& options,
                                           SimilarityMetric metric,
                                           std::vector<Candidate>& scratch,
                                           std::vector<Candidate>& out) {
  if (query_id != store.size()) {
    internal::throw_invalid("DynamicNodes::assign: query ", query_id, " must be the next frame (",
                            store.size(), ")");
  }
  Outcome outcome;
  out.clear();
  ++call_;
  path_.push_back(0.0);
  // The bounds live in one metric space: one metric, and for compact storage
  // with the reference metric one cell size (the store's).
  if (metric != metric_) forget_bounds();
  metric_ = metric;
  const bool bounded =
      options.nodes.bounds && (query.storage() == HistogramStorage::kExact || store.size() == 0 ||
                               query.cell_pixels == store.view(0).cell_pixels);
  const bool follows = follows_last_query(store, query_id);
  last_query_ = -1;  // set again when this call succeeds
  if (!follows && query_id > 0 && query_id - 1 < static_cast<std::int64_t>(to_first_.size())) {
    to_first_[static_cast<std::size_t>(query_id - 1)] = -1;  // measured on another descriptor
  }
  if (!bounded || !follows) valid_from_ = call_;

  // Thresholds relative to how similar the query is to its previous frame
  // (reference implementation; the first frame compares with itself: 1).
  double previous = 1.0;
  if (query_id > 0) {
    const DescriptorView prev = store.view(query_id - 1);
    const double d = distance(query, prev, metric);
    previous = score_from_distance(d, query, prev, metric);
    ++outcome.similarities;
    if (bounded && follows) {
      path_[static_cast<std::size_t>(call_)] = path_[static_cast<std::size_t>(call_ - 1)] + d;
    }
    if (bounded) record(query_id - 1, d, d);
  }
  const double base = options.nodes.threshold_0 * previous;
  const double first_threshold = options.nodes.alpha * base;
  const double mean_threshold = options.nodes.beta * base;

  auto score_member = [&](Member& m) {
    const DescriptorView view = store.view(m.frame);
    const double d = distance(query, view, metric);
    const double s = score_from_distance(d, query, view, metric);
    m = {m.frame, s, s, d, d, true};
    ++outcome.similarities;
    if (bounded) record(m.frame, d, d);
  };

  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    std::vector<std::int64_t>& node = nodes_[i];
    const std::int64_t f = node.front();
    if (query_id - f <= options.min_gap) continue;  // first frame too recent
    const DescriptorView first_view = store.view(f);
    if (bounded) {
      double lo, hi;
      distance_bounds(f, lo, hi);
      if (score_from_distance(lo, query, first_view, metric) + kMargin <= first_threshold) {
        ++outcome.skipped;  // its first frame cannot pass alpha * base
        continue;
      }
    }
    const double d_first = distance(query, first_view, metric);
    const double first = score_from_distance(d_first, query, first_view, metric);
    ++outcome.similarities;
    if (bounded) record(f, d_first, d_first);
    if (!(first > first_threshold)) continue;

    // Score bounds of every member (members_[0] is the first frame).
    members_.clear();
    members_.push_back({f, first, first, d_first, d_first, true});
    double sum_lo = first, sum_hi = first;
    for (std::size_t k = 1; k < node.size(); ++k) {
      Member m{node[k], 0.0, 1.0, 0.0, kInf, false};
      if (!bounded) {
        score_member(m);
      } else {
        distance_bounds(m.frame, m.d_lo, m.d_hi);
        const double to_first = m.frame < static_cast<std::int64_t>(to_first_.size())
                                    ? to_first_[static_cast<std::size_t>(m.frame)]
                                    : -1.0;
        if (to_first >= 0) {  // triangle through the first frame
          const double slack = kSlack * (1.0 + d_first + to_first);
          m.d_lo = std::max(m.d_lo, std::fabs(d_first - to_first) - slack);
          m.d_hi = std::min(m.d_hi, d_first + to_first + slack);
        }
        // Every metric's score lies in [0, 1].
        const DescriptorView view = store.view(m.frame);
        m.s_lo = std::max(0.0, score_from_distance(m.d_hi, query, view, metric));
        m.s_hi = std::min(1.0, score_from_distance(m.d_lo, query, view, metric));
      }
      sum_lo += m.s_lo;
      sum_hi += m.s_hi;
      members_.push_back(m);
    }

    // Mean test: sum / n > beta * base. Decided by the bounds when they are
    // clear of the threshold; otherwise members are scored, widest score
    // interval first, until they are (or until every member is scored, and the
    // exact sum, in member order as Algorithm 1 adds it, decides).
    const double n = static_cast<double>(node.size());
    int verdict = 0;  // +1 accept, -1 reject
    auto bounds_decide = [&] {
      if (sum_hi / n + kMargin <= mean_threshold) return -1;
      if (sum_lo / n - kMargin > mean_threshold) return 1;
      return 0;
    };
    if (bounded) {
      verdict = bounds_decide();
      if (verdict == 0) {
        order_.clear();
        for (std::size_t k = 1; k < members_.size(); ++k) {
          if (!members_[k].scored) order_.push_back(k);
        }
        std::sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) {
          const double wa = members_[a].s_hi - members_[a].s_lo;
          const double wb = members_[b].s_hi - members_[b].s_lo;
          return wa != wb ? wa > wb : a < b;
        });
        for (const std::size_t k : order_) {
          Member& m = members_[k];
          sum_lo -= m.s_lo;
          sum_hi -= m.s_hi;
          score_member(m);
          sum_lo += m.s_lo;
          sum_hi += m.s_hi;
          verdict = bounds_decide();
          if (verdict != 0) break;
        }
      }
    }
    const bool all_scored =
        std::all_of(members_.begin(), members_.end(), [](const Member& m) { return m.scored; });
    if (all_scored) {
      double sum = 0;
      for (const Member& m : members_) sum += m.s_lo;
      verdict = sum / n > mean_threshold ? 1 : -1;
    }
    if (verdict < 0) {
      for (const Member& m : members_) {
        if (!m.scored) {
          ++outcome.skipped;
          record(m.frame, m.d_lo, m.d_hi);
        }
      }
      continue;
    }

    // Accepted: the best top_n members outside the temporal window are the
    // candidates. Scored ones enter at once; an unscored one is scored only if
    // its score bound can beat the current top_n-th score.
    node.push_back(query_id);
    if (bounded) {
      if (query_id >= static_cast<std::int64_t>(to_first_.size())) {
        to_first_.resize(static_cast<std::size_t>(query_id) + 1, -1.0);
      }
      to_first_[static_cast<std::size_t>(query_id)] = d_first;
    }
    const std::int64_t limit = query_id - options.min_gap;
    const std::size_t top_n = static_cast<std::size_t>(options.top_n);
    scratch.clear();
    std::vector<double>& heap = top_scores_;  // min-heap of the best top_n scores
    heap.clear();
    auto offer = [&](const Member& m) {
      scratch.push_back({m.frame, m.s_lo});
      if (heap.size() < top_n) {
        heap.push_back(m.s_lo);
        std::push_heap(heap.begin(), heap.end(), std::greater<>());
      } else if (m.s_lo > heap.front()) {
        std::pop_heap(heap.begin(), heap.end(), std::greater<>());
        heap.back() = m.s_lo;
        std::push_heap(heap.begin(), heap.end(), std::greater<>());
      }
    };
    order_.clear();
    for (std::size_t k = 0; k < members_.size(); ++k) {
      if (members_[k].frame >= limit) continue;  // inside the temporal window
      if (members_[k].scored) {
        offer(members_[k]);
      } else {
        order_.push_back(k);
      }
    }
    std::sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) {
      return members_[a].s_hi != members_[b].s_hi ? members_[a].s_hi > members_[b].s_hi : a < b;
    });
    for (const std::size_t k : order_) {
      Member& m = members_[k];
      if (heap.size() == top_n && m.s_hi + kMargin <= heap.front()) break;  // nor any after it
      score_member(m);
      offer(m);
    }
    for (const Member& m : members_) {
      if (!m.scored) {
        ++outcome.skipped;
        record(m.frame, m.d_lo, m.d_hi);
      }
    }
    keep_best(scratch, options.top_n, out);
    outcome.node = static_cast<std::int64_t>(i);
    if (bounded) {
      copy_view(query, last_bytes_);
      last_query_ = query_id;
    }
    return outcome;
  }
  nodes_.push_back({query_id});
  outcome.node = static_cast<std::int64_t>(nodes_.size()) - 1;
  outcome.created = true;
  if (bounded) {
    copy_view(query, last_bytes_);
    last_query_ = query_id;
  }
  return outcome;
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
  forget_bounds();
}

}  // namespace lsgd
