// The loop decision (beyond the paper): evidence from every enabled stage
// adds up to one score, in standard deviations (sigma), and a reported
// candidate is a loop when that score reaches decision.threshold.
//
//   score = appearance                           (evidence.h: R with the temporal stage,
//                                                 the standardised similarity without it)
//         + geometric_bonus   when the geometric stage confirmed the candidate
//         + continuity_bonus  when, confirmed, it continues the loop declared for
//                             the previous frame: it is that loop's frame j or
//                             one of the next 1 + verification.temporal.tolerance
//                             (a revisit may be slower or faster, never backwards)
//
// A stage can also sink a candidate: one the geometric stage or the agreement
// gate rejected is never reported. With the defaults (threshold 7, bonuses
// 3.5 and 2.5) a first loop needs appearance >= 3.5 sigma and geometry, a loop
// that continues a declared one >= 1 sigma and geometry, and a loop on
// appearance alone (no geometric stage) >= 7 sigma. docs/results.md has the
// leave-one-sequence-out study behind these values.
//
// Continuity: the geometric check of a continuing candidate passes with
// `continuity_inliers` times the inliers its loop has had so far (an average
// over the loop's frames) instead of geometric.min_inliers, so a long revisit
// of a low-texture place stays tracked, while a revisit that ends (its
// inliers collapse) stops at once.
#pragma once

#include <cstdint>
#include <string>

#include "lsgd/options.h"

namespace lsgd {

// A loop on appearance alone (no geometric stage) needs a grid of at least
// this many cells: with fewer the descriptor is almost a whole-image
// histogram, whose standardised scores have heavy tails (nordland-trimmed at
// 64x32, one cell: 411 false loops on appearance alone, none true). Below it
// the candidate is still reported, its score kept just under the threshold.
constexpr int kMinAppearanceCells = 4;

struct DecisionOptions {
  // A reported candidate is a loop when its score >= threshold; sigma, (0, 1000].
  double threshold = 7.0;
  // Added to the score of a candidate the geometric stage confirmed; sigma, [0, 1000].
  double geometric_bonus = 3.5;
  // Added to the score of a confirmed candidate that continues the loop
  // declared for the previous frame; sigma, [0, 1000] (0: no continuity).
  double continuity_bonus = 2.5;
  // A continuing candidate passes the geometric check with at least this
  // fraction of its loop's average inliers; (0, 1].
  double continuity_inliers = 0.2;
  void check() const;
  static const OptionTable<DecisionOptions>& fields();  // lsgd/options.h
};

// What decided the reported candidate (Result::evidence).
struct LoopEvidence {
  double appearance = 0;   // its appearance score, sigma (NaN: none reported)
  int inliers = -1;        // geometric inliers; -1: not checked
  bool confirmed = false;  // the geometric stage accepted it
  bool continues = false;  // confirmed and continuing the previous frame's loop
};

// The state the decision carries from frame to frame: the loop declared for
// the last processed frame and its loop's average inliers.
struct ContinuityState {
  std::int64_t query = -1;  // last processed frame (-1: none)
  std::int64_t loop = -1;   // the frame declared as its loop, -1: none
  double inliers = 0;       // the loop's inlier average (exponential, weight 0.2 for each new frame)

  // True when candidate `frame` of query `query` continues the loop.
  bool continues(std::int64_t query, std::int64_t frame, int tolerance) const;
  // Records the decision for `query`: a loop to `frame` with `inliers`
  // (frame -1: no loop).
  void record(std::int64_t query, std::int64_t frame, int inliers, bool continued);
};

}  // namespace lsgd
