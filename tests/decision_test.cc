// Tests of the loop decision alone (include/lsgd/decision.h): its options,
// confirmation by fixed support, the first loop's bars, continuity over gaps,
// the ranking's track, and its state (ContinuityState, restore). Stays,
// places and leaps: decision_places_test.cc. Through the Detector:
// verification_test.cc.
#include "lsgd/decision.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/verification.h"
#include "decision_test_support.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::decide_one;
using test::FixedSupport;
using test::sequence_query;

TEST(DecisionOptions, RangesNameTheField) {
  DecisionOptions d;
  d.threshold = 0;
  EXPECT_NE(test::message_of<InvalidArgument>([&] { d.check(); }).find("decision.threshold"),
            std::string::npos);
  d = {};
  d.geometric_bonus = -1;
  EXPECT_NE(test::message_of<InvalidArgument>([&] { d.check(); }).find("decision.geometric_bonus"),
            std::string::npos);
  d = {};
  d.continuity_bonus = std::nan("");
  EXPECT_THROW(d.check(), InvalidArgument);
  d = {};
  d.leap = -0.5;
  EXPECT_NE(test::message_of<InvalidArgument>([&] { d.check(); }).find("decision.leap"), std::string::npos);
  d.leap = std::nan("");
  EXPECT_THROW(d.check(), InvalidArgument);
  d = {};
  d.contradiction = -1;
  EXPECT_NE(test::message_of<InvalidArgument>([&] { d.check(); }).find("decision.contradiction"),
            std::string::npos);
  d = {};
  d.continuity_inliers = 0;
  EXPECT_THROW(d.check(), InvalidArgument);
  d.continuity_inliers = 1.5;
  EXPECT_THROW(d.check(), InvalidArgument);
  EXPECT_NO_THROW(DecisionOptions{}.check());
}

// decision.strong_bonus: the candidate appearance ranks first, confirmed with
// at least strong_inliers, is a first loop with that much less appearance;
// fewer inliers, or a candidate ranked below it, earn no strong bonus. Off
// (0), the decision is the one before it.
TEST(LoopDecision, StrongGeometryConfirmsAWeakFirstRank) {
  DecisionOptions d;
  d.strong_bonus = 2.0;
  d.strong_inliers = 40;
  const std::vector<Candidate> weak = {{5, 2.0}, {9, 1.8}};
  {
    LoopDecision decision(d);
    FixedSupport stage(std::map<std::int64_t, int>{{5, 45}, {9, 90}});
    const Decision out = decide_one(decision, stage, 100, weak);
    EXPECT_TRUE(out.loop);  // 2.0 + 3.5 + 2.0
    EXPECT_EQ(out.best.frame, 5);
    EXPECT_DOUBLE_EQ(out.best.score, 7.5);
    EXPECT_EQ(out.evidence.inliers, 45);
  }
  {
    // Confirmed, but with fewer than strong_inliers: reported, no loop, and
    // the second candidate (no strong bonus below the first rank) neither.
    LoopDecision decision(d);
    FixedSupport stage(std::map<std::int64_t, int>{{5, 39}, {9, 90}});
    const Decision out = decide_one(decision, stage, 100, weak);
    EXPECT_FALSE(out.loop);
    EXPECT_EQ(out.best.frame, 5);
    EXPECT_DOUBLE_EQ(out.best.score, 5.5);
    EXPECT_TRUE(out.evidence.confirmed);
    EXPECT_EQ(stage.checks, 1);  // 1.8 + 3.5 cannot reach 7
  }
  {
    // Off: a candidate that cannot reach 7 is not confirmed by the decision
    // (the ranking examines it: confirmed there, and its inliers reported).
    DecisionOptions off;
    off.strong_bonus = 0;
    LoopDecision decision(off);
    FixedSupport stage(std::map<std::int64_t, int>{{5, 200}});
    const Decision out = decide_one(decision, stage, 100, weak);
    EXPECT_FALSE(out.loop);
    EXPECT_EQ(stage.checks, 1);
    EXPECT_FALSE(out.evidence.confirmed);
    EXPECT_EQ(out.evidence.inliers, 200);
    EXPECT_DOUBLE_EQ(out.best.score, 2.0);
    EXPECT_EQ(out.ranking.best.frame, 5);
    EXPECT_TRUE(out.ranking.confirmed);
  }
}

