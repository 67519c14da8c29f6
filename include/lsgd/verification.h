// Verification stages that run after the candidate search (beyond the paper),
// so that a reported loop can be trusted by a SLAM map. Each is switchable;
// with none enabled the detector is the faithful method (its ranking; the
// loop decision is decision.h's).
//
// - temporal (sequence consistency): every candidate is scored by its
//   sequence evidence, the mean standardised similarity along the diagonal
//   over `frames` and `long_frames` frames, standardised against every other
//   place the query could be (evidence.h); candidates are the best distinct
//   places by that score (exhaustive search) or the search's candidates moved
//   within +-tolerance frames to their best diagonal (dynamic nodes).
//   Optionally (agree > 0) a candidate is accepted only when the previous
//   `agree` queries were placed on consecutive places (query i - t's best
//   place within tolerance + 1 of j - t).
// - geometric: ORB features matched between the query and the candidate,
//   F and H fitted with RANSAC, accepted on the inlier count (geometric.h);
//   its verdict adds to the loop's score or removes the candidate (decision.h).
#pragma once

#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "lsgd/geometric.h"
#include "lsgd/search.h"

namespace lsgd {

struct TemporalOptions {
  // Sequence length: the query and the frames-1 frames before it, [1, 100]
  // (docs/results.md has the sweeps behind 16 and 48).
  int frames = 16;
  // Realignment: a candidate moves within +-tolerance frames to its
  // best-aligned diagonal; also the slack of the agreement check. [0, 100].
  int tolerance = 2;
  // Previous queries that must agree on consecutive places, [0, 100] (0: no
  // gate). Off by default: the decision's continuity (decision.h) rewards
  // agreement instead of requiring it (docs/results.md).
  int agree = 0;
  // Second, longer sequence, [0, 1000] frames (0: off; else > frames): the
  // score is the mean of the sequence scores over `frames` and over
  // `long_frames` frames, so a long consistent history counts while a short
  // revisit still scores on its first frames. Memory: long_frames rows of 4
  // bytes per stored frame (exhaustive search).
  int long_frames = 48;
  void check() const;
  static const OptionTable<TemporalOptions>& fields();  // lsgd/options.h
};

struct VerificationOptions {
  // Sequence evidence: on by default (docs/results.md: it raises R@1 and the
  // loops declared on every sequence measured).
  bool temporal = true;
  // ORB + RANSAC: on by default. Appearance alone cannot separate a revisit
  // from a look-alike place on every camera; geometry can (docs/results.md).
  // Costs ORB on every frame (~1.5-5 ms at the default working size) and a
  // check (~0.5 ms) for each candidate that could become a loop.
  bool geometric = true;
  // Candidates examined best first; the first one that no enabled stage
  // rejects is reported. [1, 100]; at most search.top_n are available.
  int max_candidates = 3;
  TemporalOptions temporal_options;
  GeometricOptions geometric_options;
  void check() const;
  static const OptionTable<VerificationOptions>& fields();  // lsgd/options.h
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

// The temporal stage's agreement gate (agree > 0). Remembers the best place
// of the last `agree` queries. The sequence scores are AppearanceEvidence's.
class TemporalVerifier {
 public:
  explicit TemporalVerifier(const TemporalOptions& options = {});

  struct Check {
    bool accepted = false;
    std::string reason;
  };
  // The agreement gate for a candidate of query `query`.
  Check agree(std::int64_t query, const Candidate& candidate) const;

  // Remembers the query's best place (its first candidate, frame -1 for
  // none); call once per processed frame, after agree().
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
  TemporalOptions options_;
  std::deque<std::int64_t> places_;  // best place of the previous queries, newest last
  std::int64_t last_query_ = -1;
};

}  // namespace lsgd
