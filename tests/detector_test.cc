// Tests of the online detector (include/lsgd/detector.h): frame ids, self
// matches, determinism, agreement of the two search modes, rejection of bad
// frames without side effects, result fields, memory accounting.
#include "lsgd/detector.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <atomic>
#include <limits>
#include <map>
#include <utility>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "lsgd/error.h"
#include "lsgd/image.h"
#include "lsgd/search/exhaustive.h"
#include "detector_util.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::message_of;
using test::splitmix64;

constexpr int kW = 96;
constexpr int kH = 64;

// Textured random frame: a smooth random gradient plus noise, so frames from
// different seeds differ but are not pure noise.
cv::Mat random_frame(std::uint64_t seed, int type = CV_8UC3, int width = kW, int height = kH) {
  std::uint64_t s = seed * 7919 + 1;
  const double a = static_cast<double>(splitmix64(s) % 1000) / 1000.0;
  const double b = static_cast<double>(splitmix64(s) % 1000) / 1000.0;
  const double ph = static_cast<double>(splitmix64(s) % 628) / 100.0;
  cv::Mat m(height, width, type);
  const int ch = m.channels();
  for (int y = 0; y < height; ++y) {
    std::uint8_t* row = m.ptr<std::uint8_t>(y);
    for (int x = 0; x < width; ++x) {
      const double base = 128 + 80 * std::sin((0.05 + 0.2 * a) * x + ph) *
                                    std::cos((0.05 + 0.2 * b) * y - ph);
      for (int c = 0; c < ch; ++c) {
        const int v = static_cast<int>(base) + static_cast<int>(splitmix64(s) % 41) - 20 + 10 * c;
        row[x * ch + c] = static_cast<std::uint8_t>(std::max(0, std::min(255, v)));
      }
    }
  }
  return m;
}

DetectorOptions small_options(const std::string& mode = kExhaustiveSearch, std::int64_t min_gap = 3,
                              int top_n = 5) {
  DetectorOptions o;
  o.segmentation.superpixel_size = 16;  // 96x64 -> 3 x 4 = 12 cells
  o.search.mode = mode;
  o.search.min_gap = min_gap;
  o.search.top_n = top_n;
  // The faithful method: these tests check the search itself.
  o.verification.stages = {};
  return o;
}

// Processes `n` distinct frames: scores are standardised only once a query
// has kMinCalibration candidates (evidence.h).
void calibrate(Detector& det, int n = static_cast<int>(kMinCalibration) + 4) {
  for (int i = 0; i < n; ++i) det.process(random_frame(5000 + i));
}

void expect_same_result(const Result& a, const Result& b) {
  EXPECT_EQ(a.frame, b.frame);
  EXPECT_EQ(a.loop, b.loop);
  EXPECT_EQ(a.best.frame, b.best.frame);
  EXPECT_EQ(a.best.score, b.best.score);
  EXPECT_EQ(a.node, b.node);
  EXPECT_EQ(a.node_created, b.node_created);
  ASSERT_EQ(a.candidates.size(), b.candidates.size());
  for (std::size_t i = 0; i < a.candidates.size(); ++i) {
    EXPECT_EQ(a.candidates[i].frame, b.candidates[i].frame) << "rank " << i;
    EXPECT_EQ(a.candidates[i].score, b.candidates[i].score) << "rank " << i;
  }
}

ImageView view_of_mat(const cv::Mat& m) {
  ImageView v;
  v.data = m.ptr<std::uint8_t>(0);
  v.width = m.cols;
  v.height = m.rows;
  v.stride_bytes = static_cast<std::ptrdiff_t>(m.step[0]);
  v.format = m.channels() == 1 ? PixelFormat::kGray8
             : m.channels() == 3 ? PixelFormat::kBgr8
                                 : PixelFormat::kBgra8;
  return v;
}

TEST(Detector, FrameIsItsOwnBestMatch) {
  const DetectorOptions o = small_options(kExhaustiveSearch, 3, 5);
  Detector det(o);
  const cv::Mat a = random_frame(1);
  EXPECT_EQ(det.process(a).frame, 0);
  calibrate(det);
  const Result r = det.process(a);
  EXPECT_EQ(r.frame, 1 + static_cast<int>(kMinCalibration) + 4);
  EXPECT_EQ(r.best.frame, 0);
  EXPECT_GT(r.best.score, 3.0);  // standardised: far above the other frames
  EXPECT_EQ(r.loop, r.best.score >= o.decision.threshold);
  ASSERT_FALSE(r.candidates.empty());
  EXPECT_EQ(r.candidates[0].frame, 0);
  for (std::size_t i = 1; i < r.candidates.size(); ++i) {
    EXPECT_LT(r.candidates[i].score, r.candidates[0].score);
  }
  EXPECT_EQ(det.similarity(0, r.frame), 1.0);
}

