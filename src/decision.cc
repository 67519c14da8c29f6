#include "lsgd/decision.h"

#include <cstdlib>

#include "internal/check.h"

namespace lsgd {

const OptionTable<DecisionOptions>& DecisionOptions::fields() {
  using S = DecisionOptions;
  static const OptionTable<S> table = [] {
    OptionTable<S> t = {
        real_option("threshold", &S::threshold, 0.0, 1000.0, true, "sigma",
                    "a reported candidate is a loop when its loop score reaches this"),
        real_option("geometric_bonus", &S::geometric_bonus, 0.0, 1000.0, false, "sigma",
                    "added to the score of a candidate the geometric stage confirmed"),
        real_option("continuity_bonus", &S::continuity_bonus, 0.0, 1000.0, false, "sigma",
                    "added to a confirmed candidate that continues the previous frame's loop "
                    "(0: no continuity)"),
        real_option("continuity_inliers", &S::continuity_inliers, 0.0, 1.0, true, "",
                    "a continuing candidate needs this fraction of its loop's average inliers"),
    };
    for (OptionField<S>& f : t) f.resumable = true;  // the decision may change on resume
    return t;
  }();
  return table;
}

void DecisionOptions::check() const { check_options(fields(), *this, "decision"); }

bool ContinuityState::continues(std::int64_t q, std::int64_t frame, int tolerance) const {
  return loop >= 0 && query == q - 1 && frame >= loop && frame <= loop + 1 + tolerance;
}

void ContinuityState::record(std::int64_t q, std::int64_t frame, int frame_inliers,
                             bool continued) {
  query = q;
  loop = frame;
  if (frame < 0) {
    inliers = 0;
  } else {
    const double v = frame_inliers > 0 ? frame_inliers : 0;
    inliers = continued ? 0.8 * inliers + 0.2 * v : v;
  }
}

}  // namespace lsgd
