// The route of synthetic places the verification tests run the Detector
// on (verification_test.cc, stage_interface_test.cc).
#pragma once

#include <algorithm>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/verification.h"
#include "test_util.h"

namespace lsgd::test {

// A route through 30 places, then the same places again. Place p is noise over
// its own 8 random gray levels, so unrelated places share almost no histogram
// bin; frame i of the route is place i % 30 shifted by i / 30 pixels, so a
// revisit is a slightly moved view (geometry fits it) rather than a copy.
inline cv::Mat place(int p, int shift = 0) {
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

inline constexpr int kPlaces = 60;

inline std::vector<Result> run(const DetectorOptions& options, int laps = 2) {
  Detector detector(options);
  std::vector<Result> results;
  for (int i = 0; i < laps * kPlaces; ++i) {
    results.push_back(detector.process(place(i % kPlaces, i / kPlaces)));
  }
  return results;
}

inline DetectorOptions route_options(const char* stages) {
  DetectorOptions options;
  options.search.min_gap = 10;
  options.verification.temporal_options.frames = 4;
  options.verification.temporal_options.long_frames = 8;
  parse_verification_stages(stages, options.verification);
  return options;
}

}  // namespace lsgd::test
