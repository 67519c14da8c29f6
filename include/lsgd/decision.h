// The loop decision (beyond the paper): evidence from every enabled stage
// adds up to one score, in standard deviations (sigma), and a reported
// candidate is a loop when that score reaches decision.threshold.
//
//   score = appearance                           (evidence.h: R with the temporal stage,
//                                                 the standardised similarity without it)
//         + geometric_bonus   when the confirming stages (the geometric stage;
//                             lsgd/stage.h) confirmed the candidate
//         + strong_bonus      when it is the best-ranked candidate, confirmed as a
//                             first loop with at least strong_inliers inliers, or
//                             ending a track of strong_track such candidates, one
//                             frame after the other
//         + track_bonus       when that first loop also tracks the ranking's
//                             confirmed candidate of the previous frame
//         + continuity_bonus  when, confirmed, it continues the loop declared for
//                             the previous frame (or up to continuity_gap frames
//                             before it): it is that loop's frame j or one of the
//                             next frames since + verification.temporal.tolerance
//                             (a revisit may be slower or faster, never backwards)
//
// A stage can also sink a candidate: one a confirming stage or a gate (the
// temporal stage's agreement gate) rejected is never reported, nor is a
// stay: a candidate every frame after which, up to the query, looks like the
// query, or a first loop whose query geometry also matches the frames
// between (stay_z; the camera never left, it did not come back). With the defaults (threshold 7, bonuses
// 3.5 and 2.5) a first loop needs appearance >= 3.5 sigma and geometry, a loop
// that continues a declared one >= 1 sigma and geometry, and a loop on
// appearance alone (no geometric stage) >= 7 sigma. docs/results.md has the
// leave-one-sequence-out study behind these values.
//
// Continuity stops at a scene cut: a frame that would continue the loop but
// scores below continuity_min_z for the query, single frame, is another
// place than the query and continues nothing (a new session starts with no
// loop to continue at all: Detector::cut()). Nor does it cross a place the
// map found (DecisionQuery::places, lsgd/places.h): a loop is continued only
// while its run of loops began in the query's place and its frame j stays in
// the place it was in; past a cut a loop must be found again, as a first one.
// Nor is a loop continued where the ranking contradicts it: its first
// candidate, elsewhere in the map, explains the query clearly better
// (DecisionOptions::contradiction).
//
// Continuity: the geometric check of a continuing candidate passes with
// `continuity_inliers` times the inliers its loop has had so far (an average
// over the loop's frames) instead of geometric.min_inliers, so a long revisit
// of a low-texture place stays tracked, while a revisit that ends (its
// inliers collapse) stops at once.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "lsgd/options.h"
#include "lsgd/stage.h"

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
  // declared for the previous frame (or continuity_gap frames before); sigma,
  // [0, 1000] (0: no continuity).
  double continuity_bonus = 2.5;
  // A continuing candidate passes the geometric check with at least this
  // fraction of its loop's average inliers; (0, 1].
  double continuity_inliers = 0.2;
  // A scene cut: a frame that would continue the loop (the loop's frame j ..
  // j + 1 + tolerance) continues nothing when it scores below this for the
  // query, single frame (the query's standardised similarity to it); sigma,
  // [-1000, 1000]. True continuations score -1.3 at the lowest on every
  // sequence measured, the cut of a two-place map -2.7 (docs/results.md).
  double continuity_min_z = -2.0;
  // A loop is continued after at most this many frames that declared none
  // (frames whose geometric check failed: a blurred or occluded frame need
  // not end the revisit); over more than one such frame only the candidate
  // appearance ranks first continues it. Frames, [0, 100] (0: only the
  // previous frame's loop is continued). 3 by leave-one-sequence-out with a
  // margin: 5 and 6 carry lip6-outdoor's tracks past their revisit
  // (docs/results.md).
  int continuity_gap = 3;
  // Added to the candidate appearance ranks first when it is confirmed with
  // at least strong_inliers (its geometric support) as a first loop: a
  // weak ranking (a viewpoint change, another lens) that geometry holds
  // strongly; sigma, [0, 1000] (0: off). With the defaults a first loop
  // needs 2 sigma and 40 inliers, or 3.5 sigma and 20, or 1.75 sigma and 20
  // at the end of a track of strong_track frames (with track_bonus)
  // (docs/results.md has the leave-one-sequence-out choices).
  double strong_bonus = 1.5;
  // The support a confirmed candidate needs for strong_bonus; inliers, [1, 100000].
  int strong_inliers = 40;
  // Added to the candidate appearance ranks first when it is confirmed as a
  // first loop and tracks the ranking's confirmed candidate of the previous
  // frame (Ranking): geometry that holds two frames in a row along the
  // revisit; sigma, [0, 1000] (0: off). 0.25 by leave-one-sequence-out with
  // a margin: at 0.75 and 1 the synthetic streets and a map of three places
  // get false loops (docs/results.md).
  double track_bonus = 0.25;
  // A first loop whose candidate continues the ranking's track, geometry
  // confirmed on the candidate ranked first this many frames in a row (this
  // one included, each within 1 + tolerance frames after the one before),
  // counts as strong as strong_inliers would make it (strong_bonus): a
  // revisit at night or from another lane, weak in appearance (1.8-2.0
  // sigma) and in each frame's inliers (16-31), but held frame after frame.
  // Frames, [0, 1000] (0: off). 9: the smallest value that adds no false
  // loop on any sequence of the suite; the margin rule of
  // leave-one-sequence-out chose 8, which adds 19 on synthetic street 3
  // (docs/results.md).
  int strong_track = 9;
  // A stay, not a revisit: the camera never left the place (a train
  // standing in a station, a robot waiting, a hand-held camera held still)
  // for longer than search.min_gap. A candidate is gated (for the ranking
  // and the decision) when every frame between it and the query (up to
  // kStaySamples of them, spread evenly) scores at least this for the query,
  // single frame; and a first loop is none when the query also matches the
  // frames a half, a quarter and three quarters of the way back by every
  // confirming stage (a stay that fills the query's candidates, whose
  // statistics are then the stay's own). Sigma, [0, 1000] (0: both off).
  // 3: the frames between a true loop and its query score 1.65 at the most
  // on every sequence of the suite (a corridor after two other places),
  // those of a train standing still 5.8 and more (docs/results.md, "A
  // camera that stays is not a loop").
  double stay_z = 3.0;
  // A scene cut as it happens: no loop is continued (nor the ranking's track
  // followed) across a frame whose view leapt from the frames just before
  // it, its leap (lsgd/places.h: the block contrast of its place signature
  // against the kPlaceBlock frames before it) reaching this; the loop must
  // then be found again as a first loop. A place is found only kPlaceBlock
  // frames after it begins; a leap at once. Needs the places' signatures
  // (verification.temporal.place_cut > 0). [0, 1000] (0: off). 1.25 by
  // leave-one-sequence-out with a margin (1.0 costs corridor-shifted 6
  // loops, 2.0 leaves two maps' false loops): every frame of corridor,
  // lip6-outdoor and their variants leaps 1.41 at the most, every cut where
  // a loop was in progress 1.71 or more (docs/results.md, "A loop in
  // progress is not carried into the next place").
  double leap = 1.25;
  // A continuation the ranking contradicts is none: the candidate appearance
  // ranks first lies elsewhere in the map (more than kElsewhereFrames from
  // the loop's window), its geometric support is at least the
  // continuation's, and the query looks more like it than like the
  // continuation by this much, single frame. The revisit has left the
  // loop's track (a track that fell behind its revisit, or walks along a
  // stay's copies while the query moves on), and the relaxed bar of a
  // continuation (continuity_inliers) would carry it on. Not when the later
  // of the two frames declared a loop to the earlier (two visits of one
  // place). Sigma, [0, 1000] (0: off). Off by default: at 2 it removes
  // 7-17 false loops from a held camera, a blurred revisit and maps at
  // 64 x 32, but costs lip6-outdoor alone at 64 x 32 six of its 503 true
  // loops, whose continuations run along the ground truth band's edge with
  // the same scores (docs/results.md, "A continuation the ranking
  // contradicts"); for a map that must not take a false loop at that price.
  double contradiction = 0.0;
  void check() const;
  static const OptionTable<DecisionOptions>& fields();  // lsgd/options.h
};