TEST(Detector, OwnMatchInEveryMetricAndMode) {
  for (SimilarityMetric metric :
       {SimilarityMetric::kReference, SimilarityMetric::kL1, SimilarityMetric::kNormalizedL1}) {
    for (const std::string mode : {kExhaustiveSearch, kNodesSearch}) {
      SCOPED_TRACE(testing::Message() << to_string(metric) << " " << mode);
      DetectorOptions o = small_options(mode, 2, 3);
      o.similarity.metric = metric;
      o.search.nodes.alpha = 0;  // every frame in one node: the query is always examined
      o.search.nodes.beta = 0;
      Detector det(o);
      const cv::Mat a = random_frame(2);
      det.process(a);
      calibrate(det);
      const Result r = det.process(a);
      EXPECT_EQ(r.best.frame, 0);
      ASSERT_GE(r.candidates.size(), 2u);
      EXPECT_GT(r.best.score, r.candidates[1].score);
    }
  }
}

TEST(Detector, GrayVersionOfABgrFrameMatchesIt) {
  Detector det(small_options(kExhaustiveSearch, 1, 3));
  const cv::Mat a = random_frame(3);
  cv::Mat gray;
  cv::cvtColor(a, gray, cv::COLOR_BGR2GRAY);
  cv::Mat bgra;
  cv::cvtColor(a, bgra, cv::COLOR_BGR2BGRA);
  det.process(a);
  calibrate(det);
  const Result rg = det.process(gray);
  EXPECT_EQ(rg.best.frame, 0);
  EXPECT_EQ(det.similarity(0, rg.frame), 1.0);
  const Result ra = det.process(bgra);
  EXPECT_EQ(ra.best.frame, 0);
  EXPECT_EQ(det.similarity(0, ra.frame), 1.0);
}

// The extension point: a mode registered from outside the library runs in
// the detector through CandidateSearch alone.
// "test-copy": exhaustive search under another name (it forwards to the
// built-in one); results must be identical.
class CopyOfExhaustive final : public CandidateSearch {
 public:
  explicit CopyOfExhaustive(const SearchOptions& o) : inner_(make_exhaustive_search(o)) {}
  const char* name() const override { return "test-copy"; }
  bool scores_every_frame() const override { return inner_->scores_every_frame(); }
  Outcome search(const Query& q, std::vector<Candidate>& out, std::vector<double>& row) override {
    return inner_->search(q, out, row);
  }

 private:
  std::unique_ptr<CandidateSearch> inner_;
};

// "test-blocks": a shortlist with groups: frame i is in group i / 4, and the
// candidates are the frames of the newest group outside the window.
class Blocks final : public CandidateSearch {
 public:
  explicit Blocks(const SearchOptions& o) : options_(o) {}
  const char* name() const override { return "test-blocks"; }
  bool scores_every_frame() const override { return false; }
  Outcome search(const Query& q, std::vector<Candidate>& out, std::vector<double>&) override {
    out.clear();
    const std::int64_t limit = q.id - options_.min_gap;
    for (std::int64_t j = std::max<std::int64_t>(0, (limit - 1) / 4 * 4); j < limit; ++j) {
      out.push_back({j, similarity(q.descriptor, q.store.view(j), q.metric)});
    }
    std::sort(out.begin(), out.end(), better);
    if (out.size() > static_cast<std::size_t>(options_.top_n)) out.resize(options_.top_n);
    const std::int64_t group = q.id / 4;
    if (group == static_cast<std::int64_t>(groups_.size())) groups_.emplace_back();
    groups_.back().push_back(q.id);
    return {group, q.id % 4 == 0};
  }
  bool has_groups() const override { return true; }
  std::int64_t groups() const override { return static_cast<std::int64_t>(groups_.size()); }
  const std::vector<std::int64_t>& members(std::int64_t g) const override {
    return groups_.at(static_cast<std::size_t>(g));
  }

 private:
  SearchOptions options_;
  std::vector<std::vector<std::int64_t>> groups_;
};

void register_test_modes() {
  static const bool once = [] {
    register_search_mode({"test-copy", "exhaustive, renamed",
                          [](const SearchOptions& o) -> std::unique_ptr<CandidateSearch> {
                            return std::make_unique<CopyOfExhaustive>(o);
                          }});
    register_search_mode({"test-blocks", "groups of 4 frames",
                          [](const SearchOptions& o) -> std::unique_ptr<CandidateSearch> {
                            return std::make_unique<Blocks>(o);
                          },
                          // Its memory model: a group id per frame, and 2 bytes a cell.
                          [](const DetectorOptions&, int cells) -> std::int64_t {
                            return 8 + 2 * std::int64_t{cells};
                          }});
    return true;
  }();
  (void)once;
}

