// Candidate search over stored frames (paper Sec. III-D/E): exhaustive, or
// through dynamic nodes (Algorithm 1) with the reference implementation's
// thresholds relative to the similarity between the query and its previous frame.
#pragma once

#include <cstdint>
#include <vector>

#include "lsgd/frame_store.h"
#include "lsgd/similarity.h"

namespace lsgd {

enum class SearchMode { kExhaustive, kDynamicNodes };

const char* to_string(SearchMode mode);
// Parses "exhaustive" or "nodes"; throws InvalidArgument otherwise.
SearchMode parse_search_mode(const char* name);

struct DynamicNodeOptions {
  // base = threshold_0 * sim(query, previous frame); in (0, 10]. Reference: 0.9.
  double threshold_0 = 0.9;
  // A node is examined when sim(query, its first frame) > alpha * base; in [0, 10].
  // Reference threshold_1 = 0.8.
  double alpha = 0.8;
  // The query joins the node when the mean similarity to its frames > beta * base;
  // in [0, 10]. Reference threshold_2 = 1.0; the paper's Table II sweeps 0.9 / 1.0 / 1.1.
  double beta = 1.0;
  void check() const;
};

struct SearchOptions {
  SearchMode mode = SearchMode::kExhaustive;
  // Temporal window w in frames, [0, 1e9]: frame j is a candidate for query i
  // only if j < i - w. Reference disc_num: 50.
  std::int64_t min_gap = 50;
  // How many best candidates to return, [1, 1000].
  int top_n = 10;
  DynamicNodeOptions nodes;
  void check() const;
};

struct Candidate {
  std::int64_t frame = -1;
  double score = 0.0;
};

// Orders candidates best first; equal scores by lower (older) frame id, so
// results are deterministic.
bool better(const Candidate& a, const Candidate& b);

// Keeps the top_n best candidates of all frames j < query - min_gap.
// `scratch` is reused between calls; the result is written best first. When
// `row` is given it receives every candidate's similarity, in frame order
// (row[j] for j < query - min_gap).
void search_exhaustive(const FrameStore& store, const DescriptorView& query, std::int64_t query_id,
                       const SearchOptions& options, SimilarityMetric metric,
                       std::vector<Candidate>& scratch, std::vector<Candidate>& out,
                       std::vector<double>* row = nullptr);

// Dynamic nodes: groups of similar earlier frames, created online.
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

  std::int64_t size() const { return static_cast<std::int64_t>(nodes_.size()); }
  // Frame ids of `node`, first frame first; InvalidArgument for a node that
  // does not exist.
  const std::vector<std::int64_t>& members(std::int64_t node) const;

  // Persistence (lsgd::io::Database): replaces the nodes by `nodes` (frame ids
  // of each node, first frame first, in creation order), as assign() would
  // have built them. Throws InvalidArgument, leaving the nodes unchanged, for
  // an empty node, a negative id or ids not increasing within a node.
  void restore(std::vector<std::vector<std::int64_t>> nodes);

 private:
  std::vector<std::vector<std::int64_t>> nodes_;  // frame ids, first frame first
};

}  // namespace lsgd