// A ranking's first candidate further than this from a loop's window (its
// frames held .. end) lies elsewhere in the map (DecisionOptions::contradiction);
// nearer, it is the same stretch aligned a few frames off (a revisit's true
// continuations have their ranking's first within 9 frames on every sequence
// measured). The temporal stage's default sequence length.
constexpr std::int64_t kElsewhereFrames = 16;

// The most frames between a candidate and its query that decide whether it
// is a stay (DecisionOptions::stay_z), the middle one first.
constexpr int kStaySamples = 8;
// A frame between a first loop and its query matches the query, for the
// geometric stay test (stay_z), when every confirming stage accepts it or
// gives it at least this fraction of the candidate's support: a camera that
// has just left its stay sees the stay's noisy copies alike, some just below
// the stage's bar (corridor's frame 60 held 60 times: 22 inliers for the
// candidate, 12-15 for the frames between; docs/results.md).
constexpr double kStayBetweenSupport = 0.5;

// What decided the reported candidate (Result::evidence).
struct LoopEvidence {
  double appearance = 0;   // its appearance score, sigma (NaN: none reported)
  int inliers = -1;        // geometric inliers; -1: not checked
  bool confirmed = false;  // the geometric stage accepted it
  bool continues = false;  // confirmed and continuing the last declared loop (continuity_gap)
};