TEST(SearchModes, ARegisteredModeRunsInTheDetectorThroughTheInterfaceAlone) {
  register_test_modes();
  EXPECT_NE(search_mode_names().find("test-copy"), std::string::npos);
  const auto make = [](const SearchOptions& o) -> std::unique_ptr<CandidateSearch> {
    return std::make_unique<CopyOfExhaustive>(o);
  };
  EXPECT_THROW(register_search_mode({"test-copy", "again", make}), InvalidArgument);
  EXPECT_THROW(register_search_mode({"", "no name", make}), InvalidArgument);
  EXPECT_THROW(register_search_mode({"test-none", "no make", nullptr}), InvalidArgument);

  DetectorOptions copy = small_options(kExhaustiveSearch, 2, 4);
  copy.verification.stages = {kTemporalStage};  // sequence evidence over the search's row
  DetectorOptions original = copy;
  copy.search.mode = "test-copy";
  Detector a(copy), b(original);
  for (int i = 0; i < 60; ++i) {
    const cv::Mat f = random_frame(700 + i % 23);  // revisits
    const Result ra = a.process(f);
    const Result rb = b.process(f);
    expect_same_result(ra, rb);
  }

  DetectorOptions blocks = small_options("test-blocks", 2, 4);
  blocks.verification.stages = {kTemporalStage};  // realigned candidates, sampled statistics
  Detector c(blocks);
  for (int i = 0; i < 60; ++i) {
    const Result r = c.process(random_frame(700 + i % 23));
    EXPECT_EQ(r.node, i / 4);
    EXPECT_EQ(r.node_created, i % 4 == 0);
    for (const Candidate& k : r.candidates) EXPECT_LT(k.frame, i - 2);
  }
  EXPECT_EQ(c.nodes(), 15);
  EXPECT_EQ(c.search().members(3), (std::vector<std::int64_t>{12, 13, 14, 15}));
}

// The memory a map takes: each frame's descriptor and its mode's own model,
// a registered mode's included.
TEST(SearchModes, EstimatedMapBytesAddTheModesOwnMemoryModel) {
  register_test_modes();
  DetectorOptions o;
  const std::int64_t exact = static_cast<std::int64_t>(Descriptor::bytes_per_frame(HistogramStorage::kExact, 80));
  o.search.mode = kExhaustiveSearch;
  EXPECT_EQ(estimated_map_bytes(o, 1000, 80), 1000 * (exact + 8 * 48));
  o.search.mode = kNodesSearch;
  EXPECT_EQ(estimated_map_bytes(o, 1000, 80), 1000 * exact);
  o.search.mode = kIndexSearch;
  EXPECT_EQ(estimated_map_bytes(o, 1000, 80), 1000 * (exact + 16 * 80 + 8 * o.search.index.m + 64));
  o.search.mode = "test-blocks";
  EXPECT_EQ(estimated_map_bytes(o, 1000, 80), 1000 * (exact + 8 + 160));
  o.search.mode = "test-copy";  // no model: the descriptors alone
  EXPECT_EQ(estimated_map_bytes(o, 10, 80), 10 * exact);
  o.search.mode = "no-such-mode";
  EXPECT_THROW(estimated_map_bytes(o, 10, 80), InvalidArgument);
}

TEST(Detector, Deterministic) {
  for (const std::string mode : {kExhaustiveSearch, kNodesSearch}) {
    SCOPED_TRACE(mode);
    Detector a(small_options(mode, 2, 4)), b(small_options(mode, 2, 4));
    calibrate(a);
    calibrate(b);
    for (int i = 0; i < 14; ++i) {
      const cv::Mat f = random_frame(300 + i % 5);  // revisits
      const Result ra = a.process(f);
      const Result rb = b.process(f);
      expect_same_result(ra, rb);
    }
    EXPECT_EQ(a.nodes(), b.nodes());
  }
}

TEST(Detector, ExhaustiveAndNodesAgreeWhenOneNode) {
  DetectorOptions ex = small_options(kExhaustiveSearch, 0, 6);
  DetectorOptions dn = small_options(kNodesSearch, 0, 6);
  dn.search.nodes.alpha = 0;
  dn.search.nodes.beta = 0;
  Detector a(ex), b(dn);
  const int n = static_cast<int>(kMinCalibration) + 16;
  for (int i = 0; i < n; ++i) {
    SCOPED_TRACE(i);
    const cv::Mat f = random_frame(400 + (i * 7) % 45);
    const Result ra = a.process(f);
    const Result rb = b.process(f);
    EXPECT_EQ(ra.node, -1);
    EXPECT_EQ(rb.node, 0);
    EXPECT_EQ(rb.node_created, i == 0);
    EXPECT_EQ(ra.best.frame, rb.best.frame);
    EXPECT_EQ(ra.best.score, rb.best.score);
    ASSERT_EQ(ra.candidates.size(), rb.candidates.size());
    for (std::size_t k = 0; k < ra.candidates.size(); ++k) {
      EXPECT_EQ(ra.candidates[k].frame, rb.candidates[k].frame);
      EXPECT_EQ(ra.candidates[k].score, rb.candidates[k].score);
    }
    EXPECT_EQ(ra.loop, rb.loop);
  }
  EXPECT_EQ(a.nodes(), 0);
  EXPECT_EQ(b.nodes(), 1);
  EXPECT_EQ(b.search().members(0).size(), static_cast<std::size_t>(n));
}

