// Tests of the verification stages' options, the agreement gate
// (include/lsgd/verification.h) and their integration, with the loop
// decision, in the Detector. The decision alone: decision_test.cc; the
// sequence scores: evidence_test.cc.
#include "lsgd/verification.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "synthetic/synthetic.h"
#include "lsgd/stages/temporal.h"
#include "test_util.h"

namespace lsgd {
namespace {

TEST(VerificationStages, ParseAndPrint) {
  VerificationOptions o;
  for (const char* text : {"none", "temporal", "geometric", "temporal,geometric"}) {
    parse_verification_stages(text, o);
    EXPECT_EQ(verification_stages(o), text);
  }
  parse_verification_stages("geometric,temporal", o);  // kept in registration order
  EXPECT_EQ(verification_stages(o), "temporal,geometric");
  EXPECT_TRUE(o.has(kTemporalStage) && o.has(kGeometricStage));
  for (const char* bad : {"temporal,temporal", "none,temporal", "temporal,", ",geometric"}) {
    EXPECT_THROW(parse_verification_stages(bad, o), InvalidArgument) << bad;
  }
  EXPECT_EQ(verification_stages(o), "temporal,geometric");  // unchanged by a refused text
  o.stages = {kGeometricStage, kGeometricStage};
  EXPECT_NE(test::message_of<InvalidArgument>([&] { o.check(); }).find("lists 'geometric' twice"),
            std::string::npos);
  o.stages = {"sift"};
  EXPECT_NE(test::message_of<InvalidArgument>([&] { o.check(); })
                .find("verification stage 'sift' is unknown: expected one of temporal, geometric"),
            std::string::npos);
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
      if (r.frame - 10 >= kMinCalibration) {
        EXPECT_EQ(r.best.score, r.candidates.front().score);  // the standardised similarity
      } else {
        // A young query, on the prior: reported, never a loop on appearance alone.
        EXPECT_EQ(r.best.score, std::min(r.candidates.front().score, std::nextafter(7.0, -1.0)));
        EXPECT_FALSE(r.loop);
      }
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
    // The strong bonus (1.5): a first loop of the best-ranked candidate with 40 inliers or more.
    const bool strong = !r.evidence.continues && r.evidence.inliers >= 40 &&
                        r.best.frame == r.candidates[0].frame;
    const double bonus = 3.5 + (r.evidence.continues ? 2.5 : 0.0) + (strong ? 1.5 : 0.0);
    EXPECT_DOUBLE_EQ(r.best.score, r.evidence.appearance + bonus);
    continued += r.evidence.continues;
    ASSERT_FALSE(r.verification.empty());
    EXPECT_EQ(r.verification.back().stage, "geometric");
    EXPECT_TRUE(r.verification.back().accepted) << r.verification.back().reason;
  }
  EXPECT_GE(loops, kPlaces - 15);
  EXPECT_GT(continued, 0);
}

// A camera that stays is not a loop (decision.stay_z): after three laps of
// the route it stands at the last place for 15 frames (jittering by a
// pixel), longer than min_gap (10). The frames since the stay began, and
// the third lap's view of the place just before it, look like the query
// all the way: no loop to them. Loops to the first two laps' views (the
// camera left and came back) stay. With stay_z 0 (off) the stay declares
// loops to itself.
TEST(DetectorVerification, ACameraStandingStillDeclaresNoLoopToItself) {
  for (const double stay_z : {3.0, 0.0}) {
    SCOPED_TRACE(testing::Message() << "stay_z " << stay_z);
    DetectorOptions options = route_options("temporal,geometric");
    options.decision.stay_z = stay_z;
    Detector detector(options);
    constexpr int kLaps = 3, kStay = 15;
    constexpr int kStayStart = kLaps * kPlaces;
    int to_the_stay = 0, revisits = 0;
    for (int i = 0; i < kStayStart + kStay; ++i) {
      const cv::Mat frame = i < kStayStart ? place(i % kPlaces, i / kPlaces) : place(kPlaces - 1, i % 2);
      const Result r = detector.process(frame);
      if (!r.loop) continue;
      if (r.best.frame >= kStayStart - 1) {
        ++to_the_stay;
      } else {
        ++revisits;
        EXPECT_EQ(r.best.frame % kPlaces, i < kStayStart ? i % kPlaces : kPlaces - 1) << "frame " << i;
      }
    }
    EXPECT_EQ(to_the_stay == 0, stay_z > 0);
    EXPECT_GT(revisits, kPlaces);
  }
}

// A camera held still at the start: lip6-outdoor's first frame 60 times
// (sensor noise, sigma 2 gray levels), then its frames 1-199, min_gap 20
// (the shipped defaults otherwise). Every early candidate is a frame of the
// stay, so the query's statistics are the stay's own and the appearance
// test cannot see it; the frames between match the query by geometry, so
// no loop is declared to a frame of the stay (with stay_z 0, off, some
// are; docs/results.md, "A camera that stays is not a loop").
TEST(DetectorVerification, ACameraHeldStillAtTheStartDeclaresNoLoopToItself) {
  const std::filesystem::path dir = std::filesystem::path(LSGD_SHARED_DIR) / "datasets" / "lip6-outdoor";
  std::ifstream list(dir / "sequence.txt");
  if (!list) GTEST_SKIP() << "lip6-outdoor not found at " << dir << " (../shared is absent)";
  std::vector<std::string> names;
  for (std::string line; std::getline(list, line) && names.size() < 200;) {
    if (!line.empty()) names.push_back((dir / line).string());
  }
  ASSERT_EQ(names.size(), 200u);
  const cv::Mat first = cv::imread(names[0], cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(first.empty());
  constexpr int kStill = 60;
  for (const double stay_z : {3.0, 0.0}) {
    SCOPED_TRACE(testing::Message() << "stay_z " << stay_z);
    DetectorOptions options;
    options.search.min_gap = 20;
    options.decision.stay_z = stay_z;
    Detector detector(options);
    std::uint64_t state = 11;
    int to_the_still = 0;
    for (int i = 0; i < kStill + 199; ++i) {
      cv::Mat frame;
      if (i < kStill) {
        frame = first.clone();
        for (int k = 0; k < static_cast<int>(frame.total()); ++k) {
          // About normal: the sum of four uniform draws in [-2, 2].
          int noise = 0;
          for (int t = 0; t < 4; ++t) noise += static_cast<int>(test::splitmix64(state) % 5) - 2;
          frame.data[k] = static_cast<std::uint8_t>(std::clamp(frame.data[k] + noise, 0, 255));
        }
      } else {
        frame = cv::imread(names[static_cast<std::size_t>(i - kStill + 1)], cv::IMREAD_GRAYSCALE);
      }
      const Result r = detector.process(frame);
      if (r.loop && r.best.frame < kStill) ++to_the_still;
    }
    if (stay_z > 0) {
      EXPECT_EQ(to_the_still, 0);
    } else {
      EXPECT_GT(to_the_still, 0);  // the scene reproduces the defect
    }
  }
}

// Detector::cut() between two frames of a revisit: the frame after it
// continues no loop (its result is the one of a first loop, or none), while
// the same frame without the cut continues the loop.
TEST(DetectorVerification, ACutEndsTheLoopItFollows) {
  const DetectorOptions options = route_options("temporal,geometric");
  Detector plain(options), cut(options);
  int checked = 0;
  for (int i = 0; i < 2 * kPlaces; ++i) {
    const cv::Mat frame = place(i % kPlaces, i / kPlaces);
    const Result a = plain.process(frame);
    const Result b = cut.process(frame);
    if (a.loop && i % 7 == 0) cut.cut();
    if (i > 0 && (i - 1) % 7 == 0 && plain.size() > kPlaces + 1 && a.evidence.continues) {
      ++checked;
      EXPECT_FALSE(b.evidence.continues) << i;
    }
  }
  EXPECT_GT(checked, 3);
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
    EXPECT_EQ(both[i].candidates.size(), temporal[i].candidates.size());
    if (static_cast<std::int64_t>(i) - 10 < kMinCalibration) {
      // A young query: only what geometry confirms is reported.
      EXPECT_EQ(both[i].best.frame, -1) << i;
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
      // Only candidates whose score plus the bonuses could reach the threshold,
      // and the best-ranked one (the ranking examines it on every query).
      for (const Candidate& c : r.candidates) {
        if (c.frame == v.candidate && &c != &r.candidates[0]) {
          EXPECT_GE(c.score + 3.5, 7.0);
        }
      }
    }
    // The best candidate's verdict comes first, and is the ranking's.
    if (!r.candidates.empty()) {
      ASSERT_FALSE(r.verification.empty());
      EXPECT_EQ(r.verification[0].candidate, r.candidates[0].frame);
      EXPECT_EQ(r.ranking.best.frame, r.candidates[0].frame);
      EXPECT_EQ(r.ranking.confirmed, r.verification[0].accepted);  // no temporal stage: no track
    }
    if (r.frame - 10 < kMinCalibration && !r.candidates.empty()) {
      ASSERT_FALSE(r.verification.empty());
      EXPECT_EQ(r.verification[0].candidate, r.candidates[0].frame);
      EXPECT_EQ(r.best.frame >= 0, r.evidence.confirmed);  // reported only when confirmed
    }
  }
}


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

// ---- the stage interface: a stage registered by an application runs in the
// detector through the interface alone, and its state travels with the
// frame's state blob (what docs/design.md, "Add a verification stage",
// promises: one file pair and its registration).

// A gate that rejects candidates with an odd frame id, and remembers for each
// query how many candidates it rejected (its state, version 1).
class EvenFramesOnly final : public VerificationStage {
 public:
  const char* name() const override { return "test-even"; }
  Role role() const override { return Role::kGate; }
  StageCheck check(std::int64_t, const Candidate& c) override {
    const bool even = c.frame % 2 == 0;
    if (!even) ++rejected_now_;
    return {even, -1, even ? "even" : "odd frame", 0.0, nullptr};
  }
  void end(std::int64_t query, const std::vector<Candidate>&) override {
    rejected_.resize(static_cast<std::size_t>(query));
    rejected_.push_back(rejected_now_);
    rejected_now_ = 0;
  }
  bool has_state() const override { return true; }
  void save_frame(std::int64_t frame, StateWriter& out) const override {
    out.put_i64(rejected_.at(static_cast<std::size_t>(frame)));
  }
  void check_frame(std::int64_t, int, int, std::uint32_t version, StateReader in) const override {
    check_state_version(in.what(), name(), version, 1);
    in.get_i64();
    in.finish();
  }
  void restore_frame(std::int64_t frame, int, int, std::uint32_t, StateReader in) override {
    rejected_.resize(static_cast<std::size_t>(frame));
    rejected_.push_back(in.get_i64());
  }

