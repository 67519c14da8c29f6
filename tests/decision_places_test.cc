// Tests of the loop decision alone (include/lsgd/decision.h) where the camera
// stays or the map changes place: a candidate the camera never left is a stay,
// and no loop is continued into another place or across a leap of the place
// signature. The other rules: decision_test.cc.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "decision_test_support.h"
#include "lsgd/decision.h"
#include "lsgd/verification.h"

namespace lsgd {
namespace {

using test::decide_one;
using test::FixedSupport;
using test::sequence_query;

// decision.stay_z: a candidate every frame after which looks like the query
// (a camera that never left) is gated, for the ranking and the decision.
// Frame 60's candidate 10 (5 sigma, 60 inliers: 5 + 3.5 + 1.5) is a loop
// unless the frames between score stay_z (3) or more. Variants: 0 every
// frame between at 4 (a stay), 1 the middle frame at 0 (the camera left), 2
// stay_z 0 (off), 3 every frame at 2.9, 4 no statistics (NaN), 5 the frame
// one past the first quarter low (the samples find it), 6 a continuation
// that is a stay (frame 61 would continue 60's loop to 11).
TEST(LoopDecision, ACandidateTheCameraNeverLeftIsAStayNotALoop) {
  for (const int variant : {0, 1, 2, 3, 4, 5, 6}) {
    SCOPED_TRACE(testing::Message() << "variant " << variant);
    DecisionOptions d;
    if (variant == 2) d.stay_z = 0;
    LoopDecision decision(d);
    FixedSupport stage(std::map<std::int64_t, int>{{10, 60}, {11, 60}});
    DecisionQuery q = sequence_query(true);
    q.appearance = [](std::int64_t j) { return j == 11 ? 5.0 : 0.0; };
    bool stay_now = variant == 0 || variant == 2;  // variant 6: from frame 61 on
    std::int64_t looked = 0;
    q.single_frame = [&](std::int64_t j) {
      ++looked;
      if (variant == 4) return std::nan("");
      if (variant == 1 && j == 35) return 0.0;
      if (variant == 5 && j == 22) return -1.0;
      if (variant == 3) return 2.9;
      if (variant == 5) return 4.0;
      return stay_now ? 4.0 : 0.0;
    };
    std::vector<Candidate> first = {{10, 5.0}};
    q.frame = 60;
    q.candidates = &first;
    const Decision out = decision.decide(q, {&stage});
    const bool stay = variant == 0;
    EXPECT_EQ(out.loop, !stay);
    EXPECT_EQ(out.ranking.best.frame, stay ? -1 : 10);
    const bool gated = std::any_of(out.verdicts.begin(), out.verdicts.end(), [](const StageVerdict& v) {
      return v.stage == "decision" && !v.accepted && v.reason.find("stay") != std::string::npos;
    });
    EXPECT_EQ(gated, stay);
    // At most kStaySamples frames are looked at; the camera that left shows it at the first.
    if (variant == 0) {
      EXPECT_LE(looked, kStaySamples);
    }
    if (variant == 1) {
      EXPECT_EQ(looked, 1);
    }
    if (variant != 6) continue;
    stay_now = true;
    std::vector<Candidate> second = {{11, 5.0}};
    q.frame = 61;
    q.candidates = &second;
    const Decision next = decision.decide(q, {&stage});
    EXPECT_FALSE(next.loop);
    EXPECT_EQ(next.ranking.best.frame, -1);
  }
}

// A stay the appearance test cannot see (every candidate is of the stay, so
// the query's statistics are the stay's own): a first loop whose query also
// matches the frames halfway and a quarter and three quarters back, by every
// confirming stage, is a stay. Frame 60's candidate 10 (60 inliers); the
// frames between, 35, 22 and 47, match with 25. Variants: 0 all three match
// (a stay), 1 the three-quarter frame does not (a route that passes the
// place again halfway: a loop), 2 stay_z 0 (off), 3 a continuation (frame 61
// continues 60's loop to 11: not a first loop, kept), 4 a stay whose
// appearance alone (7.5 sigma) reaches the threshold: still no loop. 5: the
// candidate has 22 inliers and the frames between 12, below the stage's bar
// (20) but above kStayBetweenSupport of the candidate's (the camera just
// left its stay: noisy copies of one view): a stay; 6: 10, below both: a loop.
TEST(LoopDecision, AFirstLoopWhoseQueryMatchesTheFramesBetweenIsAStay) {
  for (const int variant : {0, 1, 2, 3, 4, 5, 6}) {
    SCOPED_TRACE(testing::Message() << "variant " << variant);
    DecisionOptions d;
    if (variant == 2) d.stay_z = 0;
    LoopDecision decision(d);
    const int between = variant == 5 ? 12 : variant == 6 ? 10 : 25;
    std::map<std::int64_t, int> inliers{{10, variant >= 5 ? 22 : 60}, {11, 60}, {35, between}, {22, between}};
    if (variant != 1) inliers[47] = between;
    FixedSupport stage(inliers);
    DecisionQuery q = sequence_query(true);
    const double appearance = variant == 4 ? 7.5 : 5.0;
    q.appearance = [&](std::int64_t) { return appearance; };
    q.single_frame = [](std::int64_t) { return 0.0; };
    std::vector<Candidate> first = {{10, appearance}};
    q.frame = 60;
    q.candidates = &first;
    if (variant == 3) {
      stage = FixedSupport(std::map<std::int64_t, int>{{10, 60}, {11, 60}});
      ASSERT_TRUE(decision.decide(q, {&stage}).loop);
      stage = FixedSupport(std::map<std::int64_t, int>{{11, 60}, {36, 25}, {23, 25}, {48, 25}});
      std::vector<Candidate> second = {{11, 5.0}};
      q.frame = 61;
      q.candidates = &second;
      q.appearance = [](std::int64_t j) { return j == 11 ? 5.0 : 0.0; };  // the window's best
      const Decision next = decision.decide(q, {&stage});
      EXPECT_TRUE(next.loop);
      EXPECT_TRUE(next.evidence.continues);
      continue;
    }
    const Decision out = decision.decide(q, {&stage});
    const bool stay = variant == 0 || variant == 4 || variant == 5;
    EXPECT_EQ(out.loop, !stay);
    EXPECT_EQ(out.ranking.best.frame, 10);  // the ranking is appearance's: not gated
    const bool said = std::any_of(out.verdicts.begin(), out.verdicts.end(), [](const StageVerdict& v) {
      return v.stage == "decision" && v.reason.find("a stay: the query also matches frames 35, 22, 47") != std::string::npos;
    });
    EXPECT_EQ(said, stay);
    if (stay) {
      EXPECT_EQ(out.status, LoopStatus::kNotConfirmed);
    }
  }
}

// A place the map found (DecisionQuery::places) ends a loop: frame 51 would
// continue the run of loops that began at frame 49 (49 -> 9, 50 -> 10), but
// not once a place is found to begin at 50 or 51 (the query's side: found
// late, as the detector finds them) or at 11 (frame j's side). A place that
// began before the run, or one elsewhere, changes nothing; the run survives
// a restore frame by frame.
TEST(LoopDecision, NoLoopIsContinuedIntoAnotherPlace) {
  struct Variant {
    std::vector<std::int64_t> places;
    bool restored, continues;
  };
  for (const Variant& v : {Variant{{}, false, true}, Variant{{50}, false, false},
                           Variant{{51}, false, false}, Variant{{11}, false, false},
                           Variant{{49}, false, true}, Variant{{20}, false, true},
                           Variant{{50}, true, false}, Variant{{20, 49}, true, true}}) {
    SCOPED_TRACE(testing::Message() << "places " << testing::PrintToString(v.places)
                                    << (v.restored ? " restored" : ""));
    DecisionOptions d;
    auto decision = std::make_unique<LoopDecision>(d);
    FixedSupport stage(std::map<std::int64_t, int>{{9, 60}, {10, 13}, {11, 13}});
    DecisionQuery q = sequence_query(true);
    std::vector<Candidate> candidates;
    q.appearance = [&](std::int64_t j) { return j == candidates[0].frame ? candidates[0].score : 0.0; };
    q.single_frame = [](std::int64_t) { return 0.0; };
    q.candidates = &candidates;
    // Frame 49: a first loop (4 + 3.5); frame 50 continues it (1.5 + 3.5 +
    // 2.5 with 13 inliers, 0.2 of 60 needed), as frame 51 would.
    candidates = {{9, 4.0}};
    q.frame = 49;
    ASSERT_TRUE(decision->decide(q, {&stage}).loop);
    candidates = {{10, 1.5}};
    q.frame = 50;
    ASSERT_TRUE(decision->decide(q, {&stage}).evidence.continues);
    EXPECT_EQ(decision->continuity().held.since, 49);
    if (v.restored) {  // a new process restores the frames' states in order
      auto restored = std::make_unique<LoopDecision>(d);
      for (std::int64_t f = 0; f <= 50; ++f) {
        StateWriter out;
        decision->save_frame(f, out);
        restored->restore_frame(f, 64, 48, 2, StateReader(out.bytes().data(), out.bytes().size(), "t"));
      }
      EXPECT_EQ(restored->continuity().held.since, 49);
      decision = std::move(restored);
    }
    candidates = {{11, 1.5}};
    q.frame = 51;
    q.places = &v.places;
    const Decision out = decision->decide(q, {&stage});
    EXPECT_EQ(out.loop, v.continues);
    EXPECT_EQ(out.evidence.continues, v.continues);
  }
}

// A frame whose view leapt from the frames before it (DecisionQuery::leap
// reaching decision.leap: a scene cut as it happens, before any place is
// found) continues no loop and no track of the ranking: frame 51 would
// continue the run 49 -> 9, 50 -> 10 (and the ranking's track, whose
// relaxed bar confirms 11 with 13 inliers), but not when it leaps itself or
// a frame after the last loop did (frame 51 after 50 declared none, here by
// a gap: 52 after 50). A leap below decision.leap, unknown (NaN), one before
// the run, or decision.leap 0 changes nothing.
TEST(LoopDecision, NoLoopIsContinuedAcrossALeap) {
  struct Variant {
    std::int64_t at;   // the frame that leaps
    double value;      // its leap
    double option;     // decision.leap
    bool skip_51;      // frame 51 declares nothing (no candidate); the query is 52
    bool continues;
  };
  const double nan = std::nan("");
  for (const Variant& v : {Variant{-1, 0, 1.5, false, true}, Variant{51, 5.0, 1.5, false, false},
                           Variant{51, 1.5, 1.5, false, false}, Variant{51, 1.4, 1.5, false, true},
                           Variant{51, nan, 1.5, false, true}, Variant{51, 5.0, 0.0, false, true},
                           Variant{49, 5.0, 1.5, false, true}, Variant{51, 5.0, 1.5, true, false},
                           Variant{52, 5.0, 1.5, true, false}, Variant{-1, 0, 1.5, true, true}}) {
    SCOPED_TRACE(testing::Message() << "leap " << v.value << " at " << v.at << ", decision.leap " << v.option
                                    << (v.skip_51 ? ", frame 51 without a loop" : ""));
    DecisionOptions d;
    d.leap = v.option;
    LoopDecision decision(d);
    FixedSupport stage(std::map<std::int64_t, int>{{9, 60}, {10, 13}, {11, 13}, {12, 13}});
    DecisionQuery q = sequence_query(true);
    std::vector<Candidate> candidates;
    q.appearance = [&](std::int64_t j) {
      return !candidates.empty() && j == candidates[0].frame ? candidates[0].score : 0.0;
    };
    q.single_frame = [](std::int64_t) { return 0.0; };
    q.candidates = &candidates;
    q.leap = [&](std::int64_t f) { return f == v.at && f <= q.frame ? v.value : 0.0; };
    candidates = {{9, 4.0}};
    q.frame = 49;
    ASSERT_TRUE(decision.decide(q, {&stage}).loop);
    candidates = {{10, 1.5}};
    q.frame = 50;
    ASSERT_TRUE(decision.decide(q, {&stage}).evidence.continues);
    if (v.skip_51) {
      candidates.clear();
      q.frame = 51;
      ASSERT_FALSE(decision.decide(q, {&stage}).loop);
    }
    q.frame = v.skip_51 ? 52 : 51;
    candidates = {{q.frame - 40, 1.5}};
    const Decision out = decision.decide(q, {&stage});
    EXPECT_EQ(out.loop, v.continues);
    EXPECT_EQ(out.evidence.continues, v.continues);
    if (!v.skip_51) {
      EXPECT_EQ(out.ranking.confirmed, v.continues) << "the ranking's track";
    }
  }
}

}  // namespace
}  // namespace lsgd