// Why a query has a loop or none (Result::status), for a program to branch
// on; the stages' verdicts (Result::verification) say it in words.
enum class LoopStatus {
  kLoop,            // a loop is declared (Result::loop)
  kTooFewFrames,    // no stored frame lies outside the temporal window yet
  kNoCandidate,     // frames outside the window, but the search returned none
                    // (statistics not calibrated yet; nodes mode: a new node)
  kGated,           // every candidate was rejected by a gate (temporal agreement)
  kYoung,           // too few candidates for statistics of its own, and no
                    // confirming stage confirmed the best (evidence.h)
  kNotConfirmed,    // the best candidate was rejected by a confirming stage
                    // (too few geometric inliers) and nothing else reached the threshold
  kBelowThreshold,  // the reported candidate scores below decision.threshold
};
// "loop", "too_few_frames", "no_candidate", "gated", "young", "not_confirmed",
// "below_threshold": the CSV's and Python's names.
const char* to_string(LoopStatus status);
// The status of that name; InvalidArgument naming the names otherwise.
LoopStatus parse_loop_status(const std::string& name);

// The state the decision carries from frame to frame: the loop declared for
// the last processed frame and its loop's average inliers, and the last loop
// declared at all (which a loop may continue over `gap` frames).
struct ContinuityState {
  std::int64_t query = -1;  // last processed frame (-1: none)
  std::int64_t loop = -1;   // the frame declared as its loop, -1: none
  double inliers = 0;       // the loop's inlier average (exponential, weight 0.2 for each new frame)
  struct Held {
    std::int64_t query = -1;  // the last frame that declared a loop (-1: none)
    std::int64_t loop = -1;   // its loop
    double inliers = 0;       // its loop's inlier average
    // The first frame of its run: the frames that declared loops with at
    // most `gap` frames between them (record()), ending at `query`.
    std::int64_t since = -1;
  } held;

  // True when candidate `frame` of query `query` continues the last loop
  // declared: it was declared at most 1 + gap frames before `query`, and
  // `frame` lies between its loop and window_end().
  bool continues(std::int64_t query, std::int64_t frame, int tolerance, int gap) const;
  // The last frame that may continue the held loop for query `query`: the
  // loop moved on by the frames since, plus `tolerance`.
  std::int64_t window_end(std::int64_t query, int tolerance) const;
  // Records the decision for `query`: a loop to `frame` with `inliers`
  // (frame -1: no loop); a loop within 1 + gap frames of the held one
  // belongs to its run (Held::since).
  void record(std::int64_t query, std::int64_t frame, int inliers, bool continued, int gap);
  // The loop held, loop `frame` with `inliers` declared for `query` (a
  // restored frame, record()'s rule for its run).
  void hold(std::int64_t query, std::int64_t frame, double inliers, int gap);
};

// One query as the decision sees it.
struct DecisionQuery {
  std::int64_t frame = 0;  // the query's id
  // Its candidates best first, scored by appearance (sigma; evidence.h).
  const std::vector<Candidate>* candidates = nullptr;
  int max_candidates = 3;   // verification.max_candidates
  std::int64_t min_gap = 0;  // search.min_gap: the continuation stays outside the window
  // Continuity needs sequence evidence (the temporal stage); its slack in
  // frames is temporal.tolerance.
  bool continuity = false;
  int tolerance = 0;
  int cells = 0;  // the descriptor grid's cells (kMinAppearanceCells)
  // The query is young (evidence.h): its candidates are scored on the prior,
  // not on statistics of its own, so only a candidate a confirming stage
  // accepts is reported (its best candidate is always examined).
  bool young = false;
  // The appearance score of frame j for this query, as the candidates are
  // scored (NaN: not available).
  std::function<double(std::int64_t)> appearance;
  // The standardised similarity (single frame) of frame j for this query
  // (NaN: not available): a continuation must not look unlike the query.
  std::function<double(std::int64_t)> single_frame;
  // The first frames of the places after the first that the map has found
  // so far, ascending (Detector::place_starts(); nullptr or empty: one
  // place). No loop is continued, and no track followed, across one.
  const std::vector<std::int64_t>* places = nullptr;
  // The leap of frame f (the query's own included) from the frames just
  // before it (lsgd/places.h; -infinity or NaN: none known; unset: none).
  std::function<double(std::int64_t)> leap;
};