// A young query (scored on the prior) has its best candidate examined
// whatever it could score, and reports a candidate only when confirmed.
TEST(LoopDecision, AYoungQueryReportsOnlyWhatIsConfirmed) {
  const std::vector<Candidate> candidates = {{3, 1.0}, {7, 0.5}};
  {
    LoopDecision decision(DecisionOptions{});
    FixedSupport stage(std::map<std::int64_t, int>{{3, 10}});
    const Decision out = decide_one(decision, stage, 30, candidates, true);
    EXPECT_EQ(stage.checks, 1);
    EXPECT_EQ(out.best.frame, -1);
    EXPECT_FALSE(out.loop);
    ASSERT_EQ(out.verdicts.size(), 1u);
    EXPECT_FALSE(out.verdicts[0].accepted);
  }
  {
    LoopDecision decision(DecisionOptions{});
    FixedSupport stage(std::map<std::int64_t, int>{{3, 30}});
    const Decision out = decide_one(decision, stage, 30, candidates, true);
    EXPECT_EQ(out.best.frame, 3);
    EXPECT_DOUBLE_EQ(out.best.score, 4.5);  // confirmed, below the threshold
    EXPECT_FALSE(out.loop);
  }
  {
    // Not young: the best candidate is reported with its appearance score
    // (the ranking's check confirms it, but 1 + 3.5 + 1.5 cannot reach 7).
    LoopDecision decision(DecisionOptions{});
    FixedSupport stage(std::map<std::int64_t, int>{{3, 30}});
    const Decision out = decide_one(decision, stage, 30, candidates, false);
    EXPECT_EQ(stage.checks, 1);
    EXPECT_EQ(out.best.frame, 3);
    EXPECT_DOUBLE_EQ(out.best.score, 1.0);
    EXPECT_FALSE(out.loop);
    EXPECT_TRUE(out.ranking.confirmed);
  }
}

// A scene cut: the frame that would continue the previous frame's loop, but
// looks unlike the query (single frame below continuity_min_z), gets neither
// the continuity bonus nor its relaxed inliers; one that looks like it does.
// Detector::cut() (LoopDecision::cut()) ends the loop outright.
TEST(LoopDecision, NothingContinuesAcrossACut) {
  for (const double z : {-2.7, -1.3}) {
    for (const bool cut : {false, true}) {
      SCOPED_TRACE(testing::Message() << "z " << z << (cut ? " cut" : ""));
      LoopDecision decision(DecisionOptions{});
      FixedSupport stage(std::map<std::int64_t, int>{{10, 60}, {11, 8}});
      DecisionQuery q = sequence_query(true);
      q.appearance = [](std::int64_t j) { return j == 11 ? 1.5 : 0.0; };
      q.single_frame = [&](std::int64_t j) { return j == 11 ? z : 0.0; };
      // Frame 50: a first loop to 10 (appearance 4 + 3.5).
      std::vector<Candidate> first = {{10, 4.0}};
      q.frame = 50;
      q.candidates = &first;
      ASSERT_TRUE(decision.decide(q, {&stage}).loop);
      if (cut) decision.cut();
      // Frame 51: frame 11 would continue it, 1.5 sigma and 13 inliers: a
      // continuation needs 0.2 of the loop's 60 (12), a first loop 20.
      FixedSupport next(std::map<std::int64_t, int>{{11, 13}});
      std::vector<Candidate> second = {{11, 1.5}};
      q.frame = 51;
      q.candidates = &second;
      const Decision out = decision.decide(q, {&next});
      const bool continues = z > -2.0 && !cut;
      EXPECT_EQ(out.loop, continues);  // 1.5 + 3.5 + 2.5 with 13 of the 12 inliers needed
      EXPECT_EQ(out.evidence.continues, continues);
    }
  }
}

