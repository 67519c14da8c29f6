#include "lsgd/decision.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "internal/check.h"
#include "internal/clock.h"
#include "lsgd/places.h"

namespace lsgd {

namespace {
constexpr const char* kStayReason =
    "a stay: every frame since it looks like the query (decision.stay_z), the camera never left";
}  // namespace

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
        real_option("continuity_min_z", &S::continuity_min_z, -1000.0, 1000.0, false, "sigma",
                    "a frame that would continue the loop continues nothing when it scores below "
                    "this for the query, single frame (a scene cut)"),
        real_option("strong_bonus", &S::strong_bonus, 0.0, 1000.0, false, "sigma",
                    "added to the best-ranked candidate, confirmed as a first loop with at least "
                    "strong_inliers inliers (0: off)"),
        integer_option("strong_inliers", &S::strong_inliers, 1, 100000, "inliers",
                       "the geometric support a confirmed candidate needs for strong_bonus"),
        real_option("track_bonus", &S::track_bonus, 0.0, 1000.0, false, "sigma",
                    "added to the best-ranked candidate, confirmed as a first loop, when it tracks "
                    "the ranking's confirmed candidate of the previous frame (0: off)"),
        integer_option("strong_track", &S::strong_track, 0, 1000, "frames",
                       "a first loop tracking the ranking's confirmed candidates this many frames in a row "
                       "gets strong_bonus as if it had strong_inliers (0: off)"),
        real_option("stay_z", &S::stay_z, 0.0, 1000.0, false, "sigma",
                    "a candidate is a stay, not a loop, when every frame between it and the query "
                    "(8 sampled) scores at least this for the query, single frame, or (a first loop) "
                    "the query's geometry matches the frames between (0: both off)"),
        real_option("leap", &S::leap, 0.0, 1000.0, false, "",
                    "no loop is continued across a frame whose place signature leapt this far (block "
                    "contrast) from the 8 frames before it: a scene cut as it happens (needs "
                    "verification.temporal.place_cut; 0: off)"),
        real_option("contradiction", &S::contradiction, 0.0, 1000.0, false, "sigma",
                    "a continuation is none when the candidate ranked first lies elsewhere (more than "
                    "16 frames from the loop's window), with at least its inliers, and the query looks "
                    "more like it by this much, single frame (0: off)"),
        integer_option("continuity_gap", &S::continuity_gap, 0, 100, "frames",
                       "a loop is continued after at most this many frames that declared none (after more "
                       "than one, by the candidate ranked first only)"),
    };
    for (OptionField<S>& f : t) f.resumable = true;  // the decision may change on resume
    return t;
  }();
  return table;
}

void DecisionOptions::check() const { check_options(fields(), *this, "decision"); }

bool ContinuityState::continues(std::int64_t q, std::int64_t frame, int tolerance, int gap) const {
  return held.loop >= 0 && held.query < q && q - held.query <= 1 + gap && frame >= held.loop &&
         frame <= window_end(q, tolerance);
}

std::int64_t ContinuityState::window_end(std::int64_t q, int tolerance) const {
  return held.loop + (q - held.query) + tolerance;
}

void ContinuityState::record(std::int64_t q, std::int64_t frame, int frame_inliers,
                             bool continued, int gap) {
  query = q;
  loop = frame;
  if (frame < 0) {
    inliers = 0;
  } else {
    const double v = frame_inliers > 0 ? frame_inliers : 0;
    inliers = continued ? 0.8 * held.inliers + 0.2 * v : v;
    hold(q, frame, inliers, gap);
  }
}

void ContinuityState::hold(std::int64_t q, std::int64_t frame, double frame_inliers, int gap) {
  const bool run = held.loop >= 0 && held.query < q && q - held.query <= 1 + gap;
  held = {q, frame, frame_inliers, run ? held.since : q};
}