// The ranking no decision setting changes (what R@100P and AP are computed
// from, docs/evaluation.md): the candidate appearance ranks first among those
// the gates let through, its appearance score, and whether every confirming
// stage accepts it. The confirming stages examine it on every query, whatever
// the decision needs. As the decision's continuity rule does, a candidate
// that tracks the ranking's confirmed candidate of the previous frame (it is
// that frame or one of the next 1 + verification.temporal.tolerance) passes
// the geometric check with kRankingTrackInliers of the track's average
// inliers, unless it looks unlike the query (single frame below
// kRankingTrackMinZ: a scene cut) or crosses a place found (the continuity
// rule's); the track is the ranking's own, whatever the decision declared.
// (The constants are the decision's defaults.)
struct Ranking {
  Candidate best;          // frame -1: no candidate (or every one gated)
  bool confirmed = false;  // every confirming stage accepts it (true without one)
};
constexpr double kRankingTrackInliers = 0.2;
constexpr double kRankingTrackMinZ = -2.0;

// What the decision found for one query (fields of Result).
struct Decision {
  bool loop = false;
  LoopStatus status = LoopStatus::kTooFewFrames;
  Candidate best;
  LoopEvidence evidence;
  Ranking ranking;
  std::shared_ptr<const LoopGeometry> geometry;  // of `best`, when a stage fitted one
  std::vector<StageVerdict> verdicts;  // in the order examined
};

// The loop decision over the verification stages (the comment at the top of
// this file): the gates examine the best candidates in rank order, the
// confirming stages the candidates that could reach the threshold, the
// continuation of the previous frame's loop first when it could score
// higher. The first candidate every confirming stage accepts is reported;
// when none is, the best candidate the gates let through is reported with its
// appearance score (below the threshold if a confirming stage rejected it).
// Its state (persistence, state.h, under "decision"): the loop declared for
// every frame and its loop's inliers.
class LoopDecision final : public Stateful {
 public:
  explicit LoopDecision(const DecisionOptions& options);

  // Decides query q.frame (the frame after the last one decided) with
  // `stages` (every stage's check(); begin() has run), and records the
  // decision. The stages' end() is the caller's.
  Decision decide(const DecisionQuery& q, const std::vector<VerificationStage*>& stages);

  // The state after the last frame decided.
  const ContinuityState& continuity() const { return state_; }
  // The ranking's track after the last frame (its confirmed candidate, -1: none).
  const ContinuityState& ranking_track() const { return track_; }
  // What decide() changes, to put back after a query that is not stored
  // (Detector::query()): restore() undoes every decide() since checkpoint().
  struct Checkpoint {
    ContinuityState state, track;
    std::size_t decided = 0;
  };
  Checkpoint checkpoint() const { return {state_, track_, history_.size()}; }
  void restore(const Checkpoint& c) { state_ = c.state, track_ = c.track, history_.resize(c.decided); }

  // The next frame continues no loop, and tracks no ranked candidate (Detector::cut()).
  void cut() { state_ = {state_.query, -1, 0, {}}, track_ = {track_.query, -1, 0, {}}; }

  const char* name() const override { return "decision"; }
  bool has_state() const override { return true; }
  std::uint32_t state_version() const override { return 2; }
  void save_frame(std::int64_t frame, StateWriter& out) const override;
  void check_frame(std::int64_t frame, int width, int height, std::uint32_t version,
                   StateReader in) const override;
  void restore_frame(std::int64_t frame, int width, int height, std::uint32_t version,
                     StateReader in) override;
  // A loop or track to a forgotten frame is none.
  bool forgets() const override { return true; }
  void restore_renumbered(std::int64_t frame, int width, int height, std::uint32_t version,
                          StateReader in, const FrameRenumbering& renumbered) override;

 private:
  void record(std::int64_t frame, std::int64_t loop, int inliers, bool continued);
  // The ranking's candidate and its verdicts (step 2 of decide()); returns
  // its support as its stages gave it (the smallest; -1: none).
  double rank(const DecisionQuery& q, const Candidate& best, const std::vector<VerificationStage*>& confirms,
            Decision& out);