// decision.continuity_gap: a loop is continued over a frame that declared
// none (frame 51: its candidate has no geometric support), not over more
// than the gap; over two frames or more only by the candidate ranked first;
// the held loop survives a restore frame by frame, and a cut() ends it.
TEST(LoopDecision, ContinuesOverAGapOfFrames) {
  // 0: continued, 1: gap 0, 2: two frames without a loop, gap 1, 3:
  // restored, 4: cut, 5: two frames, gap 3, 6: two frames, gap 3, another
  // candidate ranked first
  for (const int variant : {0, 1, 2, 3, 4, 5, 6}) {
    SCOPED_TRACE(testing::Message() << "variant " << variant);
    DecisionOptions d;
    d.continuity_gap = variant == 1 ? 0 : variant >= 5 ? 3 : 1;
    auto decision = std::make_unique<LoopDecision>(d);
    FixedSupport stage(std::map<std::int64_t, int>{{10, 60}, {11, 0}, {12, 0}, {13, 13}});
    DecisionQuery q = sequence_query(true);
    std::vector<Candidate> candidates = {{10, 4.0}};  // a first loop: 4 + 3.5 + 1.5
    // Only the query's own candidate looks like it (the rest of the window
    // cannot reach the threshold: 0 + 3.5 + 2.5).
    q.appearance = test::scores_of(candidates);
    q.single_frame = [](std::int64_t) { return 0.0; };
    q.frame = 50;
    q.candidates = &candidates;
    ASSERT_TRUE(decision->decide(q, {&stage}).loop);
    std::int64_t frame = 51;
    const bool two = variant == 2 || variant >= 5;
    for (const std::int64_t j : two ? std::vector<std::int64_t>{11, 12} : std::vector<std::int64_t>{11}) {
      candidates = {{j, 2.0}};
      q.frame = frame++;
      EXPECT_FALSE(decision->decide(q, {&stage}).loop) << "no support for " << j;
    }
    if (variant == 3) {  // a new process restores the frames' states in order
      auto restored = std::make_unique<LoopDecision>(d);
      for (std::int64_t f = 0; f < frame; ++f) {
        StateWriter out;
        decision->save_frame(f, out);
        restored->restore_frame(f, 64, 48, 2, StateReader(out.bytes().data(), out.bytes().size(), "t"));
      }
      EXPECT_EQ(restored->continuity().loop, -1);
      EXPECT_EQ(restored->continuity().held.loop, 10);
      EXPECT_DOUBLE_EQ(restored->continuity().held.inliers, 60);
      decision = std::move(restored);
    }
    if (variant == 4) decision->cut();
    // Frame 13: 2 + 3.5 + 2.5 with 13 inliers, 0.2 of the loop's 60 (12)
    // needed for a continuation, 20 for a first loop.
    candidates = {{13, 2.0}};
    if (variant == 6) candidates = {{40, 2.5}, {13, 2.0}};  // 40: no support
    q.frame = frame;
    const Decision out = decision->decide(q, {&stage});
    const bool continues = variant == 0 || variant == 3 || variant == 5;
    EXPECT_EQ(out.loop, continues);
    EXPECT_EQ(out.evidence.continues, continues);
    if (continues) {
      EXPECT_EQ(decision->continuity().held.query, frame);
    }
  }
}

