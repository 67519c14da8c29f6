// Tests of the verification stages' options, the agreement gate
// (include/lsgd/verification.h), the loop decision (include/lsgd/decision.h)
// and their integration in the Detector. The sequence scores are
// evidence_test.cc's.
#include "lsgd/verification.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "synthetic/synthetic.h"
#include "test_util.h"

namespace lsgd {
namespace {

TEST(VerificationStages, ParseAndPrint) {
  VerificationOptions o;
  for (const char* text : {"none", "temporal", "geometric", "temporal,geometric"}) {
    parse_verification_stages(text, o);
    EXPECT_EQ(verification_stages(o), text);
  }
  parse_verification_stages("geometric,temporal", o);
  EXPECT_TRUE(o.temporal && o.geometric);
  EXPECT_THROW(parse_verification_stages("temporal,sift", o), InvalidArgument);
  EXPECT_THROW(parse_verification_stages("", o), InvalidArgument);
  EXPECT_NE(
      test::message_of<InvalidArgument>([&] { parse_verification_stages("gps", o); }).find("gps"),
      std::string::npos);
}

TEST(VerificationOptions, RangesNameTheField) {
  VerificationOptions o;
  o.max_candidates = 0;
  EXPECT_NE(test::message_of<InvalidArgument>([&] { o.check(); }).find("max_candidates"),
            std::string::npos);
  o = {};
  o.temporal_options.frames = 0;
  EXPECT_NE(test::message_of<InvalidArgument>([&] { o.check(); }).find("temporal.frames"),
            std::string::npos);
  o = {};
  o.temporal_options.tolerance = -1;
  EXPECT_THROW(o.check(), InvalidArgument);
  o = {};
  o.temporal_options.agree = 101;
  EXPECT_THROW(o.check(), InvalidArgument);
  o = {};
  o.temporal_options.long_frames = -1;
  EXPECT_NE(test::message_of<InvalidArgument>([&] { o.check(); }).find("temporal.long_frames"),
            std::string::npos);
  o = {};
  o.temporal_options.long_frames = 1001;
  EXPECT_THROW(o.check(), InvalidArgument);
  o = {};
  o.temporal_options.long_frames = o.temporal_options.frames;  // must be longer
  EXPECT_NE(
      test::message_of<InvalidArgument>([&] {
        o.check();
      }).find("long_frames = 16 must be 0 (off) or more than verification.temporal.frames = 16"),
      std::string::npos);
  o.temporal_options.long_frames = 0;  // off
  EXPECT_NO_THROW(o.check());
  o.temporal_options.long_frames = 17;
  EXPECT_NO_THROW(o.check());
  DetectorOptions d;
  d.verification.max_candidates = 0;
  EXPECT_THROW(Detector{d}, InvalidArgument);
}

TEST(TemporalAgree, ConsecutivePlacesAreAcceptedOthersRejected) {
  TemporalOptions options;
  options.agree = 2;
  options.tolerance = 0;  // slack 1
  TemporalVerifier v(options);
  EXPECT_FALSE(v.agree(0, {5, 1.0}).accepted);  // no history yet
  v.push(0, 3);
  v.push(1, 4);
  EXPECT_TRUE(v.agree(2, {5, 1.0}).accepted);  // 4 = 5-1, 3 = 5-2
  EXPECT_TRUE(v.agree(2, {6, 1.0}).accepted);  // within slack 1
  const auto rejected = v.agree(2, {20, 1.0});
  EXPECT_FALSE(rejected.accepted);
  EXPECT_NE(rejected.reason.find("placed at 4"), std::string::npos) << rejected.reason;
  v.push(5, 9);  // a gap in queries forgets the history
  EXPECT_FALSE(v.agree(6, {10, 1.0}).accepted);
  v.push(6, -1);  // a query without a place breaks the chain
  EXPECT_FALSE(v.agree(7, {11, 1.0}).accepted);
}

TEST(TemporalAgree, ZeroAgreeAcceptsEverything) {
  TemporalOptions options;
  options.agree = 0;
  const TemporalVerifier v(options);
  EXPECT_TRUE(v.agree(0, {3, 0.5}).accepted);
}

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
  d.continuity_inliers = 0;
  EXPECT_THROW(d.check(), InvalidArgument);
  d.continuity_inliers = 1.5;
  EXPECT_THROW(d.check(), InvalidArgument);
  EXPECT_NO_THROW(DecisionOptions{}.check());
}

// A revisit may be slower (the same frame again) or faster (up to tolerance
// frames skipped), never backwards, and only right after the declared loop.
TEST(ContinuityState, ContinuesForwardFromTheLastLoop) {
  ContinuityState s;
  EXPECT_FALSE(s.continues(0, 0, 2));
  s.record(10, 40, 30, false);
  EXPECT_EQ(s.inliers, 30);
  for (std::int64_t f = 40; f <= 43; ++f) EXPECT_TRUE(s.continues(11, f, 2)) << f;
  EXPECT_FALSE(s.continues(11, 39, 2));  // backwards
  EXPECT_FALSE(s.continues(11, 44, 2));
  EXPECT_FALSE(s.continues(12, 41, 2));  // not the next frame
  s.record(11, 41, 10, true);            // continued: the average moves by 0.2
  EXPECT_DOUBLE_EQ(s.inliers, 0.8 * 30 + 0.2 * 10);
  s.record(12, 90, 50, false);  // a new loop starts its own average
  EXPECT_DOUBLE_EQ(s.inliers, 50);
  s.record(13, -1, -1, false);
  EXPECT_FALSE(s.continues(14, 91, 2));
  EXPECT_EQ(s.inliers, 0);
}

// A route through 30 places, then the same places again. Place p is noise over
// its own 8 random gray levels, so unrelated places share almost no histogram
// bin; frame i of the route is place i % 30 shifted by i / 30 pixels, so a
// revisit is a slightly moved view (geometry fits it) rather than a copy.
cv::Mat place(int p, int shift = 0) {
  std::uint64_t state = 7000 + p;
  std::uint8_t levels[8];
  for (auto& l : levels) l = static_cast<std::uint8_t>(test::splitmix64(state));
  const GrayImage g = test::random_image(160, 120, 1000 + p);
  cv::Mat m(120, 160, CV_8UC1);
  for (int y = 0; y < 120; ++y) {
    for (int x = 0; x < 160; ++x) {
      const int sx = std::min(159, x + shift);
      m.data[y * 160 + x] = levels[g.pixels[static_cast<std::size_t>(y * 160 + sx)] % 8];
    }
  }
  return m;
}

constexpr int kPlaces = 60;

std::vector<Result> run(const DetectorOptions& options, int laps = 2) {
  Detector detector(options);
  std::vector<Result> results;
  for (int i = 0; i < laps * kPlaces; ++i) {
    results.push_back(detector.process(place(i % kPlaces, i / kPlaces)));
  }
  return results;
}

DetectorOptions route_options(const char* stages) {
  DetectorOptions options;
  options.search.min_gap = 10;
  options.verification.temporal_options.frames = 4;
  options.verification.temporal_options.long_frames = 8;
  parse_verification_stages(stages, options.verification);
  return options;
}

TEST(DetectorVerification, NoneReportsTheBestCandidate) {
  const auto a = run(route_options("none"));
  for (const Result& r : a) {
    EXPECT_TRUE(r.verification.empty());
    if (!r.candidates.empty()) {
      EXPECT_EQ(r.best.frame, r.candidates.front().frame);
      EXPECT_EQ(r.best.score, r.candidates.front().score);  // the standardised similarity
    }
  }
}

TEST(DetectorVerification, DefaultsFindTheRevisitAndExplainThemselves) {
  const auto results = run(route_options("temporal,geometric"));
  int loops = 0, continued = 0;
  for (const Result& r : results) {
    if (r.frame < kPlaces) {
      EXPECT_FALSE(r.loop) << r.frame;  // nothing before the revisit
      continue;
    }
    if (!r.loop) continue;
    ++loops;
    EXPECT_EQ(r.best.frame, r.frame - kPlaces) << "frame " << r.frame;
    EXPECT_TRUE(r.evidence.confirmed);
    EXPECT_GE(r.evidence.inliers, 1);
    const double bonus = 3.5 + (r.evidence.continues ? 2.5 : 0.0);
    EXPECT_DOUBLE_EQ(r.best.score, r.evidence.appearance + bonus);
    continued += r.evidence.continues;
    ASSERT_FALSE(r.verification.empty());
    EXPECT_EQ(r.verification.back().stage, "geometric");
    EXPECT_TRUE(r.verification.back().accepted) << r.verification.back().reason;
  }
  EXPECT_GE(loops, kPlaces - 15);
  EXPECT_GT(continued, 0);
}

// The geometric stage can sink a candidate: with a zero bonus and a low
// threshold a candidate the check rejects still never becomes a loop.
TEST(DetectorVerification, GeometryRejectsWhatAppearanceAlonePasses) {
  DetectorOptions options = route_options("temporal,geometric");
  options.decision.threshold = 0.5;
  options.decision.geometric_bonus = 0;
  options.verification.geometric_options.min_inliers = 10000;  // nothing passes
  options.decision.continuity_bonus = 0;
  int unconfirmed = 0;
  for (const Result& r : run(options)) {
    EXPECT_FALSE(r.loop) << r.frame;
    if (r.best.frame >= 0 && r.evidence.inliers >= 0) {
      ++unconfirmed;
      EXPECT_LT(r.best.score, options.decision.threshold);  // rejected: below the threshold
    }
  }
  EXPECT_GT(unconfirmed, 0);
  // Without the geometric stage the same appearance declares loops.
  options = route_options("temporal");
  options.decision.threshold = 3.0;
  int loops = 0;
  for (const Result& r : run(options)) loops += r.loop;
  EXPECT_GT(loops, 0);
}

// Adding the geometric stage never changes what an unconfirmed frame reports:
// its report is the temporal stage's own (the ranking behind R@100P), so the
// combination can only add confirmed loops on top of it.
TEST(DetectorVerification, GeometryOnlyAddsToTheTemporalRanking) {
  const auto temporal = run(route_options("temporal"));
  const auto both = run(route_options("temporal,geometric"));
  ASSERT_EQ(temporal.size(), both.size());
  int confirmed = 0;
  for (std::size_t i = 0; i < both.size(); ++i) {
    if (both[i].evidence.confirmed) {
      ++confirmed;
      EXPECT_GE(both[i].best.score, temporal[i].best.score);
      continue;
    }
    EXPECT_EQ(both[i].best.frame, temporal[i].best.frame) << i;
    if (both[i].evidence.inliers < 0) {
      EXPECT_EQ(both[i].best.score, temporal[i].best.score) << i;
    }
    EXPECT_LE(both[i].best.score, temporal[i].best.score) << i;
    EXPECT_EQ(both[i].candidates.size(), temporal[i].candidates.size());
  }
  EXPECT_GT(confirmed, 0);
}

// Appearance alone on a grid of fewer than kMinAppearanceCells cells (a
// whole-image histogram) never declares a loop; the same frames with a finer
// grid do.
TEST(DetectorVerification, AppearanceAloneNeedsAGridOfFourCells) {
  for (const int sp : {80, 20}) {  // 160x120: 1x1 and 4x5 cells
    SCOPED_TRACE(sp);
    DetectorOptions options = route_options("temporal");
    options.segmentation.superpixel_size = sp;
    options.decision.threshold = 2.0;
    int loops = 0, reported = 0;
    for (const Result& r : run(options)) {
      loops += r.loop;
      if (r.best.frame >= 0) {
        ++reported;
        if (sp == 80) {
          EXPECT_LT(r.best.score, 2.0);
        }
      }
    }
    EXPECT_GT(reported, 0);
    if (sp == 80) {
      EXPECT_EQ(loops, 0);
    } else {
      EXPECT_GT(loops, 0);
    }
  }
}

TEST(DetectorVerification, GeometricOnlyChecksCandidatesThatCouldBeLoops) {
  DetectorOptions options = route_options("geometric");
  options.verification.max_candidates = 2;
  Detector detector(options);
  for (int i = 0; i < kPlaces + 15; ++i) {
    const Result r = detector.process(place(i % kPlaces, i / kPlaces));
    EXPECT_LE(r.verification.size(), 2u);
    for (const auto& v : r.verification) EXPECT_EQ(v.stage, "geometric");
    if (r.loop) {
      EXPECT_TRUE(r.evidence.confirmed);
      EXPECT_FALSE(r.evidence.continues);  // continuity needs the temporal stage
      EXPECT_EQ(r.best.frame, i - kPlaces);
    }
    for (const auto& v : r.verification) {
      // Only candidates whose score plus the bonus reached the threshold.
      for (const Candidate& c : r.candidates) {
        if (c.frame == v.candidate) {
          EXPECT_GE(c.score + 3.5, 7.0);
        }
      }
    }
  }
}

}  // namespace
}  // namespace lsgd

namespace lsgd {
namespace {

// The robustness requirement: lighting changes (revisits A', A'' and
// the new streets F, G) and moving objects (C, B', A'', G and the dense H)
// must not produce accepted false loops in the synthetic world, in either
// search mode, with the default options.
class SyntheticDefaults : public ::testing::TestWithParam<std::string> {};

TEST_P(SyntheticDefaults, AcceptNoFalseLoop) {
  const eval::SyntheticWorld world;
  DetectorOptions options;
  options.search.mode = GetParam();
  Detector detector(options);
  int loops = 0;
  for (std::int64_t i = 0; i < world.frames(); ++i) {
    const Result r = detector.process(world.render(i));
    if (!r.loop) continue;
    ++loops;
    EXPECT_TRUE(world.ground_truth().is_loop(i, r.best.frame))
        << "false loop " << i << " -> " << r.best.frame << " score " << r.best.score << " in "
        << world.route()[world.segment_of(i)].label;
  }
  EXPECT_GT(loops, 100);  // and it still closes loops
}

INSTANTIATE_TEST_SUITE_P(Modes, SyntheticDefaults,
                         ::testing::Values(kExhaustiveSearch, kNodesSearch));

}  // namespace
}  // namespace lsgd
