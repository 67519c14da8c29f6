// Tests of the evaluation runner (eval/runner.h): frame ids, skipping bad frames.
#include "lsgd/eval/runner.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <set>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "test_util.h"

namespace lsgd::eval {
namespace {

// Ten frames; frame i shows noise pattern i % 3, so frames 3 apart are
// identical. Frame 2 cannot be read and frame 5 has another size.
FrameSource flawed_source() {
  FrameSource source;
  source.frames = 10;
  source.load = [](std::int64_t i) -> cv::Mat {
    if (i == 2) throw FormatError("image 'f2.png' is truncated");
    if (i == 5) return cv::Mat(32, 32, CV_8UC1, cv::Scalar(7));
    const GrayImage g = test::random_image(64, 48, static_cast<std::uint64_t>(i % 3) + 1);
    return cv::Mat(48, 64, CV_8UC1, const_cast<std::uint8_t*>(g.pixels.data())).clone();
  };
  source.name = [](std::int64_t i) { return "f" + std::to_string(i) + ".png"; };
  return source;
}

DetectorOptions options() {
  DetectorOptions o;
  o.segmentation.superpixel_size = 16;
  o.search.min_gap = 0;
  o.search.top_n = 20;
  o.verification.temporal = false;
  return o;
}

TEST(RunDetector, StopsAtTheFirstBadFrameByDefault) {
  Detector detector(options());
  std::vector<std::int64_t> seen;
  const std::string e = test::message_of<FormatError>([&] {
    run_detector(detector, flawed_source(),
                 [&](const Result& r, double) { seen.push_back(r.frame); });
  });
  EXPECT_NE(e.find("frame 2 (f2.png)"), std::string::npos) << e;
  EXPECT_EQ(seen, (std::vector<std::int64_t>{0, 1}));  // frames before the error were passed on
}

TEST(RunDetector, SkipsBadFramesAndKeepsSourceIndices) {
  Detector detector(options());
  std::vector<std::int64_t> skipped;
  std::vector<std::string> errors;
  RunOptions run;
  run.skip_bad_frames = true;
  const auto records =
      run_detector(detector, flawed_source(), {}, run,
                   [&](std::int64_t frame, const std::string& name, const std::string& error) {
                     skipped.push_back(frame);
                     errors.push_back(name + ": " + error);
                   });
  EXPECT_EQ(skipped, (std::vector<std::int64_t>{2, 5}));
  EXPECT_NE(errors[0].find("f2.png: image 'f2.png' is truncated"), std::string::npos);
  EXPECT_NE(errors[1].find("f5.png"), std::string::npos);
  EXPECT_NE(errors[1].find("size"), std::string::npos) << errors[1];
  EXPECT_EQ(detector.size(), 8);  // the skipped frames never reached the detector
  ASSERT_EQ(records.size(), 10u);
  for (std::int64_t i = 0; i < 10; ++i) {
    EXPECT_EQ(records[i].frame, i);
    EXPECT_EQ(records[i].skipped, i == 2 || i == 5);
  }
  EXPECT_EQ(records[2].reported.frame, -1);
  // Frame 7 shows pattern 1, as frames 1 and 4 do: its identical candidates
  // are named by source index (4), not by detector id (3).
  std::set<std::int64_t> identical;
  for (const Candidate& c : records[7].candidates) {
    if (c.score == 1.0) identical.insert(c.frame);
  }
  EXPECT_EQ(identical, (std::set<std::int64_t>{1, 4}));
  EXPECT_EQ(records[7].reported.frame, 1);  // ties go to the older frame
  identical.clear();  // frame 9, pattern 0: frames 0, 3 and 6 (detector ids 0, 2, 4)
  for (const Candidate& c : records[9].candidates) {
    if (c.score == 1.0) identical.insert(c.frame);
  }
  EXPECT_EQ(identical, (std::set<std::int64_t>{0, 3, 6}));
}

}  // namespace
}  // namespace lsgd::eval