TEST(Detector, OtherSizeThrowsAndLeavesDetectorUnchanged) {
  for (const std::string mode : {kExhaustiveSearch, kNodesSearch}) {
    SCOPED_TRACE(mode);
    Detector det(small_options(mode, 1, 5));
    Detector reference(small_options(mode, 1, 5));
    for (int i = 0; i < 3; ++i) {
      det.process(random_frame(500 + i));
      reference.process(random_frame(500 + i));
    }
    const std::int64_t nodes_before = det.nodes();
    // Other sizes, including the same pixel count transposed and a size with
    // the same grid (3 x 4 cells at S_p = 16).
    for (const auto& wh : {std::pair{kH, kW}, std::pair{kW + 1, kH}, std::pair{kW, kH - 1},
                           std::pair{80, 60}}) {
      const cv::Mat bad = random_frame(600, CV_8UC3, wh.first, wh.second);
      EXPECT_THROW(det.process(bad), InvalidArgument) << wh.first << "x" << wh.second;
      EXPECT_THROW(det.process(view_of_mat(bad)), InvalidArgument);
      EXPECT_EQ(det.size(), 3);
      EXPECT_EQ(det.store().size(), 3);
      EXPECT_EQ(det.nodes(), nodes_before);
    }
    // The next valid frame processes normally, exactly as if nothing happened.
    for (int i = 3; i < 6; ++i) {
      const Result r = det.process(random_frame(500 + i % 4));
      const Result want = reference.process(random_frame(500 + i % 4));
      EXPECT_EQ(r.frame, i);
      expect_same_result(r, want);
    }
    EXPECT_EQ(det.size(), 6);
  }
}

TEST(Detector, BadFormatThrowsAndLeavesDetectorUnchanged) {
  Detector det(small_options(kNodesSearch, 1, 5));
  Detector reference(small_options(kNodesSearch, 1, 5));
  for (int i = 0; i < 2; ++i) {
    det.process(random_frame(700 + i));
    reference.process(random_frame(700 + i));
  }
  const cv::Mat sixteen(kH, kW, CV_16UC1, cv::Scalar(30000));
  EXPECT_THROW(det.process(sixteen), InvalidArgument);
  EXPECT_THROW(det.process(cv::Mat(kH, kW, CV_32FC1, cv::Scalar(0.5))), InvalidArgument);
  EXPECT_THROW(det.process(cv::Mat(kH, kW, CV_8UC2, cv::Scalar(1, 2))), InvalidArgument);
  EXPECT_THROW(det.process(cv::Mat()), InvalidArgument);
  ImageView null_view;
  null_view.width = kW;
  null_view.height = kH;
  null_view.stride_bytes = kW;
  EXPECT_THROW(det.process(null_view), InvalidArgument);
  EXPECT_EQ(det.size(), 2);
  EXPECT_EQ(det.nodes(), reference.nodes());
  const Result r = det.process(random_frame(702));
  EXPECT_EQ(r.frame, 2);
  expect_same_result(r, reference.process(random_frame(702)));
}

TEST(Detector, RejectedFirstFrameLeavesDetectorEmpty) {
  Detector det(small_options());
  EXPECT_THROW(det.process(cv::Mat(kH, kW, CV_16UC1)), InvalidArgument);
  EXPECT_EQ(det.size(), 0);
  EXPECT_EQ(det.process(random_frame(1, CV_8UC3, 50, 40)).frame, 0);
  // The size is fixed by the first accepted frame.
  EXPECT_THROW(det.process(random_frame(2)), InvalidArgument);
  EXPECT_EQ(det.process(random_frame(3, CV_8UC1, 50, 40)).frame, 1);
}

