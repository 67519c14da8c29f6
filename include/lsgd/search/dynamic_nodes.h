// Search mode "nodes": the paper's dynamic nodes (Sec. III-D/E, Algorithm 1),
// groups of similar earlier frames created online, with the reference
// implementation's thresholds relative to the similarity between the query
// and its previous frame (DynamicNodeOptions in lsgd/search.h).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "lsgd/search.h"

namespace lsgd {

class DynamicNodes {
 public:
  struct Outcome {
    std::int64_t node = -1;  // node the query joined, or the one it created
    bool created = false;    // true when no node accepted the query
    std::int64_t similarities = 0;  // similarity evaluations spent
  };

  // Runs Algorithm 1 for frame `query_id` (which must be store.size(): the
  // query is assigned before it is stored). Writes the best top_n candidates of
  // the accepting node that lie outside the temporal window, best first; none
  // when a new node is created.
  Outcome assign(const FrameStore& store, const DescriptorView& query, std::int64_t query_id,
                 const SearchOptions& options, SimilarityMetric metric,
                 std::vector<Candidate>& scratch, std::vector<Candidate>& out);

  // The same answer without adding the query: the node it would join, or
  // size() when it would create one (Detector::query()).
  Outcome find(const FrameStore& store, const DescriptorView& query, std::int64_t query_id,
               const SearchOptions& options, SimilarityMetric metric,
               std::vector<Candidate>& scratch, std::vector<Candidate>& out) const;

  std::int64_t size() const { return static_cast<std::int64_t>(nodes_.size()); }
  // Frame ids of `node`, first frame first; InvalidArgument for a node that
  // does not exist.
  const std::vector<std::int64_t>& members(std::int64_t node) const;

  // Persistence: replaces the nodes by `nodes` (frame ids of each node, first
  // frame first, in creation order), as assign() would have built them.
  // Throws InvalidArgument, leaving the nodes unchanged, for an empty node, a
  // negative id or ids not increasing within a node.
  void restore(std::vector<std::vector<std::int64_t>> nodes);
  // Adds frame `frame` to `node` (an existing node, or size(): a new one), as
  // assign() would have. InvalidArgument, nodes unchanged, for another node or
  // a frame not after the node's last one.
  void add_member(std::int64_t node, std::int64_t frame);

 private:
  std::vector<std::vector<std::int64_t>> nodes_;  // frame ids, first frame first
};

// The registered mode (SearchMode::make). Its state (state.h, version 1):
// the node each frame joined or created; a restored frame's node must exist
// or be the next new one, as assign() guarantees.
std::unique_ptr<CandidateSearch> make_nodes_search(const SearchOptions& options);

}  // namespace lsgd