 private:
  std::int64_t rejected_now_ = 0;
  std::vector<std::int64_t> rejected_;
};

void register_test_stage() {
  static const bool once = [] {
    register_verification_stage({"test-even", "rejects odd frames",
                                 [](const VerificationOptions&) -> std::unique_ptr<VerificationStage> {
                                   return std::make_unique<EvenFramesOnly>();
                                 }});
    return true;
  }();
  (void)once;
}

TEST(StageRegistry, ARegisteredStageRunsInTheDetectorThroughTheInterfaceAlone) {
  register_test_stage();
  EXPECT_NE(verification_stage_names().find("temporal, geometric, test-even"), std::string::npos);
  const auto make = [](const VerificationOptions&) -> std::unique_ptr<VerificationStage> {
    return std::make_unique<EvenFramesOnly>();
  };
  EXPECT_THROW(register_verification_stage({"test-even", "again", make}), InvalidArgument);
  EXPECT_THROW(register_verification_stage({"none", "reserved", make}), InvalidArgument);
  EXPECT_THROW(register_verification_stage({"", "no name", make}), InvalidArgument);
  EXPECT_THROW(register_verification_stage({"test-x", "no make", nullptr}), InvalidArgument);

  DetectorOptions o = route_options("temporal");
  parse_verification_stages("test-even,temporal", o.verification);
  EXPECT_EQ(verification_stages(o.verification), "temporal,test-even");
  Detector d(o);
  ASSERT_NE(d.stage("test-even"), nullptr);
  EXPECT_EQ(d.stage(kGeometricStage), nullptr);
  int examined = 0, odd_reported = 0;
  for (int lap = 0; lap < 2; ++lap) {
    for (int p = 0; p < kPlaces; ++p) {
      const Result r = d.process(place(p, lap));
      for (const StageVerdict& v : r.verification) {
        ASSERT_EQ(v.stage, "test-even");
        EXPECT_EQ(v.accepted, v.candidate % 2 == 0);
        ++examined;
      }
      odd_reported += r.best.frame >= 0 && r.best.frame % 2 != 0 ? 1 : 0;
    }
  }
  EXPECT_GT(examined, 50);
  EXPECT_EQ(odd_reported, 0);
  {
    // With geometry the decision also examines the continuation of the
    // previous frame's loop; the gate judges it too.
    DetectorOptions g = o;
    parse_verification_stages("temporal,geometric,test-even", g.verification);
    DetectorOptions plain = g;
    plain.verification.stages = {kTemporalStage, kGeometricStage};
    Detector with(g), without(plain);
    int odd_loops_without = 0, loops = 0;
    for (int lap = 0; lap < 3; ++lap) {
      for (int p = 0; p < kPlaces; ++p) {
        const Result a = with.process(place(p, lap));
        const Result b = without.process(place(p, lap));
        EXPECT_FALSE(a.loop && a.best.frame % 2 != 0) << "query " << a.frame;
        loops += a.loop ? 1 : 0;
        odd_loops_without += b.loop && b.best.frame % 2 != 0 ? 1 : 0;
      }
    }
    EXPECT_GT(loops, 10);
    EXPECT_GT(odd_loops_without, 10);  // the gate had work to do
  }

  // Its state travels in the frame's state blob: a detector restored from
  // the blobs continues exactly as the original.
  Detector restored(o);
  for (std::int64_t f = 0; f < d.size(); ++f) {
    Descriptor copy;
    const DescriptorView v = d.store().view(f);
    copy.grid = d.store().grid();
    copy.hist.assign(v.hist, v.hist + v.cells * kBins);
    copy.pixels.assign(v.pixels, v.pixels + v.cells);
    restored.restore_frame(d.width(), d.height(), copy, d.frame_state(f));
    EXPECT_EQ(restored.frame_state(f), d.frame_state(f));
  }
  for (int p = 0; p < 10; ++p) {
    const Result a = d.process(place(p, 3));
    const Result b = restored.process(place(p, 3));
    EXPECT_EQ(a.best.frame, b.best.frame);
    EXPECT_EQ(a.best.score, b.best.score);
    EXPECT_EQ(a.verification.size(), b.verification.size());
  }
  // A detector without the stage refuses its records.
  DetectorOptions without = o;
  without.verification.stages = {kTemporalStage};
  Detector other(without);
  Descriptor first;
  first.grid = d.store().grid();
  first.hist.assign(d.store().view(0).hist, d.store().view(0).hist + first.grid.cells() * kBins);
  first.pixels.assign(d.store().view(0).pixels, d.store().view(0).pixels + first.grid.cells());
  EXPECT_NE(test::message_of<InvalidArgument>([&] {
              other.restore_frame(d.width(), d.height(), first, d.frame_state(0));
            }).find("has state of 'test-even', which these options do not have"),
            std::string::npos);
}

// Records of a frame's state blob read back as written; the record helpers
// refuse what they cannot read.
TEST(StateRecords, RoundTripAndBounds) {
  StateWriter w;
  w.put_i64(-5);
  w.put_f64(2.5);
  const float xs[2] = {1.5f, -0.25f};
  w.put_f32s(xs, 2);
  const std::uint8_t raw[3] = {7, 8, 9};
  w.put_bytes(raw, 3);
  const std::vector<std::uint8_t> blob = encode_records({{"a", 1, w.bytes()}, {"b", 3, {}}});
  const std::vector<StateRecord> r = decode_records(blob.data(), blob.size());
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].component, "a");
  EXPECT_EQ(r[1].version, 3u);
  StateReader in(r[0].bytes.data(), r[0].bytes.size(), "a");
  EXPECT_EQ(in.get_i64(), -5);
  EXPECT_EQ(in.get_f64(), 2.5);
  float ys[2] = {};
  in.get_f32s(ys, 2);
  EXPECT_EQ(ys[0], 1.5f);
  EXPECT_EQ(ys[1], -0.25f);
  EXPECT_EQ(in.get_bytes(3)[2], 9);
  EXPECT_NO_THROW(in.finish());
  EXPECT_THROW(in.get_i64(), InvalidArgument);
  StateReader absent("frame 3's x state");
  EXPECT_FALSE(absent.present());
  EXPECT_NE(test::message_of<InvalidArgument>([&] { absent.get_i64(); }).find("frame 3's x state: there is no record"),
            std::string::npos);
  for (std::size_t cut = 0; cut < blob.size(); ++cut) {
    EXPECT_THROW(decode_records(blob.data(), cut), InvalidArgument) << cut;
  }
  EXPECT_THROW(check_state_version("x", "a", 2, 1), InvalidArgument);
  EXPECT_THROW(check_state_version("x", "a", 0, 1), InvalidArgument);
}
}  // namespace
}  // namespace lsgd
