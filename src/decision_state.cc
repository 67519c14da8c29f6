// The loop decision's state per frame, persisted with the detector's
// database (the decision itself: src/decision.cc).
#include <cmath>

#include "internal/check.h"
#include "lsgd/decision.h"

namespace lsgd {

// State, version 2: the loop declared for the frame (int64, -1: none) and its
// loop's inlier average (float64), then the ranking's track after the frame
// alike (version 1 has no track: none). A frame without a record (written
// before the decision kept one) declared no loop.
void LoopDecision::save_frame(std::int64_t frame, StateWriter& out) const {
  if (frame < 0 || frame >= static_cast<std::int64_t>(history_.size())) {
    internal::throw_invalid("decision: frame ", frame, " was not decided (", history_.size(),
                            " frames)");
  }
  const Loop& h = history_[static_cast<std::size_t>(frame)];
  out.put_i64(h.frame);
  out.put_f64(h.inliers);
  out.put_i64(h.track);
  out.put_f64(h.track_inliers);
}

void LoopDecision::check_frame(std::int64_t frame, int, int, std::uint32_t version,
                               StateReader in) const {
  if (!in.present()) return;
  check_state_version(in.what(), name(), version, 2);
  for (int k = 0; k < (version >= 2 ? 2 : 1); ++k) {
    const std::int64_t loop = in.get_i64();
    const double inliers = in.get_f64();
    if (loop < -1 || loop >= frame || !std::isfinite(inliers) || inliers < 0) {
      internal::throw_invalid(in.what(), ": ", k == 0 ? "loop " : "the ranking's track ", loop,
                              " with ", inliers, " inliers is not an earlier frame or -1");
    }
  }
  in.finish();
}

void LoopDecision::restore_frame(std::int64_t frame, int, int, std::uint32_t version, StateReader in) {
  restore_renumbered(frame, 0, 0, version, in, FrameRenumbering::identity());
}

void LoopDecision::restore_renumbered(std::int64_t frame, int, int, std::uint32_t version,
                                      StateReader in, const FrameRenumbering& renumbered) {
  // As record() leaves it: a frame without a loop keeps the last one held
  // (the frames are restored in order), a loop to a forgotten frame is none.
  ContinuityState s{frame, -1, 0, state_.held}, t{frame, -1, 0, track_.held};
  const auto read = [&](ContinuityState& c, int gap) {
    const std::int64_t loop = in.get_i64();
    c.inliers = in.get_f64();
    c.loop = renumbered.after(loop);
    if (c.loop >= 0) {
      c.hold(frame, c.loop, c.inliers, gap);
    } else if (loop >= 0) {
      c.inliers = 0;  // forgotten
      c.held = {};
    }
  };
  if (in.present()) {
    read(s, options_.continuity_gap);
    if (version >= 2) read(t, 0);
  }
  state_ = s;
  track_ = t;
  history_.resize(static_cast<std::size_t>(frame), kUndecided);
  history_.push_back({s.loop, s.inliers, t.loop, t.inliers});
}

}  // namespace lsgd
