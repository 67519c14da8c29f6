// The loop decision's tests' helpers (decision_test.cc, decision_places_test.cc):
// a confirming stage of fixed support and queries to decide.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "lsgd/decision.h"
#include "lsgd/verification.h"

namespace lsgd::test {

// A confirming stage whose support (inliers) per candidate frame is given.
class FixedSupport final : public VerificationStage {
 public:
  explicit FixedSupport(std::map<std::int64_t, int> inliers) : inliers_(std::move(inliers)) {}
  const char* name() const override { return "fixed"; }
  Role role() const override { return Role::kConfirm; }
  StageCheck check(std::int64_t, const Candidate& c) override {
    ++checks;
    const auto it = inliers_.find(c.frame);
    const int n = it == inliers_.end() ? 0 : it->second;
    return {n >= 20, static_cast<double>(n), std::to_string(n) + " inliers", 0, nullptr};
  }
  int checks = 0;

 private:
  std::map<std::int64_t, int> inliers_;
};

// A query of a sequence (continuity, with the temporal stage's tolerance 2),
// a 12-cell grid, min_gap 5; appearance and single-frame scores are the
// test's to set.
inline DecisionQuery sequence_query(bool continuity) {
  DecisionQuery q;
  q.cells = 12;
  q.continuity = continuity;
  q.tolerance = 2;
  q.min_gap = 5;
  return q;
}

// Appearance as the query's candidates score it (0 for any other frame);
// `candidates` is read at each call, so a test may change it between queries.
inline std::function<double(std::int64_t)> scores_of(const std::vector<Candidate>& candidates) {
  return [&candidates](std::int64_t j) {
    for (const Candidate& c : candidates) {
      if (c.frame == j) return c.score;
    }
    return 0.0;
  };
}

inline Decision decide_one(LoopDecision& decision, FixedSupport& stage, std::int64_t frame,
                    const std::vector<Candidate>& candidates, bool young = false) {
  DecisionQuery q;
  q.frame = frame;
  q.candidates = &candidates;
  q.cells = 12;
  q.young = young;
  q.appearance = [](std::int64_t) { return std::nan(""); };
  return decision.decide(q, {&stage});
}

}  // namespace lsgd::test
