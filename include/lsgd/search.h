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
  // Beyond the paper, same results: skip the similarities that cannot change
  // the outcome, using triangle-inequality bounds on the distance behind the
  // score (see DynamicNodes). false scores every frame Algorithm 1 touches, as
  // the paper and the reference code do (for measuring the faithful cost).
  bool bounds = true;
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
// `scratch` is reused between calls; the result is written best first.
void search_exhaustive(const FrameStore& store, const DescriptorView& query, std::int64_t query_id,
                       const SearchOptions& options, SimilarityMetric metric,
                       std::vector<Candidate>& scratch, std::vector<Candidate>& out);

// Dynamic nodes: groups of similar earlier frames, created online.
//
// Exact pruning (options.nodes.bounds): the score is a decreasing function
// of a metric distance d (lsgd::distance), so every distance computed for one
// query also bounds later ones. DynamicNodes keeps, per stored frame, an
// interval for d(query, frame) and widens it by d(query, previous query) at
// each call (triangle inequality); it also keeps each member's distance to
// its node's first frame, which bounds d(query, member) once d(query, first)
// is known. A node is rejected when even the upper bounds of its members'
// scores cannot pass the thresholds, accepted when the lower bounds already
// do, and otherwise members are scored, widest interval first, until the
// decision is certain; of the accepting node only the members that can reach
// the top_n are scored. Decisions keep a margin far above rounding error, so
// the nodes and the candidates (frames and scores) are identical to scoring
// every member; tests check this against the unpruned search.
class DynamicNodes {
 public:
  struct Outcome {
    std::int64_t node = -1;  // node the query joined, or the one it created
    bool created = false;    // true when no node accepted the query
    std::int64_t similarities = 0;  // similarity evaluations spent
    std::int64_t skipped = 0;       // evaluations of Algorithm 1 the bounds made unnecessary
  };

  // Runs Algorithm 1 for frame `query_id` (which must be store.size(): the
  // query is assigned before it is stored, and the bounds assume the stored
  // frame equals the query; a different one is detected at the next call and
  // only costs the bounds gathered so far). Writes the best top_n candidates
  // of the accepting node that lie outside the temporal window, best first;
  // none when a new node is created.
  Outcome assign(const FrameStore& store, const DescriptorView& query, std::int64_t query_id,
                 const SearchOptions& options, SimilarityMetric metric,
                 std::vector<Candidate>& scratch, std::vector<Candidate>& out);

  std::int64_t size() const { return static_cast<std::int64_t>(nodes_.size()); }
  const std::vector<std::int64_t>& members(std::int64_t node) const { return nodes_.at(node); }

  // Persistence (lsgd::io::Database): replaces the nodes by `nodes` (frame ids
  // of each node, first frame first, in creation order), as assign() would
  // have built them, and forgets the bounds (they are rebuilt as queries
  // come). Throws InvalidArgument, leaving the nodes unchanged, for an empty
  // node, a negative id or ids not increasing within a node.
  void restore(std::vector<std::vector<std::int64_t>> nodes);

 private:
  // Interval for the distance between frame and the query of call `call`.
  struct Known {
    double lo = 0;
    double hi = 0;
    std::int64_t call = -1;  // -1: nothing known
  };
  struct Member {  // one member of the node being examined
    std::int64_t frame;
    double s_lo, s_hi;  // score bounds (equal once scored)
    double d_lo, d_hi;  // distance bounds (equal once scored)
    bool scored;
  };

  // True when the stored frame query_id - 1 is the query of the last call.
  bool follows_last_query(const FrameStore& store, std::int64_t query_id) const;
  void forget_bounds();
  // Distance interval of frame f for the current call; [0, inf) when unknown.
  void distance_bounds(std::int64_t f, double& lo, double& hi) const;
  void record(std::int64_t f, double lo, double hi);

  std::vector<std::vector<std::int64_t>> nodes_;  // frame ids, first frame first
  // Bounds state. Calls are numbered; path_[c] is the sum of
  // d(query of call k, query of call k - 1) for k = valid_from_ + 1 .. c, so
  // an interval known at call a widens by path_[c] - path_[a] by call c.
  std::vector<Known> known_;        // per frame id
  std::vector<double> to_first_;    // per frame id: d(frame, its node's first frame); < 0 unknown
  std::vector<double> path_;        // per call
  std::int64_t call_ = -1;          // current call number
  std::int64_t valid_from_ = 0;     // intervals from earlier calls are void
  std::int64_t last_query_ = -1;    // query id of the last bounded call that succeeded
  std::vector<unsigned char> last_bytes_;  // its descriptor bytes
  SimilarityMetric metric_ = SimilarityMetric::kReference;  // of every distance kept
  std::vector<Member> members_;     // scratch
  std::vector<std::size_t> order_;  // scratch
  std::vector<double> top_scores_;  // scratch
};

}  // namespace lsgd