namespace {

// The places a query knows (none: one place).
const std::vector<std::int64_t>& places_of(const std::vector<std::int64_t>* places) {
  static const std::vector<std::int64_t> kOne;
  return places != nullptr ? *places : kOne;
}

// The held loop's run began in the query's place: it may be continued there
// (within its frame j's place: place_end()).
bool same_place(const std::vector<std::int64_t>* places, const ContinuityState::Held& held,
                std::int64_t query) {
  return held.since >= place_start(places_of(places), query);
}

}  // namespace

LoopDecision::LoopDecision(const DecisionOptions& options) : options_(options) { options_.check(); }

namespace {
constexpr std::pair<LoopStatus, const char*> kStatusNames[] = {
    {LoopStatus::kLoop, "loop"},
    {LoopStatus::kTooFewFrames, "too_few_frames"},
    {LoopStatus::kNoCandidate, "no_candidate"},
    {LoopStatus::kGated, "gated"},
    {LoopStatus::kYoung, "young"},
    {LoopStatus::kNotConfirmed, "not_confirmed"},
    {LoopStatus::kBelowThreshold, "below_threshold"},
};
}  // namespace

const char* to_string(LoopStatus status) {
  for (const auto& [s, name] : kStatusNames) {
    if (s == status) return name;
  }
  return "unknown";
}

LoopStatus parse_loop_status(const std::string& name) {
  std::string names;
  for (const auto& [s, n] : kStatusNames) {
    if (name == n) return s;
    names += (names.empty() ? "" : ", ") + std::string(n);
  }
  internal::throw_invalid("loop status '", name, "' is not one of ", names);
}

void LoopDecision::record(std::int64_t frame, std::int64_t loop, int inliers, bool continued) {
  state_.record(frame, loop, inliers, continued, options_.continuity_gap);
  history_.resize(static_cast<std::size_t>(frame), kUndecided);
  history_.push_back({state_.loop, state_.inliers, track_.loop, track_.inliers});
}

double LoopDecision::rank(const DecisionQuery& q, const Candidate& best,
                          const std::vector<VerificationStage*>& confirms, Decision& out) {
  first_checks_.clear();
  out.ranking.best = best;
  out.ranking.confirmed = best.frame >= 0;
  bool tracking = q.continuity && best.frame >= 0 && track_.continues(q.frame, best.frame, q.tolerance, 0) &&
                  same_place(q.places, track_.held, q.frame) && !leapt(q, track_.held) &&
                  best.frame <= place_end(places_of(q.places), track_.held.loop);
  if (tracking && q.single_frame && !confirms.empty()) {
    tracking = !(q.single_frame(best.frame) < kRankingTrackMinZ);  // a scene cut; NaN: not unlike
  }
  first_tracks_ = tracking && !confirms.empty();
  double support = -1;
  for (VerificationStage* stage : confirms) {
    if (best.frame < 0) break;
    StageCheck check = stage->check(q.frame, best);
    out.verdicts.push_back({best.frame, stage->name(), check.accepted, check.reason, check.ms});
    // Tracking the ranking's candidate of the previous frame, a fraction of
    // the track's inliers is enough.
    const bool accepted = check.accepted || (tracking && check.support > 0 &&
                                             check.support >= kRankingTrackInliers * track_.inliers);
    if (check.support >= 0) support = support < 0 ? check.support : std::min(support, check.support);
    first_checks_.push_back(std::move(check));
    if (!accepted) {
      out.ranking.confirmed = false;
      break;
    }
  }
  const bool tracked = out.ranking.confirmed && !confirms.empty();
  track_.record(q.frame, tracked ? best.frame : -1, static_cast<int>(support), tracked && tracking, 0);
  return support;
}