// decision.contradiction: a continuation confirmed on its relaxed bar is none
// when the candidate appearance ranks first lies elsewhere in the map, has at
// least its support and scores `contradiction` sigma more for the query,
// single frame; nearer, with less support, a smaller margin, no single-frame
// score, or the option off, the loop continues.
TEST(LoopDecision, AContinuationTheRankingContradictsIsNone) {
  // 0: contradicted, 1: contradiction 0 (off, the default), 2: the first with fewer
  // inliers, 3: a margin of 1.5 only, 4: the first within 16 frames of the
  // window, 5: no single-frame score for the first, 6: a 1.5 margin with
  // contradiction 1.5
  for (const int variant : {0, 1, 2, 3, 4, 5, 6}) {
    SCOPED_TRACE(testing::Message() << "variant " << variant);
    DecisionOptions d;
    d.contradiction = variant == 1 ? 0.0 : variant == 6 ? 1.5 : 2.0;  // off by default
    LoopDecision decision(d);
    const std::int64_t first = variant == 4 ? 29 : 80;  // the window is 10 .. 13
    FixedSupport stage(std::map<std::int64_t, int>{{10, 60}, {11, 13}, {first, variant == 2 ? 12 : 13}});
    DecisionQuery q = sequence_query(true);
    std::vector<Candidate> candidates = {{10, 4.0}};  // a first loop: 4 + 3.5 + 1.5
    q.appearance = test::scores_of(candidates);
    const double margin = variant == 3 || variant == 6 ? 1.5 : 2.5;
    q.single_frame = [&](std::int64_t j) {
      if (j == first) return variant == 5 ? std::nan("") : 0.5 + margin;
      return j == 11 ? 0.5 : 0.0;
    };
    q.frame = 50;
    q.candidates = &candidates;
    ASSERT_TRUE(decision.decide(q, {&stage}).loop);
    // Frame 51: 11 continues the loop (13 inliers, 0.2 of 60 needed: 2 +
    // 3.5 + 2.5); the ranking's first is `first`, 13 inliers, no first loop.
    candidates = {{first, 2.5}, {11, 2.0}};
    q.frame = 51;
    const Decision out = decision.decide(q, {&stage});
    const bool contradicted = variant == 0 || variant == 6;
    EXPECT_EQ(out.loop, !contradicted);
    if (!contradicted) {
      EXPECT_EQ(out.best.frame, 11);
      EXPECT_TRUE(out.evidence.continues);
    }
    const bool said = std::any_of(out.verdicts.begin(), out.verdicts.end(), [](const StageVerdict& v) {
      return v.reason.find("contradicted") != std::string::npos;
    });
    EXPECT_EQ(said, contradicted);
  }
}

// A place passed three times: the ranking's first is the first visit (40),
// the loop follows the second (100, 101). The continuation is not
// contradicted when the later of the two frames declared a loop to the
// earlier (frame 100 to 40); without that loop it is.
TEST(LoopDecision, TwoVisitsOfOnePlaceDoNotContradictEachOther) {
  for (const bool linked : {true, false}) {
    SCOPED_TRACE(testing::Message() << "linked " << linked);
    DecisionOptions d;
    d.contradiction = 2.0;
    LoopDecision decision(d);
    FixedSupport stage(std::map<std::int64_t, int>{{40, 13}, {41, 60}, {100, 60}, {101, 13}});
    DecisionQuery q = sequence_query(true);
    std::vector<Candidate> candidates;
    q.appearance = test::scores_of(candidates);
    q.single_frame = [](std::int64_t j) { return j == 40 ? 3.0 : 0.5; };
    q.candidates = &candidates;
    // Frame 100 closes a loop to the first visit (41 with `linked`, 13
    // frames from 40's window of one; else 1, too far to link them).
    candidates = {{linked ? 41 : 1, 4.0}};
    q.frame = 100;
    FixedSupport first_visit(std::map<std::int64_t, int>{{41, 60}, {1, 60}});
    ASSERT_TRUE(decision.decide(q, {&first_visit}).loop);
    candidates = {{100, 4.0}};
    q.frame = 150;
    ASSERT_TRUE(decision.decide(q, {&stage}).loop);
    candidates = {{40, 2.5}, {101, 2.0}};  // 40: elsewhere, 13 inliers, 2.5 sigma more
    q.frame = 151;
    const Decision out = decision.decide(q, {&stage});
    EXPECT_EQ(out.loop, linked);
    if (linked) {
      EXPECT_EQ(out.best.frame, 101);
      EXPECT_TRUE(out.evidence.continues);
    }
  }
}

