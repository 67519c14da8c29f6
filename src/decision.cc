#include "lsgd/decision.h"

#include <cstdlib>

#include "internal/check.h"

namespace lsgd {

void DecisionOptions::check() const {
  internal::check_range_open_low("decision.threshold", threshold, 0.0, 1000.0, "sigma");
  internal::check_range("decision.geometric_bonus", geometric_bonus, 0.0, 1000.0, "sigma");
  internal::check_range("decision.continuity_bonus", continuity_bonus, 0.0, 1000.0, "sigma");
  internal::check_range_open_low("decision.continuity_inliers", continuity_inliers, 0.0, 1.0);
}

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