TEST(Detector, ResultFields) {
  DetectorOptions o = small_options(kExhaustiveSearch, 2, 3);
  o.decision.threshold = 2.5;
  Detector det(o);
  const int calibrated = 2 + static_cast<int>(kMinCalibration);  // the first query with statistics
  // A young query (fewer candidates) is standardised with the prior: every
  // similarity of the young queries so far, its own included, once they are
  // kMinCalibration or more (queries 3 .. 10 have 1 .. 8 candidates: 36).
  const int prior = 10;
  for (int i = 0; i < calibrated + 10; ++i) {
    SCOPED_TRACE(i);
    const Result r = det.process(random_frame(800 + i % 20));  // revisits every 20 frames
    EXPECT_EQ(r.frame, i);
    EXPECT_EQ(det.size(), i + 1);
    EXPECT_EQ(r.candidates.size(), i >= prior ? 3u : 0u);
    if (r.candidates.empty()) {
      EXPECT_EQ(r.best.frame, -1);
      EXPECT_FALSE(r.loop);
      EXPECT_TRUE(std::isnan(r.evidence.appearance));
    } else {
      EXPECT_EQ(r.best.frame, r.candidates[0].frame);
      EXPECT_EQ(r.evidence.appearance, r.candidates[0].score);
      EXPECT_EQ(r.evidence.inliers, -1);
      EXPECT_FALSE(r.evidence.confirmed);
      if (i >= calibrated) {
        EXPECT_EQ(r.best.score, r.candidates[0].score);
        EXPECT_EQ(r.loop, r.best.score >= 2.5);
      } else {
        // On the prior and appearance alone: never a loop.
        EXPECT_EQ(r.best.score, std::min(r.candidates[0].score, std::nextafter(2.5, -1.0)));
        EXPECT_FALSE(r.loop);
      }
    }
    // Scores are the similarities standardised over every candidate (a
    // young query: over the young queries' candidates so far).
    std::vector<double> values;
    for (int q = i >= calibrated ? i : 3; q <= i; ++q) {
      for (int j = 0; j < q - 2; ++j) values.push_back(det.similarity(q, j));
    }
    double sum = 0, squares = 0;
    for (const double v : values) sum += v;
    const double mean = sum / std::max<double>(1, values.size());
    for (const double v : values) squares += std::pow(v - mean, 2);
    const double sd = std::sqrt(squares / std::max<double>(1, values.size()));
    for (std::size_t k = 0; k < r.candidates.size(); ++k) {
      EXPECT_LT(r.candidates[k].frame, i - 2);
      EXPECT_NEAR(r.candidates[k].score, (det.similarity(i, r.candidates[k].frame) - mean) / sd,
                  1e-9);
      if (k > 0) {
        EXPECT_TRUE(better(r.candidates[k - 1], r.candidates[k]));
      }
    }
    EXPECT_EQ(r.node, -1);
    EXPECT_FALSE(r.node_created);
    const Timings& t = r.timings;
    EXPECT_GE(t.convert_ms, 0.0);
    EXPECT_GE(t.segment_ms, 0.0);
    EXPECT_GE(t.describe_ms, 0.0);
    EXPECT_GE(t.search_ms, 0.0);
    EXPECT_GE(t.total_ms, t.segment_ms);
    EXPECT_GE(t.total_ms + 1e-9, t.convert_ms + t.segment_ms + t.describe_ms + t.search_ms);
    if (i >= calibrated) {
      // Revisits (period 20) beyond the window are exact matches, best first.
      EXPECT_EQ((i - r.best.frame) % 20, 0);
      EXPECT_EQ(det.similarity(i, r.best.frame), 1.0);
    }
  }
  EXPECT_EQ(det.nodes(), 0);
}

// A loop is declared exactly when the score reaches the threshold.
TEST(Detector, LoopDecisionThresholdBoundaries) {
  const auto scores = [](double threshold) {
    DetectorOptions o = small_options(kExhaustiveSearch, 0, 1);
    o.decision.threshold = threshold;
    Detector det(o);
    calibrate(det);
    std::vector<Result> out;
    for (int i = 0; i < 6; ++i) out.push_back(det.process(random_frame(5000 + i)));  // revisits
    return out;
  };
  const auto base = scores(7.0);
  for (std::size_t i = 0; i < base.size(); ++i) {
    SCOPED_TRACE(i);
    const double s = base[i].best.score;
    ASSERT_GT(s, 0.0);
    EXPECT_TRUE(scores(s)[i].loop);  // score >= threshold
    EXPECT_FALSE(scores(std::nextafter(s, 2 * s))[i].loop);
    EXPECT_EQ(scores(s)[i].best.score, s);  // the threshold does not change the score
  }
}