Decision LoopDecision::decide(const DecisionQuery& q, const std::vector<VerificationStage*>& stages) {
  const std::vector<Candidate>& candidates = *q.candidates;
  Decision out;
  out.evidence.appearance = std::numeric_limits<double>::quiet_NaN();
  const std::size_t n = std::min(candidates.size(), static_cast<std::size_t>(q.max_candidates));
  confirms_.clear();
  for (VerificationStage* s : stages) {
    if (s->role() == VerificationStage::Role::kConfirm && s->examines()) confirms_.push_back(s);
  }
  // 1. The gates, in rank order.
  const std::size_t first = gate(q, stages, n, out);  // the best candidate they let through

  // 2. The ranking (no decision setting changes it): the best candidate
  // through the gates, examined by every confirming stage on every query.
  // The decision reuses these checks. The verdict on candidates[first] as its
  // stages gave it (the decision's continuity rule may change it below).
  FirstVerdict verdict;
  verdict.support = rank(q, first < n ? candidates[first] : Candidate{}, confirms_, out);
  verdict.rejected = std::any_of(first_checks_.begin(), first_checks_.end(),
                                 [](const StageCheck& c) { return !c.accepted; });

  // 3. Confirmation, continuation first when it could score higher.
  if (!confirms_.empty()) examine(q, stages, first, n, verdict, out);

  // 4. Nothing confirmed: the best candidate through the gates, unconfirmed
  // (a young query with a confirming stage reports nothing unconfirmed).
  if (out.best.frame < 0 && first < n && !(q.young && !confirms_.empty())) {
    report_unconfirmed(q, candidates[first], verdict, out);
  }
  out.loop = out.best.frame >= 0 && out.best.score >= options_.threshold;
  out.status = status(q, first, n, verdict, out);
  record(q.frame, out.loop ? out.best.frame : -1, out.evidence.inliers,
         out.loop && out.evidence.continues);
  return out;
}

