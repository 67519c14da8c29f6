// The temporal stage (verification.stages "temporal"): sequence consistency.
// Its sequence scores are appearance evidence (evidence.h), which the stage
// switches on; as a stage it is the agreement gate (temporal.agree > 0): a
// candidate is accepted only when the previous `agree` queries were placed on
// consecutive places. Its state: the best place of every query.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "lsgd/stage.h"

namespace lsgd {

// The temporal stage's agreement gate (agree > 0). Remembers the best place
// of the last `agree` queries. The sequence scores are AppearanceEvidence's.
class TemporalVerifier {
 public:
  explicit TemporalVerifier(const TemporalOptions& options = {});
  const TemporalOptions& options() const { return options_; }

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

std::unique_ptr<VerificationStage> make_temporal_stage(const VerificationOptions& options);

}  // namespace lsgd