TEST(Detector, NodeModeReportsNodes) {
  DetectorOptions o = small_options(kNodesSearch, 2, 5);
  Detector det(o);
  std::int64_t created = 0;
  for (int i = 0; i < 15; ++i) {
    const Result r = det.process(random_frame(1000 + i % 5));
    EXPECT_GE(r.node, 0);
    EXPECT_LT(r.node, det.nodes());
    if (i == 0) {
      EXPECT_TRUE(r.node_created);
      EXPECT_EQ(r.node, 0);
    }
    if (r.node_created) {
      ++created;
      EXPECT_EQ(r.node, det.nodes() - 1);
      EXPECT_TRUE(r.candidates.empty());
    }
    for (const Candidate& c : r.candidates) EXPECT_LT(c.frame, i - 2);
  }
  EXPECT_EQ(det.nodes(), created);
  EXPECT_EQ(det.search().groups(), created);
  EXPECT_EQ(det.store().groups(), created);  // each node's frames placed together
}

TEST(Detector, ImageViewAndMatGiveIdenticalResults) {
  Detector by_mat(small_options(kExhaustiveSearch, 1, 4));
  Detector by_view(small_options(kExhaustiveSearch, 1, 4));
  for (int i = 0; i < 8; ++i) {
    const int type = i % 3 == 0 ? CV_8UC1 : i % 3 == 1 ? CV_8UC3 : CV_8UC4;
    const cv::Mat f = random_frame(1100 + i % 3, type);
    const Result rm = by_mat.process(f);
    // Padded copy of the same pixels.
    cv::Mat big(kH, kW + 7, type, cv::Scalar::all(3));
    f.copyTo(big(cv::Rect(0, 0, kW, kH)));
    const Result rv = by_view.process(view_of_mat(big(cv::Rect(0, 0, kW, kH))));
    expect_same_result(rm, rv);
  }
  // RGB view of the same image equals the BGR Mat.
  const cv::Mat bgr = random_frame(1200);
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  ImageView v = view_of_mat(rgb);
  v.format = PixelFormat::kRgb8;
  expect_same_result(by_mat.process(bgr), by_view.process(v));
}

TEST(Detector, MemoryPerFrame) {
  Detector det(small_options());
  EXPECT_EQ(det.size(), 0);
  for (int i = 0; i < 5; ++i) {
    det.process(random_frame(1300 + i));
    EXPECT_EQ(det.size(), i + 1);
    EXPECT_EQ(det.store().size(), i + 1);
  }
  const GridSize g = grid_size(kW, kH, 16);
  EXPECT_EQ(g, (GridSize{3, 4}));
  EXPECT_EQ(det.store().grid(), g);
  // 16-bit bins and a 32-bit pixel count per cell.
  EXPECT_EQ(det.bytes_per_frame(), static_cast<std::size_t>(g.cells()) * (256 * 2 + 4));
  EXPECT_EQ(det.bytes_per_frame(), 12u * 516u);
  // KITTI-sized frames at S_p = 40: 80 cells.
  DetectorOptions ko;
  ko.segmentation.superpixel_size = 40;
  Detector kitti(ko);
  kitti.process(cv::Mat(376, 1241, CV_8UC1, cv::Scalar(90)));
  EXPECT_EQ(kitti.bytes_per_frame(), 80u * 516u);  // 41,280 bytes
}

TEST(Detector, SimilarityAccessor) {
  Detector det(small_options());
  for (int i = 0; i < 4; ++i) det.process(random_frame(1400 + i));
  for (int a = 0; a < 4; ++a) {
    EXPECT_EQ(det.similarity(a, a), 1.0);
    for (int b = 0; b < 4; ++b) {
      EXPECT_EQ(det.similarity(a, b), det.similarity(b, a));
      EXPECT_EQ(det.similarity(a, b),
                lsgd::similarity(det.store().view(a), det.store().view(b),
                                 SimilarityMetric::kReference));
    }
  }
  EXPECT_THROW(det.similarity(0, 4), InvalidArgument);
  EXPECT_THROW(det.similarity(-1, 0), InvalidArgument);
}

TEST(Detector, OptionsValidatedAtConstruction) {
  DetectorOptions o;
  o.decision.threshold = 0;
  EXPECT_THROW(o.check(), InvalidArgument);
  EXPECT_THROW(Detector{o}, InvalidArgument);
  const std::string msg = message_of<InvalidArgument>([&] { Detector d(o); });
  EXPECT_NE(msg.find("threshold"), std::string::npos) << msg;
  o.decision.threshold = 1001;
  EXPECT_THROW(Detector{o}, InvalidArgument);
  o = DetectorOptions{};
  o.verification.geometric_options.min_side = 300;  // above max_side 240
  EXPECT_NE(message_of<InvalidArgument>([&] { Detector d(o); }).find("max_side"),
            std::string::npos);
  o = DetectorOptions{};
  o.segmentation.superpixel_size = 1;
  EXPECT_THROW(Detector{o}, InvalidArgument);
  o = DetectorOptions{};
  o.search.top_n = 0;
  EXPECT_THROW(Detector{o}, InvalidArgument);
  o = DetectorOptions{};
  o.search.nodes.beta = -1;
  EXPECT_THROW(Detector{o}, InvalidArgument);
  o = DetectorOptions{};
  o.similarity.metric = static_cast<SimilarityMetric>(5);
  EXPECT_THROW(Detector{o}, InvalidArgument);
  // Defaults are valid and kept.
  Detector d;
  EXPECT_NO_THROW(d.options().check());
  EXPECT_EQ(d.size(), 0);
  EXPECT_EQ(d.nodes(), 0);
}

