// Verification stages that run after the candidate search (beyond the paper),
// so that a reported loop can be trusted by a SLAM map. Each is switchable;
// with none enabled the detector is the faithful method.
//
// - temporal (sequence consistency): every candidate j of query i is scored
//   by the mean similarity along the diagonal, sim(i - t, j - t) for
//   t = 0 .. frames-1, after moving j within +-tolerance to the best-aligned
//   diagonal; candidates are re-ranked by that sequence score, which becomes
//   the loop's score. A loop is then accepted only when the previous `agree`
//   queries were placed on consecutive places (query i - t's best place within
//   tolerance + 1 of j - t), as iBoW-LCD's islands and Tsintotas' temporal
//   checks require.
// - geometric: ORB features matched between the query and the candidate,
//   F and H fitted with RANSAC, accepted on the inlier count (geometric.h).
#pragma once

#include <cstdint>
#include <deque>
#include <string>
#include <unordered_map>
#include <vector>

#include "lsgd/frame_store.h"
#include "lsgd/geometric.h"
#include "lsgd/search.h"

namespace lsgd {

struct TemporalOptions {
  // Sequence length: the query and the frames-1 frames before it, [1, 100].
  // 16: corridor R@100P 0.252 -> 0.414 and the synthetic street 0.292 -> 0.354
  // against 8; 32 overshoots the street's short revisits (docs/results.md).
  int frames = 16;
  // Realignment: a candidate moves within +-tolerance frames to its
  // best-aligned diagonal; also the slack of the agreement check. [0, 100].
  int tolerance = 2;
  // Previous queries that must agree on consecutive places, [0, 100] (0: no gate).
  int agree = 1;
  // Second, longer sequence, [0, 1000] frames (0: off; else > frames): the
  // score is the mean of the sequence scores over `frames` and over
  // `long_frames` frames, so a long consistent history counts while a short
  // revisit still scores on its first frames. 48: corridor R@100P 0.414 ->
  // 0.586, the synthetic street 0.354 -> 0.404, AP and R@1 equal or better
  // (docs/results.md). Costs long_frames similarities per examined frame.
  int long_frames = 48;
  void check() const;
};

struct VerificationOptions {
  // Sequence consistency: on by default (docs/results.md: it raises R@100P,
  // AP and R@1 on every sequence measured, for ~0.3 ms per frame).
  bool temporal = true;
  // ORB + RANSAC: off by default (it helps on sharp 320x240 frames, hurts on
  // small fisheye ones, and costs ~5 ms per frame); see docs/results.md.
  bool geometric = false;
  // Candidates examined best first; the first one every enabled stage accepts
  // is reported. [1, 100]; at most search.top_n are available.
  int max_candidates = 3;
  TemporalOptions temporal_options;
  GeometricOptions geometric_options;
  void check() const;
};

// "none", "temporal", "geometric" or "temporal,geometric" (either order).
// Throws InvalidArgument naming the unknown stage.
void parse_verification_stages(const std::string& text, VerificationOptions& options);
std::string verification_stages(const VerificationOptions& options);

// The verdict of one stage on one candidate.
struct StageVerdict {
  std::int64_t candidate = -1;
  std::string stage;  // "temporal" or "geometric"
  bool accepted = false;
  std::string reason;  // e.g. "3 of 3 previous queries agree" or "12 inliers < 20"
  double ms = 0;
};

// The temporal stage. Remembers the best place of the last `agree` queries.
class TemporalVerifier {
 public:
  explicit TemporalVerifier(const TemporalOptions& options = {});

  // Re-ranks `raw` (query's candidates by similarity) by sequence score and
  // writes the best top_n, best first, to `out`. Not thread-safe (scratch). `query` is the frame
  // being processed (descriptor `descriptor`, not stored yet); every earlier frame is in `store`.
  // Candidates stay outside the temporal window.
  void rescore(const FrameStore& store, const DescriptorView& descriptor, std::int64_t query,
               const std::vector<Candidate>& raw, std::int64_t min_gap, SimilarityMetric metric,
               int top_n, std::vector<Candidate>& out) const;

  struct Check {
    bool accepted = false;
    std::string reason;
  };
  // The agreement gate for a rescored candidate of query `query`.
  Check agree(std::int64_t query, const Candidate& candidate) const;

  // Remembers the query's best place (the first rescored candidate, frame -1
  // for none); call once per processed frame, after agree().
  void push(std::int64_t query, std::int64_t place);

  // Persistence (lsgd::io::Database): the last query pushed (-1: none) and
  // the best places remembered, oldest first (at most max(agree, 1)).
  std::int64_t last_query() const { return last_query_; }
  std::vector<std::int64_t> places() const { return {places_.begin(), places_.end()}; }
  // Restores that state as if push() had been called for queries
  // last_query - places.size() + 1 .. last_query. Throws InvalidArgument,
  // leaving the verifier unchanged, for more than max(agree, 1) places, places
  // < -1, or places without a query (last_query + 1 < places.size()).
  void restore(std::int64_t last_query, std::vector<std::int64_t> places);

 private:
  // Mean of sim(i - t, j - t) over t = 0..frames-1 (fewer near the start).
  double sequence_score(const FrameStore& store, const DescriptorView& descriptor,
                        std::int64_t query, std::int64_t j, SimilarityMetric metric) const;

  // sim(store[a], store[b]) for a > b, from the pair cache or computed and cached.
  double stored_similarity(const FrameStore& store, std::int64_t a, std::int64_t b,
                           SimilarityMetric metric) const;
  // Empties the pair cache unless it was filled from this store (by address,
  // with no fewer frames) with this metric.
  void check_cache(const FrameStore& store, SimilarityMetric metric) const;

  TemporalOptions options_;
  // Sequence scores computed in the current rescore() call: the windows of
  // neighbouring candidates overlap, so each frame is scored once.
  mutable std::vector<Candidate> scored_;
  // Similarities of stored pairs (a, b), key a << 32 | b, along the diagonals
  // of recent queries: the next query's diagonals are mostly the same pairs,
  // so each is computed once instead of once per query (stored frames never
  // change). Pairs no later sequence can reach (a older than the longest
  // sequence) are dropped after each rescore().
  mutable std::unordered_map<std::uint64_t, double> pairs_;
  mutable const FrameStore* pairs_store_ = nullptr;
  mutable std::int64_t pairs_store_size_ = 0;
  mutable SimilarityMetric pairs_metric_ = SimilarityMetric::kReference;
  std::deque<std::int64_t> places_;  // best place of the previous queries, newest last
  std::int64_t last_query_ = -1;
};

}  // namespace lsgd
