// The HTML evaluation report written to a file (include/lsgd/eval/report.h):
// atomically and equal to the rendered text, and rendered by a real headless
// Chromium when one is installed.
#include "lsgd/eval/report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "report_test_support.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace lsgd::eval {
namespace {

using report_test_support::heatmap;
using report_test_support::run;
using report_test_support::StreetRun;

class ReportFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::path(LSGD_TEST_TMP) / ("report-" + std::to_string(getpid()) + "-" +
                                   ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(ReportFile, WriteIsAtomicAndEqualsRender) {
  // Hand-made records and a made-up similarity: writing needs no detector run.
  GroundTruth gt(60);
  for (std::int64_t q = 40; q < 60; ++q) gt.add(q, q - 40);
  std::vector<FrameRecord> records(60);
  for (std::int64_t q = 0; q < 60; ++q) {
    records[static_cast<std::size_t>(q)].frame = q;
    if (q >= 40) records[static_cast<std::size_t>(q)].reported = {q - 40 + q % 3, 0.9};
  }
  const Metrics metrics = evaluate(records, gt, 10);
  ReportInput in;
  in.metrics = &metrics;
  in.records = &records;
  in.gt = &gt;
  in.similarity = [](std::int64_t a, std::int64_t b) {
    return 1.0 / (1.0 + std::abs(static_cast<double>((a - b) % 40)));
  };
  in.max_matrix_frames = 40;
  const fs::path path = dir_ / "a <report> & \"x\".html";
  write_report(in, path.string());
  ASSERT_FALSE(heatmap(render_report(in)).empty());
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  EXPECT_EQ(text.str(), render_report(in));
  EXPECT_FALSE(fs::exists(path.string() + ".tmp"));
  const std::string missing = (dir_ / "no such folder" / "r.html").string();
  EXPECT_NE(test::message_of<IoError>([&] { write_report(in, missing); }).find(missing),
            std::string::npos);
}

// Renders the report in headless Chromium and checks the screenshot: the PR
// curve's area is drawn and the heat-map's colours are on the page.
TEST_F(ReportFile, RendersInHeadlessChromium) {
  const char* chromium = "/usr/bin/chromium";
  if (!fs::exists(chromium)) GTEST_SKIP() << chromium << " is absent: no browser rendering test";
  const StreetRun& r = run();
  ReportInput in = r.input();
  in.threshold = r.options.decision.threshold;
  in.trajectory = r.trajectory;
  const fs::path html = dir_ / "report.html", png = dir_ / "shot.png", profile = dir_ / "profile";
  write_report(in, html.string());
  fs::create_directories(profile);
  const std::string cmd =
      std::string("timeout 60 ") + chromium +
      " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
      " --disable-background-networking --disable-component-update --disable-sync"
      " --hide-scrollbars --user-data-dir='" +
      profile.string() + "' --window-size=1200,2000 --screenshot='" + png.string() + "' 'file://" +
      html.string() + "' >'" + (dir_ / "log.txt").string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_EQ(status, 0) << cmd;
  const cv::Mat shot = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(shot.empty()) << "no screenshot at " << png;
  ASSERT_EQ(shot.cols, 1200);
  if (const char* keep = std::getenv("LSGD_REPORT_SCREENSHOT")) cv::imwrite(keep, shot);
  // The PR chart (560 x 440) starts under the header, at the left of the page.
  const cv::Mat pr = shot(cv::Rect(10, 260, 580, 460));
  int ink = 0, curve = 0;
  for (int y = 0; y < pr.rows; ++y) {
    for (int x = 0; x < pr.cols; ++x) {
      const cv::Vec3b p = pr.at<cv::Vec3b>(y, x);
      ink += p[0] < 200 || p[1] < 200 || p[2] < 200;
      curve += p[0] > 180 && p[2] < 80 && p[1] > 60 && p[1] < 140;  // #2563eb
    }
  }
  EXPECT_GT(ink, 3000) << "the PR chart area is nearly blank";
  EXPECT_GT(curve, 200) << "the PR curve's blue is missing";
  // The heat-map: cividis blue and yellow, and the magenta GT outline.
  int navy = 0, yellow = 0, magenta = 0;
  for (int y = 0; y < shot.rows; ++y) {
    for (int x = 0; x < shot.cols; ++x) {
      const cv::Vec3b p = shot.at<cv::Vec3b>(y, x);
      navy += p[0] > 90 && p[2] < 60 && p[1] < 90;
      yellow += p[2] > 180 && p[1] > 160 && p[0] < 110;
      magenta += p[2] > 220 && p[0] > 220 && p[1] < 40;
    }
  }
  EXPECT_GT(navy, 5000);
  EXPECT_GT(yellow, 300);
  EXPECT_GT(magenta, 300);
}

}  // namespace
}  // namespace lsgd::eval