std::size_t LoopDecision::gate(const DecisionQuery& q, const std::vector<VerificationStage*>& stages,
                               std::size_t n, Decision& out) {
  const std::vector<Candidate>& candidates = *q.candidates;
  gated_.assign(n, 0);  // 1: a gate rejected it
  for (VerificationStage* gate : stages) {
    if (gate->role() != VerificationStage::Role::kGate || !gate->examines()) continue;
    for (std::size_t i = 0; i < n; ++i) {
      if (gated_[i]) continue;
      const Candidate& c = candidates[i];
      const StageCheck check = gate->check(q.frame, c);
      out.verdicts.push_back({c.frame, gate->name(), check.accepted, check.reason, check.ms});
      gated_[i] = check.accepted ? 0 : 1;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (gated_[i] || !stay(q, candidates[i].frame)) continue;
    gated_[i] = 1;
    out.verdicts.push_back({candidates[i].frame, name(), false, kStayReason, 0});
  }
  std::size_t first = 0;
  while (first < n && gated_[first]) ++first;
  return first;
}

LoopDecision::Window LoopDecision::open_window(const DecisionQuery& q, const Candidate* first) {
  const DecisionOptions& d = options_;
  Window w;
  w.first = first;
  w.held = state_.held.loop;  // the loop a candidate may continue
  w.open = q.continuity && d.continuity_bonus > 0 &&
           state_.continues(q.frame, w.held, q.tolerance, d.continuity_gap) &&
           same_place(q.places, state_.held, q.frame) && !leapt(q, state_.held);
  // Frame j stays in its place.
  w.end = std::min(state_.window_end(q.frame, q.tolerance), place_end(places_of(q.places), w.held));
  // Over more than one frame without a loop, only the candidate appearance
  // ranks first continues it (a track kept by weaker candidates falls
  // behind the revisit).
  w.long_gap = w.open && q.frame - state_.held.query > 2;
  // A scene cut: a frame that would continue the loop but looks unlike the
  // query (its single-frame score below continuity_min_z: a new place, not
  // the revisit going on) continues nothing.
  unlike_.clear();  // the window's frames held .. end, 1: unlike
  if (w.open && q.single_frame) {
    for (std::int64_t j = w.held; j <= w.end; ++j) {
      const double z = j < q.frame - q.min_gap ? q.single_frame(j) : std::nan("");
      unlike_.push_back(z < d.continuity_min_z ? 1 : 0);  // NaN: not unlike
    }
  }
  return w;
}

bool LoopDecision::leapt(const DecisionQuery& q, const ContinuityState::Held& held) const {
  if (options_.leap <= 0 || !q.leap) return false;
  for (std::int64_t f = std::max<std::int64_t>(held.query + 1, 0); f <= q.frame; ++f) {
    if (q.leap(f) >= options_.leap) return true;  // NaN, -infinity: no leap known
  }
  return false;
}

bool LoopDecision::unlike(const Window& w, std::int64_t frame) const {
  const std::int64_t k = frame - w.held;
  return k >= 0 && k < static_cast<std::int64_t>(unlike_.size()) && unlike_[static_cast<std::size_t>(k)];
}

bool LoopDecision::continues(const DecisionQuery& q, const Window& w, const Candidate& c) const {
  if (w.long_gap && !(w.first != nullptr && c.frame == w.first->frame)) return false;
  return w.open && state_.continues(q.frame, c.frame, q.tolerance, options_.continuity_gap) &&
         c.frame <= w.end && !unlike(w, c.frame);
}

// The ranking's first candidate, elsewhere in the map, explains the query
// better than the continuation: as much geometric support and a clearly
// higher single-frame score. A true continuation's ranking's first is the
// same stretch a few frames off, or scores no more than about 1 sigma above it.
bool LoopDecision::contradicted(const DecisionQuery& q, const Window& w, const Candidate& c, double support,
                                double first_support, std::string& why) const {
  const double margin = options_.contradiction;
  if (margin <= 0 || w.first == nullptr || !q.single_frame || support < 0 || first_support < support) {
    return false;
  }
  const std::int64_t f = w.first->frame;
  if (f == c.frame || (f >= w.held - kElsewhereFrames && f <= w.end + kElsewhereFrames)) return false;
  // Two visits of one place: the later of the two frames declared a loop to
  // the earlier (a place passed three times: the ranking may prefer the
  // first visit while the loop follows the second).
  const std::int64_t later = std::max(f, c.frame), earlier = std::min(f, c.frame);
  for (std::int64_t k = std::max<std::int64_t>(later - 2, 0);
       k <= later + 2 && k < static_cast<std::int64_t>(history_.size()); ++k) {
    const std::int64_t loop = history_[static_cast<std::size_t>(k)].frame;
    if (loop >= 0 && std::abs(loop - earlier) <= kElsewhereFrames) return false;
  }
  const double first_z = q.single_frame(f), z = q.single_frame(c.frame);
  if (!(first_z - z >= margin)) return false;  // NaN: no contradiction
  why = internal::concat("contradicted: the candidate ranked first, frame ", f, ", lies elsewhere, has ",
                         first_support, " inliers against ", support, " and scores ", first_z - z,
                         " sigma more for the query, single frame (decision.contradiction ", margin, ")");
  return true;
}

// The best-scored frame that continues the held loop, outside the temporal
// window; frame -1 when there is none.
Candidate LoopDecision::continuation(const DecisionQuery& q, const Window& w) const {
  Candidate best;
  if (!w.open) return best;
  const std::int64_t limit = q.frame - q.min_gap;
  for (std::int64_t j = w.held; j <= std::min(limit - 1, w.end); ++j) {
    if (unlike(w, j)) continue;
    const double score = q.appearance(j);
    if (std::isnan(score)) return {};
    const Candidate c{j, score};
    if (best.frame < 0 || better(c, best)) best = c;
  }
  return best;
}

// The gates judge the continuation too: a rejected candidate is never
// reported, whichever way it came.
void LoopDecision::gate_continuation(const DecisionQuery& q, const std::vector<VerificationStage*>& stages,
                                     std::size_t n, Candidate& c, Decision& out) const {
  if (c.frame < 0) return;
  const std::vector<Candidate>& candidates = *q.candidates;
  for (std::size_t i = 0; i < n; ++i) {
    if (candidates[i].frame != c.frame) continue;
    if (gated_[i]) c = {};
    return;  // a candidate: the gates have judged it
  }
  for (VerificationStage* gate : stages) {
    if (c.frame < 0) break;
    if (gate->role() != VerificationStage::Role::kGate || !gate->examines()) continue;
    const StageCheck check = gate->check(q.frame, c);
    out.verdicts.push_back({c.frame, gate->name(), check.accepted, check.reason, check.ms});
    if (!check.accepted) c = {};
  }
  if (c.frame >= 0 && stay(q, c.frame)) {
    out.verdicts.push_back({c.frame, name(), false, kStayReason, 0});
    c = {};
  }
}

// A first loop j of query i is a stay when every confirming stage also
// accepts, for the query, the frames a half, a quarter and three quarters of
// the way from j to i. A revisit's path left the place, so the query does
// not match them; a camera that stood still, or has only begun to move away,
// does (the appearance test, stay(), cannot see a stay that fills the
// query's candidates: their statistics are the stay's own).
bool LoopDecision::sees_the_frames_between(const DecisionQuery& q, std::int64_t frame, double support,
                                           Decision& out) {
  const std::int64_t span = q.frame - frame;
  if (options_.stay_z <= 0 || confirms_.empty() || span < 4) return false;
  // The middle first (a revisit's path is furthest from the place there),
  // then the quarters: a route that passes the place again halfway is no stay.
  double ms = 0;
  std::string matched;
  for (const std::int64_t k : {frame + span / 2, frame + span / 4, frame + 3 * span / 4}) {
    for (VerificationStage* stage : confirms_) {
      const StageCheck check = stage->check(q.frame, Candidate{k, 0});
      ms += check.ms;
      // Below the stage's bar but with kStayBetweenSupport of the candidate's
      // support: the same view (a stay's noisy copies score alike, around the bar).
      if (!check.accepted && !(support > 0 && check.support >= kStayBetweenSupport * support)) return false;
    }
    matched += internal::concat(matched.empty() ? "" : ", ", k);
  }
  out.verdicts.push_back({frame, name(), false,
                          internal::concat("a stay: the query also matches frames ", matched,
                                           " between, by every confirming stage: the camera never left"),
                          ms});
  return true;
}

// The frames between candidate j and query i, the middle one first, then
// the quarters, the eighths ...: a revisit has left the place somewhere in
// between, which the first samples usually show (one similarity).
bool LoopDecision::stay(const DecisionQuery& q, std::int64_t frame) const {
  const double level = options_.stay_z;
  const std::int64_t span = q.frame - frame;
  if (level <= 0 || !q.single_frame || frame < 0 || span < 2) return false;
  int looked = 0;
  for (std::int64_t parts = 2; looked < kStaySamples; parts *= 2) {
    for (std::int64_t m = 1; m < parts && looked < kStaySamples; m += 2) {
      const std::int64_t k = frame + span * m / parts;
      if (k <= frame || k >= q.frame) continue;
      const double z = q.single_frame(k);
      if (!(z >= level)) return false;  // NaN (no statistics): no sign of a stay
      ++looked;
    }
    if (parts >= 2 * span) break;  // every frame between has been looked at
  }
  return looked > 0;
}

// The candidates the confirming stages may check: those through the gates,
// the window's frames (the continuation, or a candidate in the window when it
// scores better) examined once.
void LoopDecision::list_examined(const DecisionQuery& q, const Window& w, std::size_t n,
                                 const Candidate& continuation) {
  const std::vector<Candidate>& candidates = *q.candidates;
  examined_.clear();
  bool has_continuation = false;
  for (std::size_t i = 0; i < n; ++i) {
    if (gated_[i]) continue;
    const Candidate& c = candidates[i];
    if (continuation.frame >= 0 && continues(q, w, c)) {
      if (has_continuation) continue;  // the window is examined once
      has_continuation = true;
      examined_.push_back(better(continuation, c) ? continuation : c);
    } else {
      examined_.push_back(c);
    }
  }
  if (continuation.frame >= 0 && !has_continuation) examined_.push_back(continuation);
}

// strong_bonus is for the candidate appearance ranks first (after the gates),
// as a first loop: geometry confirms a weak ranking, and a continuation keeps
// its own bar.
double LoopDecision::strong(const DecisionQuery& q, const Window& w, const Candidate& c) const {
  return first_loop(q, w, c) ? options_.strong_bonus : 0.0;
}

// The candidate appearance ranks first, taken as a first loop (it continues none).
bool LoopDecision::first_loop(const DecisionQuery& q, const Window& w, const Candidate& c) const {
  return w.first != nullptr && c.frame == w.first->frame && !continues(q, w, c);
}

// Whether the candidate ranked first continues a track of the ranking's
// confirmed candidates strong_track frames long (this frame included), each
// within 1 + tolerance frames after the one of the frame before. The walk
// back stops where the track's run began (ContinuityState::Held::since,
// reset by cut(): a new session carries no track over).
bool LoopDecision::long_track(const DecisionQuery& q) const {
  const int needed = options_.strong_track;
  if (needed <= 0 || !first_tracks_ || q.frame < 1 || history_.size() < static_cast<std::size_t>(q.frame)) {
    return false;
  }
  const std::int64_t since = std::max<std::int64_t>(track_.held.since, 0);
  int run = 2;  // the previous frame's confirmed candidate, and this one tracking it
  for (std::int64_t f = q.frame - 2; f >= since && run < needed; --f, ++run) {
    const std::int64_t at = history_[static_cast<std::size_t>(f)].track;
    const std::int64_t next = history_[static_cast<std::size_t>(f + 1)].track;
    if (at < 0 || next < at || next > at + 1 + q.tolerance) break;
  }
  return run >= needed;
}

// The most a candidate can score once confirmed. track_bonus is for the
// first loop strong_bonus is for, when it tracks the ranking's candidate of
// the last frame (its own check must accept it: a first loop has no relaxed bar).
double LoopDecision::potential(const DecisionQuery& q, const Window& w, const Candidate& c) const {
  const DecisionOptions& d = options_;
  const double tracked = first_loop(q, w, c) && first_tracks_ ? d.track_bonus : 0.0;
  return c.score + d.geometric_bonus + strong(q, w, c) + tracked +
         (continues(q, w, c) ? d.continuity_bonus : 0.0);
}

// Every confirming stage on one candidate, in order, until one rejects it.
// A continuing candidate needs a fraction of its loop's inliers instead of
// the stage's own bar.
LoopDecision::Confirmation LoopDecision::confirm(const DecisionQuery& q, const Candidate& c,
                                                 bool continuing, bool is_first, Decision& out) {
  const DecisionOptions& d = options_;
  Confirmation result;
  for (std::size_t k = 0; k < confirms_.size(); ++k) {
    VerificationStage* stage = confirms_[k];
    // The ranking checked the best candidate already (its verdict is listed
    // again only when the continuity rule changes it).
    const bool cached = is_first && k < first_checks_.size();
    StageCheck check = cached ? first_checks_[k] : stage->check(q.frame, c);
    const bool listed = cached && !(continuing && check.support >= 0);
    if (continuing && check.support >= 0) {
      const double needed = d.continuity_inliers * state_.held.inliers;
      check.accepted = check.support > 0 && check.support >= needed;
      check.reason += internal::concat("; continues the loop of frame ", state_.held.query,
                                       ": needs ", needed, " inliers (", d.continuity_inliers,
                                       " of its average ", state_.held.inliers, ")");
      if (cached) check.ms = 0;  // counted once, by the ranking
    }
    if (!listed) out.verdicts.push_back({c.frame, stage->name(), check.accepted, check.reason, check.ms});
    if (check.geometry) result.geometry = check.geometry;
    if (check.support >= 0) {
      result.support = result.support < 0 ? check.support : std::min(result.support, check.support);
    }
    if (!check.accepted) {
      result.accepted = false;
      break;
    }
  }
  return result;
}

// Step 3: the candidates that could reach the threshold, by what they could
// score, until one confirmed reaches it.
void LoopDecision::examine(const DecisionQuery& q, const std::vector<VerificationStage*>& stages,
                           std::size_t first, std::size_t n, FirstVerdict& verdict, Decision& out) {
  const DecisionOptions& d = options_;
  const Candidate* best = first < n ? &(*q.candidates)[first] : nullptr;
  const Window w = open_window(q, best);
  Candidate next = continuation(q, w);
  gate_continuation(q, stages, n, next, out);
  list_examined(q, w, n, next);
  std::stable_sort(examined_.begin(), examined_.end(), [&](const Candidate& a, const Candidate& b) {
    return potential(q, w, a) > potential(q, w, b);
  });
  for (const Candidate& c : examined_) {
    const double score = potential(q, w, c);
    const bool is_first = best != nullptr && c.frame == best->frame;
    // Sorted: no later one can reach the threshold either. A young query's
    // best candidate is examined whatever it could score.
    if (score < d.threshold && !(q.young && is_first)) break;
    const bool continuing = continues(q, w, c);
    const Confirmation confirmed = confirm(q, c, continuing, is_first, out);
    if (is_first) verdict = {confirmed.support, !confirmed.accepted};
    if (!confirmed.accepted) continue;
    // A continuation the ranking contradicts continues nothing, and without
    // its continuity it cannot be a loop (its bar was the relaxed one).
    std::string why;
    if (continuing && contradicted(q, w, c, confirmed.support, verdict.support, why)) {
      out.verdicts.push_back({c.frame, name(), false, std::move(why), 0});
      continue;
    }
    // What it scores with its support: strong_bonus needs strong_inliers.
    const bool strong_enough = confirmed.support >= d.strong_inliers || long_track(q);
    const double scored = strong_enough ? score : score - strong(q, w, c);
    // A first loop the query's view never left is a stay (stay_z).
    if (scored >= d.threshold && !continuing && sees_the_frames_between(q, c.frame, confirmed.support, out)) {
      if (is_first) verdict.rejected = true;  // reported, if at all, as never a loop
      continue;
    }
    if (out.best.frame < 0 || scored >= d.threshold) {
      out.best = {c.frame, scored};
      out.evidence = {c.score, static_cast<int>(confirmed.support), true, continuing};
      out.geometry = confirmed.geometry;
    }
    // A confirmed candidate below the threshold is reported unless a later
    // one (a lower potential) reaches it.
    if (scored >= d.threshold) break;
  }
}

// Step 4: the best candidate through the gates, with its appearance score.
void LoopDecision::report_unconfirmed(const DecisionQuery& q, const Candidate& c,
                                      const FirstVerdict& verdict, Decision& out) const {
  double score = c.score;
  // Rejected by a confirming stage, or appearance alone on a degenerate
  // grid: never a loop.
  // A young query on appearance alone: its scores come from the prior, and
  // are never a loop either.
  const bool untrusted = confirms_.empty() && (q.cells < kMinAppearanceCells || q.young);
  if (verdict.rejected || untrusted) score = std::min(score, std::nextafter(options_.threshold, -1.0));
  out.best = {c.frame, score};
  out.evidence.appearance = c.score;
  out.evidence.inliers = static_cast<int>(verdict.support);
  for (const StageCheck& check : first_checks_) {
    if (check.geometry) out.geometry = check.geometry;
  }
}

LoopStatus LoopDecision::status(const DecisionQuery& q, std::size_t first, std::size_t n,
                                const FirstVerdict& verdict, const Decision& out) const {
  if (out.loop) return LoopStatus::kLoop;
  if (q.frame - q.min_gap <= 0) return LoopStatus::kTooFewFrames;
  if (n == 0) return LoopStatus::kNoCandidate;
  if (first == n) return LoopStatus::kGated;
  // Nothing unconfirmed is a loop while statistics are young.
  if (out.best.frame < 0 || (q.young && !out.evidence.confirmed)) return LoopStatus::kYoung;
  if (verdict.rejected && !out.evidence.confirmed) return LoopStatus::kNotConfirmed;
  return LoopStatus::kBelowThreshold;
}

}  // namespace lsgd