  // The steps of decide(), in its order (decision.cc).
  // The held loop as this query sees it: whether a candidate may continue it.
  struct Window {
    bool open = false;      // a candidate may continue the held loop
    bool long_gap = false;  // more than one frame since it: only the first-ranked one may
    std::int64_t held = -1, end = -1;  // its frames: held .. end
    const Candidate* first = nullptr;  // the best candidate through the gates
  };
  // The best candidate's verdicts (the ranking's, or the decision's own check).
  struct FirstVerdict {
    double support = -1;
    bool rejected = false;
  };
  // A candidate through every confirming stage, or not.
  struct Confirmation {
    bool accepted = true;
    double support = -1;
    std::shared_ptr<const LoopGeometry> geometry;
  };
  std::size_t gate(const DecisionQuery& q, const std::vector<VerificationStage*>& stages,
                   std::size_t n, Decision& out);
  Window open_window(const DecisionQuery& q, const Candidate* first);
  // Whether a frame after the held loop's last query, up to the query,
  // leapt from the frames before it (DecisionOptions::leap): it continues nothing.
  bool leapt(const DecisionQuery& q, const ContinuityState::Held& held) const;
  bool unlike(const Window& w, std::int64_t frame) const;
  // Whether candidate `frame` is a stay (stay_z): every sampled frame
  // between it and the query scores at least stay_z, single frame.
  bool stay(const DecisionQuery& q, std::int64_t frame) const;
  // Whether first loop `frame` (confirmed with `support`) is a stay by
  // geometry: every confirming stage also accepts the frames a half, a
  // quarter and three quarters of the way back, or gives them
  // kStayBetweenSupport of `support` (a verdict says so).
  bool sees_the_frames_between(const DecisionQuery& q, std::int64_t frame, double support, Decision& out);
  bool continues(const DecisionQuery& q, const Window& w, const Candidate& c) const;
  // Whether continuation `c`, confirmed with `support`, is contradicted by
  // the ranking's first candidate, which its stages gave `first_support`
  // (DecisionOptions::contradiction); the reason goes into `why`.
  bool contradicted(const DecisionQuery& q, const Window& w, const Candidate& c, double support,
                    double first_support, std::string& why) const;
  Candidate continuation(const DecisionQuery& q, const Window& w) const;
  void gate_continuation(const DecisionQuery& q, const std::vector<VerificationStage*>& stages,
                         std::size_t n, Candidate& c, Decision& out) const;
  void list_examined(const DecisionQuery& q, const Window& w, std::size_t n, const Candidate& continuation);
  double potential(const DecisionQuery& q, const Window& w, const Candidate& c) const;
  double strong(const DecisionQuery& q, const Window& w, const Candidate& c) const;
  bool first_loop(const DecisionQuery& q, const Window& w, const Candidate& c) const;
  bool long_track(const DecisionQuery& q) const;
  Confirmation confirm(const DecisionQuery& q, const Candidate& c, bool continuing, bool is_first,
                       Decision& out);
  void examine(const DecisionQuery& q, const std::vector<VerificationStage*>& stages, std::size_t first,
               std::size_t n, FirstVerdict& verdict, Decision& out);
  void report_unconfirmed(const DecisionQuery& q, const Candidate& c, const FirstVerdict& verdict,
                          Decision& out) const;
  LoopStatus status(const DecisionQuery& q, std::size_t first, std::size_t n, const FirstVerdict& verdict,
                    const Decision& out) const;

  DecisionOptions options_;
  ContinuityState state_;
  ContinuityState track_;  // the ranking's track: its confirmed candidate of the last frame
  struct Loop {
    std::int64_t frame;
    double inliers;
    std::int64_t track;
    double track_inliers;
  };
  static constexpr Loop kUndecided{-1, 0, -1, 0};  // a frame decide() never saw: no loop
  std::vector<Loop> history_;  // state_ and track_ after every frame
  // Scratch reused across frames.
  std::vector<char> gated_;          // 1 for a candidate a gate rejected
  std::vector<char> unlike_;         // 1 for a frame of the continuation window unlike the query
  std::vector<Candidate> examined_;  // candidates the confirming stages check, in order
  std::vector<VerificationStage*> confirms_;  // the confirming stages of this frame
  std::vector<StageCheck> first_checks_;      // their verdicts on the best candidate (ranking)
  bool first_tracks_ = false;  // the best candidate tracks the ranking's track (rank())
};

}  // namespace lsgd
