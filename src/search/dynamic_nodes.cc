#include "lsgd/search/dynamic_nodes.h"

#include <algorithm>
#include <unordered_map>

#include "internal/check.h"
#include "search/scoring.h"

namespace lsgd {

DynamicNodes::Outcome DynamicNodes::assign(const FrameStore& store, const DescriptorView& query,
                                           std::int64_t query_id, const SearchOptions& options,
                                           SimilarityMetric metric, std::vector<Candidate>& scratch,
                                           std::vector<Candidate>& out) {
  Outcome outcome = find(store, query, query_id, options, metric, scratch, out);
  add_member(outcome.node, query_id);
  return outcome;
}

DynamicNodes::Outcome DynamicNodes::find(const FrameStore& store, const DescriptorView& query,
                                         std::int64_t query_id, const SearchOptions& options,
                                         SimilarityMetric metric, std::vector<Candidate>& scratch,
                                         std::vector<Candidate>& out) const {
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
    const std::vector<std::int64_t>& node = nodes_[i];
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
    // Members inside the temporal window are never candidates.
    const std::int64_t limit = query_id - options.min_gap;
    scratch.erase(std::remove_if(scratch.begin(), scratch.end(),
                                 [limit](const Candidate& c) { return c.frame >= limit; }),
                  scratch.end());
    internal::keep_best(scratch, options.top_n, out);
    outcome.node = static_cast<std::int64_t>(i);
    return outcome;
  }
  outcome.node = static_cast<std::int64_t>(nodes_.size());
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

void DynamicNodes::add_member(std::int64_t node, std::int64_t frame) {
  if (node < 0 || node > size()) {
    internal::throw_invalid("DynamicNodes::add_member: node ", node, " does not exist yet (",
                            size(), " nodes)");
  }
  if (node == size()) {
    nodes_.emplace_back();
  } else if (frame <= nodes_[static_cast<std::size_t>(node)].back()) {
    internal::throw_invalid("DynamicNodes::add_member: frame ", frame, " is not after node ", node,
                            "'s last frame ", nodes_[static_cast<std::size_t>(node)].back());
  }
  nodes_[static_cast<std::size_t>(node)].push_back(frame);
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
    node_of_.resize(static_cast<std::size_t>(q.id));  // a search whose frame was not stored
    node_of_.push_back(o.node);
    return {o.node, o.created};
  }
  // The node the query would join, nothing added.
  Outcome query(const Query& q, std::vector<Candidate>& out, std::vector<double>&) override {
    const DynamicNodes::Outcome o =
        nodes_.find(q.store, q.descriptor, q.id, options_, q.metric, scratch_, out);
    return {o.node, o.created};
  }
  bool has_groups() const override { return true; }
  std::int64_t groups() const override { return nodes_.size(); }
  const std::vector<std::int64_t>& members(std::int64_t group) const override {
    return nodes_.members(group);
  }

  std::int64_t group_of(std::int64_t frame) const override {
    if (frame < 0 || frame >= static_cast<std::int64_t>(node_of_.size())) {
      internal::throw_invalid("nodes: frame ", frame, " is not stored (", node_of_.size(),
                              " frames)");
    }
    return node_of_[static_cast<std::size_t>(frame)];
  }

  // State, version 1: the node the frame joined or created (int64).
  bool has_state() const override { return true; }
  void save_frame(std::int64_t frame, StateWriter& out) const override {
    out.put_i64(group_of(frame));
  }
  void check_frame(std::int64_t frame, int, int, std::uint32_t version,
                   StateReader in) const override {
    check_state_version(in.what(), name(), version, 1);
    const std::int64_t node = in.get_i64();
    in.finish();
    if (frame != static_cast<std::int64_t>(node_of_.size())) {
      internal::throw_invalid(in.what(), ": frame ", frame, " restored after ", node_of_.size(),
                              " frames");
    }
    if (node < 0 || node > nodes_.size()) {
      internal::throw_invalid(in.what(), ": node ", node, " does not exist yet (", nodes_.size(),
                              " nodes before this frame)");
    }
  }
  void restore_frame(std::int64_t frame, int, int, std::uint32_t, StateReader in) override {
    const std::int64_t node = in.get_i64();
    nodes_.add_member(node, frame);
    node_of_.push_back(node);
  }
  // A node keeps its kept frames, the first of them its first frame; a node
  // left without frames is gone, and the nodes are numbered again in the
  // order of their first frames (as assign() would have created them).
  bool forgets() const override { return true; }
  void restore_renumbered(std::int64_t frame, int, int, std::uint32_t, StateReader in,
                          const FrameRenumbering&) override {
    if (frame == 0) renumbered_nodes_.clear();
    const std::int64_t before = in.get_i64();
    const std::int64_t node =
        renumbered_nodes_.emplace(before, static_cast<std::int64_t>(renumbered_nodes_.size()))
            .first->second;
    nodes_.add_member(node, frame);
    node_of_.push_back(node);
  }

 private:
  SearchOptions options_;
  DynamicNodes nodes_;
  std::vector<std::int64_t> node_of_;  // node of each stored frame
  // restore_renumbered(): the new number of each node numbered before.
  std::unordered_map<std::int64_t, std::int64_t> renumbered_nodes_;
  std::vector<Candidate> scratch_;
};

}  // namespace

std::unique_ptr<CandidateSearch> make_nodes_search(const SearchOptions& options) {
  return std::make_unique<NodesSearch>(options);
}

}  // namespace lsgd
