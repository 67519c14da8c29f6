// Tests of the online detector (include/lsgd/detector.h): frame ids, self
// matches, determinism, agreement of the two search modes, rejection of bad
// frames without side effects, result fields, memory accounting. A search
// mode registered from outside: detector_modes_test.cc; threads, status,
// geometry, the caller's ids and describe(): detector_results_test.cc.
#include "lsgd/detector.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "lsgd/error.h"
#include "lsgd/image.h"
#include "detector_test_support.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::message_of;
using detector_test_support::calibrate;
using detector_test_support::expect_same_result;
using detector_test_support::kH;
using detector_test_support::kW;
using detector_test_support::random_frame;
using detector_test_support::small_options;

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
  // KITTI-sized frames at S_p = 40: 80 cells at their own size, 40 at the
  // default working size (792 x 240).
  DetectorOptions ko;
  ko.segmentation.superpixel_size = 40;
  ko.segmentation.working_side = 0;
  Detector kitti(ko);
  kitti.process(cv::Mat(376, 1241, CV_8UC1, cv::Scalar(90)));
  EXPECT_EQ(kitti.bytes_per_frame(), 80u * 516u);  // 41,280 bytes
  Detector scaled{DetectorOptions{}};
  scaled.process(cv::Mat(376, 1241, CV_8UC1, cv::Scalar(90)));
  EXPECT_EQ(scaled.bytes_per_frame(), 40u * 516u);
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

}  // namespace
}  // namespace lsgd
