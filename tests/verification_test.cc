// Tests of the verification stages' options and the temporal stage
// (include/lsgd/verification.h), and of their integration in the Detector.
#include "lsgd/verification.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/eval/synthetic.h"
#include "test_util.h"

namespace lsgd {
namespace {

// A 1-cell descriptor whose whole mass sits in bin `bin`: two such frames are
// identical (similarity 1) when their bins agree, and dissimilar otherwise.
Descriptor spike(int bin) {
  Descriptor d;
  d.grid = {1, 1};
  d.hist.assign(kBins, 0);
  d.hist[bin] = 100;
  d.pixels = {100};
  return d;
}

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

// Frames 0..9 show places 0..9 (bins 10..19); frames 10..19 revisit them in
// order. Query 15 (place 5) ranks frame 6 first by a small margin; the
// sequence realigns it to frame 5, whose whole diagonal matches.
class TemporalFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int i = 0; i < 10; ++i) store.add(spike(10 + i));
    for (int i = 0; i < 5; ++i) store.add(spike(10 + i));  // frames 10..14 = places 0..4
  }
  FrameStore store;
};

TEST_F(TemporalFixture, RescoreRealignsToTheBestDiagonal) {
  TemporalOptions options;
  options.frames = 4;
  options.tolerance = 2;
  const TemporalVerifier v(options);
  const Descriptor query = spike(15);  // frame 15 = place 5
  std::vector<Candidate> out;
  v.rescore(store, query.view(), 15, {{6, 0.9}, {2, 0.5}}, 3, SimilarityMetric::kReference, 10,
            out);
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out.front().frame, 5);
  EXPECT_DOUBLE_EQ(out.front().score, 1.0);  // sim(15-t, 5-t) = 1 for t = 0..3
  for (const Candidate& c : out) EXPECT_LT(c.frame, 15 - 3);
  for (std::size_t i = 1; i < out.size(); ++i) EXPECT_FALSE(better(out[i], out[i - 1]));
}

TEST_F(TemporalFixture, RescoreKeepsTheTemporalWindowAndTopN) {
  TemporalOptions options;
  options.tolerance = 5;
  const TemporalVerifier v(options);
  const Descriptor query = spike(15);
  std::vector<Candidate> out;
  v.rescore(store, query.view(), 15, {{8, 0.9}, {3, 0.8}, {1, 0.7}}, 8,
            SimilarityMetric::kReference, 2, out);
  EXPECT_LE(out.size(), 2u);
  for (const Candidate& c : out) EXPECT_LT(c.frame, 15 - 8);
}

// The sequence score with a second length is the mean of the two single
// sequence scores, and near the start of the store both lengths shorten.
TEST(TemporalSequence, LongFramesAveragesTheTwoLengths) {
  // 1-cell frames with t of 100 pixels in bin 1 and the rest in bin 0: the
  // diagonal similarities all differ.
  auto frame = [](int t) {
    Descriptor d;
    d.grid = {1, 1};
    d.hist.assign(kBins, 0);
    d.hist[0] = static_cast<Bin>(100 - t);
    d.hist[1] = static_cast<Bin>(t);
    d.pixels = {100};
    return d;
  };
  FrameStore store;
  for (int i = 0; i < 40; ++i) store.add(frame((i * 37) % 101));
  const Descriptor query = frame(55);
  auto score = [&](int frames, int long_frames, std::int64_t j) {
    TemporalOptions o;
    o.frames = frames;
    o.long_frames = long_frames;
    o.tolerance = 0;
    const TemporalVerifier v(o);
    std::vector<Candidate> out;
    v.rescore(store, query.view(), 40, {{j, 0.5}}, 0, SimilarityMetric::kReference, 1, out);
    EXPECT_EQ(out.size(), 1u);
    return out.empty() ? -1.0 : out.front().score;
  };
  for (const std::int64_t j : {30, 20, 5}) {  // 5: the 12-frame sequence is cut to 6
    SCOPED_TRACE(j);
    const double short_score = score(4, 0, j), long_score = score(12, 0, j);
    EXPECT_NE(short_score, long_score);
    EXPECT_DOUBLE_EQ(score(4, 12, j), 0.5 * (short_score + long_score));
  }
  // j = 2: both lengths are cut to the 3 frames that exist.
  EXPECT_DOUBLE_EQ(score(4, 12, 2), score(4, 0, 2));
  EXPECT_DOUBLE_EQ(score(12, 0, 2), score(4, 0, 2));
  EXPECT_DOUBLE_EQ(score(1, 0, 0), score(1, 12, 0));  // only frame 0 exists: one similarity
}