// decision.track_bonus: a first loop whose candidate tracks the ranking's
// confirmed candidate of the previous frame needs track_bonus sigma less.
TEST(LoopDecision, TheRankingsTrackLowersAFirstLoopsBar) {
  // 0: tracked, 1: frame 50's candidate not confirmed, 2: no temporal stage,
  // 3: track_bonus 0, 4: frame 51's own check fails
  for (const int variant : {0, 1, 2, 3, 4}) {
    SCOPED_TRACE(testing::Message() << "variant " << variant);
    DecisionOptions d;
    if (variant == 3) d.track_bonus = 0;
    LoopDecision decision(d);
    FixedSupport stage(std::map<std::int64_t, int>{{10, variant == 1 ? 5 : 25}, {11, variant == 4 ? 15 : 25}});
    DecisionQuery q = sequence_query(variant != 2);
    q.appearance = [](std::int64_t) { return 0.0; };
    q.single_frame = [](std::int64_t) { return 0.0; };
    // Frame 50: 3 + 3.5 < 7, confirmed: the ranking's track.
    std::vector<Candidate> candidates = {{10, 3.0}};
    q.frame = 50;
    q.candidates = &candidates;
    EXPECT_FALSE(decision.decide(q, {&stage}).loop);
    EXPECT_EQ(decision.ranking_track().loop, variant == 1 ? -1 : 10);
    // Frame 51: 3.3 + 3.5 + 0.25 (tracked) reaches 7, 3.3 + 3.5 does not.
    candidates = {{11, 3.3}};
    q.frame = 51;
    const Decision out = decision.decide(q, {&stage});
    EXPECT_EQ(out.loop, variant == 0);
    if (variant == 0) {
      EXPECT_DOUBLE_EQ(out.best.score, 3.3 + 3.5 + 0.25);
    }
  }
}

// decision.strong_track: geometry that holds on the candidate ranked first
// frame after frame along the revisit is as strong as strong_inliers in one
// frame. 2 sigma with 25 inliers scores 2 + 3.5 + 0.25 (tracked) = 5.75
// below 7; the fourth frame of a track of 4 adds strong_bonus (7.25).
// Variants: 0 a track of 4, 1 strong_track 0 (off), 2 the track broken at
// frame 52 (its candidate elsewhere), 3 frame 51's candidate not confirmed,
// 4 a cut() before frame 52 (a new session: the track before it does not count).
TEST(LoopDecision, ALongTrackOfConfirmedCandidatesIsStrongGeometry) {
  for (const int variant : {0, 1, 2, 3, 4}) {
    SCOPED_TRACE(testing::Message() << "variant " << variant);
    DecisionOptions d;
    d.strong_track = variant == 1 ? 0 : 4;
    LoopDecision decision(d);
    FixedSupport stage(std::map<std::int64_t, int>{
        {10, 25}, {11, variant == 3 ? 0 : 25}, {12, 25}, {13, 25}, {30, 25}, {31, 25}});
    DecisionQuery q = sequence_query(true);
    q.appearance = [](std::int64_t) { return 0.0; };
    q.single_frame = [](std::int64_t) { return 0.0; };
    for (std::int64_t k = 0; k < 4; ++k) {
      const std::int64_t j = variant == 2 && k >= 2 ? 28 + k : 10 + k;
      std::vector<Candidate> candidates = {{j, 2.0}};
      q.frame = 50 + k;
      q.candidates = &candidates;
      if (variant == 4 && k == 2) decision.cut();
      const Decision out = decision.decide(q, {&stage});
      EXPECT_EQ(out.loop, variant == 0 && k == 3) << "frame " << q.frame;
      if (out.loop) {
        EXPECT_EQ(out.best.frame, 13);
        EXPECT_DOUBLE_EQ(out.best.score, 2.0 + 3.5 + 1.5 + 0.25);
      }
    }
  }
}