// One Detector shared by two threads (issue 15: SIGSEGV, heap-use-after-free
// under ASan): an overlapping call throws InvalidArgument instead of
// corrupting the detector; every call either completes or is refused, and the
// detector holds exactly the frames that completed. (Run under ASan/UBSan by
// scripts/ci-hardening.sh.)
TEST(Detector, TwoThreadsOnOneDetectorAreRefusedNotCorrupted) {
  DetectorOptions o = small_options(kNodesSearch, 2, 5);
  Detector det(o);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 8; ++i) frames.push_back(random_frame(700 + i, CV_8UC3, 320, 240));
  std::atomic<int> done{0}, refused{0};
  std::atomic<bool> go{false};
  const auto worker = [&](int offset) {
    while (!go) std::this_thread::yield();
    for (int i = 0; i < 40; ++i) {
      try {
        det.process(frames[static_cast<std::size_t>((i + offset) % 8)]);
        ++done;
      } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("one thread at a time"), std::string::npos)
            << e.what();
        ++refused;
      }
    }
  };
  std::thread a(worker, 0), b(worker, 3);
  go = true;
  a.join();
  b.join();
  EXPECT_EQ(done + refused, 80);
  EXPECT_EQ(det.size(), done.load());
  // Still a working detector.
  const Result r = det.process(frames[0]);
  EXPECT_EQ(r.frame, done.load());
}

// Result::status says why there is a loop or none, consistently with the
// rest of the Result, and every status occurs on the street's revisits.
TEST(Detector, StatusSaysWhyThereIsALoopOrNone) {
  std::map<LoopStatus, int> seen;
  for (const int agree : {0, 3}) {
    DetectorOptions o;
    o.search.min_gap = 20;
    o.verification.temporal_options.agree = agree;  // 3: the temporal gate examines
    Detector d(o);
    for (std::int64_t i = 0; i < test::world().frames(); ++i) {
      const Result r = d.process(test::frame(i));
      ++seen[r.status];
      SCOPED_TRACE("frame " + std::to_string(i) + " " + to_string(r.status));
      EXPECT_EQ(r.loop, r.status == LoopStatus::kLoop);
      EXPECT_EQ(i <= o.search.min_gap, r.status == LoopStatus::kTooFewFrames);
      if (r.status == LoopStatus::kNoCandidate) {
        EXPECT_TRUE(r.candidates.empty());
      }
      if (r.status == LoopStatus::kGated) {
        EXPECT_EQ(r.best.frame, -1);
        for (const StageVerdict& v : r.verification) EXPECT_FALSE(v.accepted);
      }
      if (r.status == LoopStatus::kNotConfirmed || r.status == LoopStatus::kBelowThreshold) {
        EXPECT_GE(r.best.frame, 0);
        EXPECT_LT(r.best.score, o.decision.threshold);
      }
      if (r.status == LoopStatus::kNotConfirmed) {
        EXPECT_FALSE(r.evidence.confirmed);
      }
    }
  }
  for (const LoopStatus s : {LoopStatus::kLoop, LoopStatus::kTooFewFrames, LoopStatus::kNoCandidate,
                             LoopStatus::kGated, LoopStatus::kYoung, LoopStatus::kNotConfirmed,
                             LoopStatus::kBelowThreshold}) {
    EXPECT_GT(seen[s], 0) << to_string(s);
    EXPECT_EQ(parse_loop_status(to_string(s)), s);
  }
  EXPECT_NE(test::message_of<InvalidArgument>([] { parse_loop_status("looped"); })
                .find("loop status 'looped' is not one of loop, too_few_frames"),
            std::string::npos);
}