// The verifier caches similarities of stored pairs between queries; its
// scores must equal a fresh verifier's bit for bit, also when the metric or
// the store changes between calls.
TEST(TemporalSequence, PairCacheGivesTheScoresOfAFreshVerifier) {
  auto frame = [](int t) {
    Descriptor d;
    d.grid = {1, 2};
    d.hist.assign(2 * kBins, 0);
    d.hist[0] = static_cast<Bin>(100 - t);
    d.hist[1] = static_cast<Bin>(t);
    d.hist[kBins + 5] = static_cast<Bin>(t / 2 + 10);
    d.hist[kBins + 6] = static_cast<Bin>(60 - t / 2);
    d.pixels = {100, 70};
    return d;
  };
  std::vector<Descriptor> frames;
  for (int i = 0; i < 160; ++i) frames.push_back(frame((i * 37 + (i / 40) * 11) % 101));
  TemporalOptions o;
  o.frames = 6;
  o.long_frames = 20;
  const TemporalVerifier warm(o);
  FrameStore store, other;
  for (int i = 0; i < 30; ++i) store.add(frames[i]);
  for (int q = 30; q < 160; ++q) {
    SCOPED_TRACE(q);
    const SimilarityMetric metric =
        q >= 90 && q < 100 ? SimilarityMetric::kL1 : SimilarityMetric::kReference;
    const FrameStore& s = q >= 120 && q < 125 ? other : store;
    if (q == 120) {
      for (int i = 0; i < 120; ++i) other.add(frames[(i + 7) % 160]);  // different frames
    }
    if (q >= 125 && other.size() > 0) {
      // back to `store`; `other` keeps growing so its frames differ
      other.add(frames[q]);
    }
    const std::vector<Candidate> raw = {{q - 25, 0.9}, {q / 3, 0.8}, {(q * 7) % (q - 10), 0.7}};
    std::vector<Candidate> got, want;
    warm.rescore(s, frames[q].view(), s.size(), raw, 5, metric, 10, got);
    const TemporalVerifier fresh(o);
    fresh.rescore(s, frames[q].view(), s.size(), raw, 5, metric, 10, want);
    ASSERT_EQ(got.size(), want.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].frame, want[i].frame);
      EXPECT_EQ(got[i].score, want[i].score);
    }
    if (&s == &store) store.add(frames[q]);
  }
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
// its own 8 random gray levels, so unrelated places share almost no histogram bin.
cv::Mat place(int p) {
  std::uint64_t state = 7000 + p;
  std::uint8_t levels[8];
  for (auto& l : levels) l = static_cast<std::uint8_t>(test::splitmix64(state));
  const GrayImage g = test::random_image(64, 48, 1000 + p);
  cv::Mat m(48, 64, CV_8UC1);
  for (int i = 0; i < 48 * 64; ++i) m.data[i] = levels[g.pixels[i] % 8];
  return m;
}

std::vector<Result> run(const DetectorOptions& options) {
  Detector detector(options);
  std::vector<Result> results;
  for (int i = 0; i < 60; ++i) results.push_back(detector.process(place(i % 30)));
  return results;
}

TEST(DetectorVerification, NoneIsTheFaithfulBaseline) {
  DetectorOptions options;
  options.search.min_gap = 10;
  parse_verification_stages("none", options.verification);
  const auto a = run(options);
  for (const Result& r : a) {
    EXPECT_TRUE(r.verification.empty());
    if (!r.candidates.empty()) {
      EXPECT_EQ(r.best.frame, r.candidates.front().frame);
    }
  }
}

TEST(DetectorVerification, TemporalFindsTheRevisitAndExplainsItself) {
  DetectorOptions options;
  options.search.min_gap = 10;
  parse_verification_stages("temporal", options.verification);
  options.verification.temporal_options.frames = 4;
  const auto results = run(options);
  int loops = 0;
  for (const Result& r : results) {
    if (r.frame < 34) continue;  // the revisit starts at 30; 4-frame sequences and 1 agreement
    EXPECT_EQ(r.best.frame, r.frame - 30) << "frame " << r.frame;
    EXPECT_NEAR(r.best.score, 1.0, 1e-12);
    ASSERT_FALSE(r.verification.empty());
    EXPECT_EQ(r.verification.front().stage, "temporal");
    EXPECT_TRUE(r.verification.front().accepted) << r.verification.front().reason;
    loops += r.loop;
  }
  EXPECT_EQ(loops, 26);
  // Before the revisit nothing is a loop.
  for (int i = 0; i < 30; ++i) EXPECT_FALSE(results[i].loop) << i;
}

TEST(DetectorVerification, GeometricAddsAVerdictPerExaminedCandidate) {
  DetectorOptions options;
  options.search.min_gap = 10;
  parse_verification_stages("geometric", options.verification);
  options.verification.max_candidates = 2;
  Detector detector(options);
  for (int i = 0; i < 45; ++i) {
    const Result r = detector.process(place(i % 30));
    EXPECT_LE(r.verification.size(), 2u);
    for (const auto& v : r.verification) EXPECT_EQ(v.stage, "geometric");
    if (r.best.frame >= 0) {
      ASSERT_FALSE(r.verification.empty());
      EXPECT_TRUE(r.verification.back().accepted);
    }
    if (i >= 30) {
      EXPECT_EQ(r.best.frame, i - 30) << "identical image must pass geometry";
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
class SyntheticDefaults : public ::testing::TestWithParam<SearchMode> {};

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
  EXPECT_GT(loops, 10);  // and it still closes loops
}

INSTANTIATE_TEST_SUITE_P(Modes, SyntheticDefaults,
                         ::testing::Values(SearchMode::kExhaustive, SearchMode::kDynamicNodes));

}  // namespace
}  // namespace lsgd