// The ranking (decision.h): the best candidate, checked on every query; one
// that tracks the ranking's confirmed candidate of the previous frame passes
// with kRankingTrackInliers of the track's inliers, unless it looks unlike
// the query. No decision setting changes it: with a threshold nothing
// reaches, it is the same.
TEST(LoopDecision, TheRankingTracksItsOwnConfirmedCandidates) {
  for (const double threshold : {7.0, 1000.0}) {
    // 0: tracked, 1: no temporal stage, 2: cut, 3: frame 11 unlike the query
    // (a scene cut), 4: a place found to begin at 51 (the query's side), 5:
    // at 11 (frame j's side), 6: at 40 (the track began in the query's place)
    for (const int variant : {0, 1, 2, 3, 4, 5, 6}) {
      SCOPED_TRACE(testing::Message() << "threshold " << threshold << " variant " << variant);
      DecisionOptions d;
      d.threshold = threshold;
      LoopDecision decision(d);
      FixedSupport stage(std::map<std::int64_t, int>{{10, 60}, {11, 13}});
      DecisionQuery q = sequence_query(variant != 1);
      q.appearance = [](std::int64_t) { return 0.5; };
      q.single_frame = [&](std::int64_t j) { return variant == 3 && j == 11 ? -2.7 : 0.0; };
      std::vector<Candidate> first = {{10, 0.5}};  // weak: never a loop
      q.frame = 50;
      q.candidates = &first;
      const Decision a = decision.decide(q, {&stage});
      EXPECT_FALSE(a.loop);
      EXPECT_EQ(a.ranking.best.frame, 10);
      EXPECT_TRUE(a.ranking.confirmed);
      EXPECT_EQ(decision.ranking_track().loop, 10);
      if (variant == 2) decision.cut();
      std::vector<Candidate> second = {{11, 0.4}};
      q.frame = 51;
      q.candidates = &second;
      const std::vector<std::int64_t> places =
          variant == 4 ? std::vector<std::int64_t>{51}
                       : variant == 5 ? std::vector<std::int64_t>{11}
                                      : variant == 6 ? std::vector<std::int64_t>{40} : std::vector<std::int64_t>{};
      q.places = &places;
      const Decision b = decision.decide(q, {&stage});
      EXPECT_FALSE(b.loop);
      // 13 inliers: below geometric.min_inliers (20), above 0.2 of 60.
      EXPECT_EQ(b.ranking.confirmed, variant == 0 || variant == 6);
      ASSERT_FALSE(b.verdicts.empty());
      EXPECT_FALSE(b.verdicts[0].accepted);  // the stage's own verdict, as it is
      // The track is persisted with the decision's state (version 2).
      StateWriter out;
      decision.save_frame(51, out);
      LoopDecision restored(d);
      restored.restore_frame(51, 64, 48, 2, StateReader(out.bytes().data(), out.bytes().size(), "t"));
      EXPECT_EQ(restored.ranking_track().loop, decision.ranking_track().loop);
      EXPECT_DOUBLE_EQ(restored.ranking_track().inliers, decision.ranking_track().inliers);
    }
  }
}