// Result::geometry: the reported candidate's matches and model whenever the
// geometric stage fitted one, consistent with its inliers; none without it.
TEST(Detector, ALoopCarriesItsGeometry) {
  for (const char* stages : {"temporal,geometric", "temporal"}) {
    DetectorOptions o;
    o.search.min_gap = 20;
    parse_verification_stages(stages, o.verification);
    Detector d(o);
    int loops = 0;
    for (std::int64_t i = 0; i < test::world().frames(); ++i) {
      const Result r = d.process(test::frame(i));
      SCOPED_TRACE(std::string(stages) + ", frame " + std::to_string(i));
      if (std::string(stages) == "temporal") {
        EXPECT_EQ(r.geometry, nullptr);
        continue;
      }
      loops += r.loop ? 1 : 0;
      if (r.loop) {
        ASSERT_NE(r.geometry, nullptr);
      }
      if (r.geometry == nullptr) continue;
      EXPECT_GE(r.best.frame, 0);
      EXPECT_EQ(std::count(r.geometry->inliers.begin(), r.geometry->inliers.end(), 1), r.evidence.inliers);
      EXPECT_EQ(r.geometry->query_points.size(), 2 * r.geometry->matches());
      EXPECT_TRUE(r.geometry->model == "fundamental" || r.geometry->model == "homography");
    }
    if (std::string(stages) != "temporal") {
      EXPECT_GT(loops, 10);
    }
  }
}

// The caller's ids and stamps: carried into the Result, mapped both ways,
// continued when not given, and refused (detector unchanged) when not
// increasing or not finite.
TEST(Detector, CallersIdsAndStamps) {
  DetectorOptions o;
  o.search.min_gap = 20;
  Detector d(o);
  std::int64_t loops = 0;
  for (std::int64_t i = 0; i < test::world().frames(); ++i) {
    const bool given = i < 150;
    const Result r = given ? d.process(test::frame(i), 10 * i + 7, 0.1 * static_cast<double>(i))
                           : d.process(test::frame(i));
    const std::int64_t id = given ? 10 * i + 7 : 10 * 149 + 7 + (i - 149);
    EXPECT_EQ(r.frame, i);
    EXPECT_EQ(r.id, id);
    EXPECT_EQ(d.id_of(i), id);
    EXPECT_EQ(d.frame_of(id), i);
    if (given) {
      EXPECT_EQ(r.stamp, 0.1 * static_cast<double>(i));
    } else {
      EXPECT_TRUE(std::isnan(r.stamp));
    }
    EXPECT_EQ(r.loop_id, r.best.frame >= 0 ? d.id_of(r.best.frame) : -1);
    loops += r.loop ? 1 : 0;
  }
  EXPECT_GT(loops, 0);
  const std::int64_t n = d.size(), last = d.id_of(n - 1);
  for (const auto& [id, stamp] : {std::pair<std::int64_t, double>{last, 0.0}, {last - 5, 0.0}, {-2, 0.0},
                                  {last + 1, std::numeric_limits<double>::infinity()}}) {
    EXPECT_THROW(d.process(test::frame(0), id, stamp), InvalidArgument) << id;
    EXPECT_EQ(d.size(), n);
  }
  EXPECT_NE(test::message_of<InvalidArgument>([&] { d.process(test::frame(0), last); })
                .find("frame id " + std::to_string(last) + " must be above the last frame's id"),
            std::string::npos);
  EXPECT_EQ(d.frame_of(-1), -1);
  EXPECT_THROW(d.id_of(n), InvalidArgument);
  // A query carries the id it was given, and changes nothing.
  const Result q = d.query(test::frame(5), last + 100, 9.5);
  EXPECT_EQ(q.id, last + 100);
  EXPECT_EQ(q.stamp, 9.5);
  EXPECT_EQ(d.process(test::frame(5)).id, last + 1);
}

// describe(): the descriptor process() stores, with nothing stored, in both storages.
TEST(Detector, DescribeGivesTheStoredDescriptorAndStoresNothing) {
  for (const HistogramStorage storage : {HistogramStorage::kExact, HistogramStorage::kCompact}) {
    DetectorOptions o = small_options();
    o.descriptor.storage = storage;
    Detector d(o);
    for (int i = 0; i < 5; ++i) {
      const cv::Mat f = random_frame(900 + i);
      const Descriptor x = d.describe(f);
      EXPECT_EQ(d.size(), i);
      d.process(f);
      const DescriptorView stored = d.store().view(i), own = x.view();
      ASSERT_EQ(own.cells, stored.cells);
      if (storage == HistogramStorage::kCompact) {
        EXPECT_TRUE(std::equal(own.compact, own.compact + own.cells * kCompactBins, stored.compact));
      } else {
        EXPECT_TRUE(std::equal(own.hist, own.hist + own.cells * kBins, stored.hist));
        EXPECT_TRUE(std::equal(own.pixels, own.pixels + own.cells, stored.pixels));
      }
      EXPECT_EQ(similarity(own, stored, o.similarity.metric), similarity(stored, stored, o.similarity.metric));
    }
    EXPECT_THROW(d.describe(random_frame(1, CV_8UC3, kW * 2, kH)), InvalidArgument);
  }
}

}  // namespace
}  // namespace lsgd
