#include "lsgd/search/dynamic_nodes.h"

#include <algorithm>

#include "internal/check.h"
#include "search/scoring.h"

namespace lsgd {

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
    internal::score_frames(
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
    internal::keep_best(scratch, options.top_n, out);
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

namespace {

class NodesSearch final : public CandidateSearch {
 public:
  explicit NodesSearch(const SearchOptions& options) : options_(options) {}
  const char* name() const override { return kNodesSearch; }
  bool scores_every_frame() const override { return false; }
  Outcome search(const Query& q, std::vector<Candidate>& out, std::vector<double>&) override {
    const DynamicNodes::Outcome o =
        nodes_.assign(q.store, q.descriptor, q.id, options_, q.metric, scratch_, out);
    return {o.node, o.created};
  }
  bool has_groups() const override { return true; }
  std::int64_t groups() const override { return nodes_.size(); }
  const std::vector<std::int64_t>& members(std::int64_t group) const override {
    return nodes_.members(group);
  }

  // As assign() builds them: every stored frame in exactly one node, nodes in
  // the order their first frames were stored.
  void restore_groups(std::vector<std::vector<std::int64_t>> nodes, std::int64_t frames) override {
    std::vector<std::int64_t> node_of(static_cast<std::size_t>(std::max<std::int64_t>(frames, 0)), -1);
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      for (const std::int64_t id : nodes[k]) {
        if (id < 0 || id >= frames) {
          internal::throw_invalid("restore_nodes: frame ", id, " of node ", k,
                                  " is not stored (", frames, " frames)");
        }
        std::int64_t& owner = node_of[static_cast<std::size_t>(id)];
        if (owner >= 0) {
          internal::throw_invalid("restore_nodes: frame ", id, " is in node ", owner,
                                  " and in node ", k);
        }
        owner = static_cast<std::int64_t>(k);
      }
      if (k > 0 && !nodes[k].empty() && !nodes[k - 1].empty() &&
          nodes[k].front() <= nodes[k - 1].front()) {
        internal::throw_invalid("restore_nodes: node ", k, " starts at frame ", nodes[k].front(),
                                ", not after node ", k - 1, "'s first frame ",
                                nodes[k - 1].front());
      }
    }
    for (std::size_t id = 0; id < node_of.size(); ++id) {
      if (node_of[id] < 0) {
        internal::throw_invalid("restore_nodes: frame ", id, " is in no node (every stored frame "
                                "joined or created one)");
      }
    }
    nodes_.restore(std::move(nodes));
  }

 private:
  SearchOptions options_;
  DynamicNodes nodes_;
  std::vector<Candidate> scratch_;
};

}  // namespace

std::unique_ptr<CandidateSearch> make_nodes_search(const SearchOptions& options) {
  return std::make_unique<NodesSearch>(options);
}

}  // namespace lsgd