// A decision state of version 1 (before the ranking's track) restores with no track.
TEST(LoopDecision, RestoresAVersion1StateWithoutATrack) {
  StateWriter v1;
  v1.put_i64(3);
  v1.put_f64(42);
  LoopDecision d(DecisionOptions{});
  d.check_frame(9, 64, 48, 1, StateReader(v1.bytes().data(), v1.bytes().size(), "t"));
  d.restore_frame(9, 64, 48, 1, StateReader(v1.bytes().data(), v1.bytes().size(), "t"));
  EXPECT_EQ(d.continuity().loop, 3);
  EXPECT_EQ(d.ranking_track().loop, -1);
  StateWriter bad;  // version 2, a track that is no earlier frame
  bad.put_i64(3);
  bad.put_f64(42);
  bad.put_i64(9);
  bad.put_f64(1);
  const StateReader in(bad.bytes().data(), bad.bytes().size(), "frame 9's decision state");
  EXPECT_THROW(d.check_frame(9, 64, 48, 2, in), InvalidArgument);
}

// A revisit may be slower (the same frame again) or faster (up to tolerance
// frames skipped), never backwards, and only right after the declared loop.
TEST(ContinuityState, ContinuesForwardFromTheLastLoop) {
  ContinuityState s;
  EXPECT_FALSE(s.continues(0, 0, 2, 0));
  s.record(10, 40, 30, false, 0);
  EXPECT_EQ(s.inliers, 30);
  EXPECT_EQ(s.held.since, 10);
  for (std::int64_t f = 40; f <= 43; ++f) EXPECT_TRUE(s.continues(11, f, 2, 0)) << f;
  EXPECT_FALSE(s.continues(11, 39, 2, 0));  // backwards
  EXPECT_FALSE(s.continues(11, 44, 2, 0));
  EXPECT_FALSE(s.continues(12, 41, 2, 0));  // not the next frame
  s.record(11, 41, 10, true, 0);            // continued: the average moves by 0.2
  EXPECT_DOUBLE_EQ(s.inliers, 0.8 * 30 + 0.2 * 10);
  EXPECT_EQ(s.held.since, 10);
  s.record(12, 90, 50, false, 0);  // a new loop starts its own average
  EXPECT_DOUBLE_EQ(s.inliers, 50);
  EXPECT_EQ(s.held.since, 10);  // in the same run of loops
  s.record(13, -1, -1, false, 0);
  EXPECT_FALSE(s.continues(14, 91, 2, 0));
  EXPECT_EQ(s.inliers, 0);
  EXPECT_EQ(s.loop, -1);
}

// With a gap, the last loop declared is continued over frames that declared
// none: its window moves on by the frames since, and the average is the
// held loop's.
TEST(ContinuityState, ContinuesOverAGapOfFramesWithoutLoop) {
  ContinuityState s;
  s.record(10, 40, 30, false, 0);
  s.record(11, -1, -1, false, 0);
  s.record(12, -1, -1, false, 0);
  EXPECT_EQ(s.loop, -1);  // the last frame declared none
  EXPECT_EQ(s.held.query, 10);
  EXPECT_EQ(s.window_end(13, 2), 45);
  for (std::int64_t f = 40; f <= 45; ++f) EXPECT_TRUE(s.continues(13, f, 2, 2)) << f;
  EXPECT_FALSE(s.continues(13, 46, 2, 2));
  EXPECT_FALSE(s.continues(13, 39, 2, 2));
  EXPECT_FALSE(s.continues(13, 42, 2, 1));  // two frames without a loop: gap 1 is too short
  EXPECT_FALSE(s.continues(14, 42, 2, 2));  // three
  s.record(13, 43, 10, true, 2);
  EXPECT_DOUBLE_EQ(s.inliers, 0.8 * 30 + 0.2 * 10);
  EXPECT_EQ(s.held.query, 13);
  EXPECT_EQ(s.held.since, 10);  // its run: two frames without a loop, gap 2
  EXPECT_TRUE(s.continues(14, 44, 2, 0));
  s.record(17, 50, 10, false, 2);  // three frames without: a run of its own
  EXPECT_EQ(s.held.since, 17);
}

}  // namespace
}  // namespace lsgd
