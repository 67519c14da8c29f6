// Helpers of the tests of the online detector (detector_test,
// detector_modes_test, detector_results_test): textured random frames, small
// options, calibration and results compared. Header-only.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "lsgd/detector.h"
#include "test_util.h"

namespace lsgd::detector_test_support {

using test::splitmix64;

inline constexpr int kW = 96;
inline constexpr int kH = 64;

// Textured random frame: a smooth random gradient plus noise, so frames from
// different seeds differ but are not pure noise.
inline cv::Mat random_frame(std::uint64_t seed, int type = CV_8UC3, int width = kW,
                            int height = kH) {
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

inline DetectorOptions small_options(const std::string& mode = kExhaustiveSearch,
                                     std::int64_t min_gap = 3, int top_n = 5) {
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
inline void calibrate(Detector& det, int n = static_cast<int>(kMinCalibration) + 4) {
  for (int i = 0; i < n; ++i) det.process(random_frame(5000 + i));
}

inline void expect_same_result(const Result& a, const Result& b) {
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

}  // namespace lsgd::detector_test_support
