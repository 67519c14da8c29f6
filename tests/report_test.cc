// The HTML evaluation report: structure, the embedded PNG, escaping, the
// optional sections, errors, and a real headless-browser rendering. This
// file: structure, header, PR curve, heatmap, loops and warnings, trajectory
// and timeline; thumbnails, compared systems, escaping, external detections
// and errors: report_inputs_test.cc; the written file and the browser:
// report_file_test.cc.
#include "lsgd/eval/report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "report_test_support.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace lsgd::eval {
namespace {

using report_test_support::count;
using report_test_support::heatmap;
using report_test_support::kMinGap;
using report_test_support::run;
using report_test_support::StreetRun;
using report_test_support::tag_balance_error;

// The value of the first attribute `name='...'` after `from`.
std::string attribute(const std::string& html, std::size_t from, const std::string& name) {
  const std::string key = name + "='";
  const std::size_t start = html.find(key, from);
  if (start == std::string::npos) return "";
  const std::size_t begin = start + key.size();
  return html.substr(begin, html.find('\'', begin) - begin);
}

TEST(Report, IsWellFormedAndSelfContained) {
  const std::string html = render_report(run().input());
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_EQ(tag_balance_error(html), "");
  EXPECT_EQ(count(html, "http://"), 0u);
  EXPECT_EQ(count(html, "https://"), 0u);
  EXPECT_EQ(count(html, "<script"), 0u);
  EXPECT_EQ(count(html, "<link"), 0u);
  EXPECT_EQ(count(html, "@import"), 0u);
  // Every href/src is inline data or a fragment of this page.
  for (const char* key : {"href='", "src='", "href=\"", "src=\""}) {
    for (std::size_t p = html.find(key); p != std::string::npos; p = html.find(key, p + 1)) {
      const std::string value = html.substr(p + std::strlen(key), 5);
      EXPECT_TRUE(value == "data:" || value[0] == '#') << key << value;
    }
  }
}

TEST(Report, HeaderTimingAndConfigurationShowTheRun) {
  const StreetRun& r = run();
  const std::string html = render_report(r.input());
  for (const char* text : {"synthetic/street.txt", "synthetic/groundtruth.txt", "strict",
                           "w = 20 frames", "mode exhaustive", "verification temporal", "R@100P",
                           "P@100R", ">AP<", "R@1<", "R@5<", "R@10<", "PRT"}) {
    EXPECT_NE(html.find(text), std::string::npos) << text;
  }
  std::ostringstream frames;
  frames << r.metrics.frames << " evaluated of " << r.world.frames() << "; " << r.metrics.positives
         << " positives";
  EXPECT_NE(html.find(frames.str()), std::string::npos) << frames.str();
  char ap[32];
  std::snprintf(ap, sizeof ap, "%.1f&#8239;%%", 100 * r.metrics.average_precision);
  EXPECT_NE(html.find(ap), std::string::npos) << ap;
  EXPECT_NE(html.find("<pre>"), std::string::npos);
  EXPECT_NE(html.find("superpixel_size"), std::string::npos);  // the configuration
  // The timing table: medians from the metrics, p95 from the records.
  std::vector<double> totals;
  for (const FrameRecord& f : r.records) totals.push_back(f.timings.total_ms);
  char row[96];
  std::snprintf(row, sizeof row, "<td>process() total</td><td>%.3f</td><td>%.3f</td>",
                r.metrics.ms_per_frame_median, percentile(totals, 0.95));
  EXPECT_NE(html.find(row), std::string::npos) << row;
  EXPECT_NE(
      html.find("<td>bytes per frame</td><td>" + std::to_string(r.detector->bytes_per_frame())),
      std::string::npos);
  EXPECT_NE(html.find("<td>dynamic nodes</td>"), std::string::npos);
}

TEST(Report, PrCurveHasOnePointPerSweepPoint) {
  // The fixture must exercise the charts: positives, reported loops, a sweep.
  const StreetRun& r = run();
  EXPECT_GT(r.metrics.positives, 10);
  ASSERT_GT(r.metrics.curve.size(), 5u);
  EXPECT_GT(r.metrics.recall_at_100_precision, 0.0);
  const std::string html = render_report(r.input());
  ASSERT_EQ(count(html, "<svg class='pr'"), 1u);
  const std::size_t svg = html.find("<svg class='pr'");
  const std::size_t polyline = html.find("<polyline class='pr-curve'", svg);
  ASSERT_NE(polyline, std::string::npos);
  ASSERT_LT(polyline, html.find("</svg>", svg));
  std::istringstream points(attribute(html, polyline, "points"));
  std::string point;
  std::size_t n = 0;
  while (points >> point) {
    double x = 0, y = 0;
    ASSERT_EQ(std::sscanf(point.c_str(), "%lf,%lf", &x, &y), 2) << point;
    const PrPoint& p = r.metrics.curve[n];
    EXPECT_NEAR(x, 70 + 470 * p.recall, 0.01) << "point " << n;      // the plot area: x 70..540
    EXPECT_NEAR(y, 380 - 360 * p.precision, 0.01) << "point " << n;  // y 380..20
    ++n;
  }
  EXPECT_EQ(n, r.metrics.curve.size());
  EXPECT_NE(html.find("R@100P"), std::string::npos);  // the marked point's legend
  EXPECT_NE(html.find(">recall</text>"), std::string::npos);
  EXPECT_NE(html.find(">precision</text>"), std::string::npos);
}

TEST(Report, HeatmapIsAPngOfTheSampledMatrixWithOverlays) {
  const StreetRun& r = run();
  ReportInput in = r.input();
  in.max_matrix_frames = 100;  // fewer than the frames: sampled
  ASSERT_GT(r.world.frames(), 100);
  std::int64_t calls = 0;
  const auto similarity = in.similarity;
  in.similarity = [&](std::int64_t a, std::int64_t b) {
    ++calls;
    EXPECT_NE(a, b);
    return similarity(a, b);
  };
  const std::string html = render_report(in);
  EXPECT_EQ(calls, 100 * 99 / 2);
  const cv::Mat png = heatmap(html);
  ASSERT_FALSE(png.empty()) << "no decodable PNG data URI";
  EXPECT_EQ(png.cols, 600);  // 100 cells, upscaled 6x to 600 pixels
  EXPECT_EQ(png.rows, 600);
  EXPECT_NE(html.find("100 of " + std::to_string(r.world.frames()) + " frames sampled uniformly"),
            std::string::npos);
  // GT loops outside the window are outlined in magenta; the similarity is a
  // colour map (blue-ish dark, yellow-ish bright).
  int magenta = 0, blue = 0, yellow = 0;
  for (int y = 0; y < png.rows; ++y) {
    for (int x = 0; x < png.cols; ++x) {
      const cv::Vec3b p = png.at<cv::Vec3b>(y, x);  // BGR
      magenta += p == cv::Vec3b(255, 0, 255);
      blue += p[0] > p[2] + 40;
      yellow += p[2] > p[0] + 80 && p[1] > p[0] + 40;
    }
  }
  EXPECT_GT(magenta, 500);
  EXPECT_GT(blue, 10000);
  EXPECT_GT(yellow, 1000);
  // One marker per loop at the operating threshold (here the loop score's
  // R@100P threshold, as the markers are the decision's reports): all true positives.
  std::int64_t tp = 0;
  for (const FrameRecord& f : r.records) {
    tp += f.reported.frame >= 0 && f.reported.score >= r.metrics.decision_threshold_at_100_precision;
  }
  EXPECT_GT(tp, 0);
  EXPECT_EQ(count(html, "<circle class='tp'"), static_cast<std::size_t>(tp));
  EXPECT_EQ(count(html, "<circle class='fp'"), 0u);
  EXPECT_NE(html.find("R@100P threshold"), std::string::npos);
}

TEST(Report, SmallSequenceIsNotSampledAndDecisionThresholdMarksFalsePositives) {
  const StreetRun& r = run();
  ReportInput in = r.input();
  in.max_matrix_frames = 4000;
  in.threshold = 0.0;  // every reported loop
  in.threshold_name = "decision threshold";
  const std::string html = render_report(in);
  const cv::Mat png = heatmap(html);
  const int n = static_cast<int>(r.world.frames());
  const int k = std::max(1, 600 / n);
  EXPECT_EQ(png.cols, n * k);
  EXPECT_EQ(png.rows, n * k);
  EXPECT_NE(html.find("all " + std::to_string(n) + " frames"), std::string::npos);
  std::size_t reported = 0, wrong = 0;
  for (const FrameRecord& f : r.records) {
    if (f.reported.frame < 0) continue;
    ++reported;
    wrong += !(f.reported.frame < f.frame - kMinGap &&
               r.world.ground_truth().is_loop(f.frame, f.reported.frame));
  }
  EXPECT_GT(wrong, 0u) << "the fixture should report some false loops at threshold 0";
  EXPECT_EQ(count(html, "<circle class='fp'"), wrong);
  EXPECT_EQ(count(html, "<circle class='tp'"), reported - wrong);
  EXPECT_NE(html.find("decision threshold 0.0000"), std::string::npos);
  EXPECT_NE(html.find(std::to_string(wrong) + " FP"), std::string::npos);
}

// The loops a detector declared (its operating point) are what the charts
// mark, with the operating point's numbers and the setup's warnings on top.
TEST(Report, DeclaredLoopsAndWarningsAreShown) {
  const StreetRun& r = run();
  std::vector<FrameRecord> records = r.records;
  // Declare two reports: one true, one false (a loop-free query).
  std::int64_t marked_true = -1, marked_false = -1;
  for (FrameRecord& f : records) {
    f.loop = false;
    if (f.reported.frame < 0) continue;
    const bool ok = f.reported.frame < f.frame - kMinGap &&
                    r.world.ground_truth().is_loop(f.frame, f.reported.frame);
    if (ok && marked_true < 0) marked_true = f.frame, f.loop = true;
    if (!ok && marked_false < 0) marked_false = f.frame, f.loop = true;
  }
  ASSERT_GE(marked_true, 0);
  ASSERT_GE(marked_false, 0);
  const Metrics m = evaluate(records, r.world.ground_truth(), kMinGap);
  ReportInput in = r.input();
  in.records = &records;
  in.metrics = &m;
  in.declared = true;
  in.warnings = {"frames of 64x32 give a 1x1 grid <&>"};
  const std::string html = render_report(in);
  EXPECT_EQ(tag_balance_error(html), "");
  EXPECT_EQ(count(html, "<circle class='fp'"), 1u);
  EXPECT_EQ(count(html, "<circle class='tp'"), 1u);
  EXPECT_NE(html.find("<th>Loops marked</th><td>the loops the system declared with its own settings "
                      "(no ground truth involved): "),
            std::string::npos);
  EXPECT_NE(html.find("false loops declared"), std::string::npos);
  // Issue 33's wording: the phrase fits each sentence it is in ...
  EXPECT_EQ(html.find("at the loops declared"), std::string::npos);
  EXPECT_EQ(html.find("at the the"), std::string::npos);
  EXPECT_NE(html.find("the ground-truth loops (outlined) and the loops the system declared"),
            std::string::npos);
  // ... the dashed line is a score, not "the loops declared" ...
  EXPECT_NE(html.find("dashed: the lowest loop score declared, "), std::string::npos);
  EXPECT_EQ(html.find("dashed: the loops"), std::string::npos);
  // ... the histogram of every report does not call a report below the line a false positive ...
  EXPECT_EQ(html.find("false positive</text>"), std::string::npos);
  EXPECT_NE(html.find("a wrong place scored below the loops marked is no false loop"), std::string::npos);
  // ... the cards say what they are, and a missed revisit shows its score.
  EXPECT_NE(html.find("P@100R: the precision at 100 % recall"), std::string::npos);
  EXPECT_NE(html.find("PRT: AP / (1 + 10 t)"), std::string::npos);

  EXPECT_NE(html.find("1x1 grid &lt;&amp;&gt;"), std::string::npos);
  EXPECT_NE(html.find("class='warning'"), std::string::npos);
}

TEST(Report, WithoutSimilarityTheHeatmapIsReplacedByANote) {
  ReportInput in = run().input();
  in.similarity = nullptr;
  const std::string html = render_report(in);
  EXPECT_EQ(html.find("data:image/png"), std::string::npos);
  EXPECT_NE(html.find("No similarity matrix"), std::string::npos);
  EXPECT_EQ(tag_balance_error(html), "");
}

TEST(Report, TrajectoryOnlyWithPoses) {
  const StreetRun& r = run();
  ReportInput in = r.input();
  in.threshold = 0.0;
  EXPECT_EQ(render_report(in).find("class='trajectory'"), std::string::npos);
  in.trajectory = r.trajectory;
  const std::string html = render_report(in);
  ASSERT_EQ(count(html, "<svg class='trajectory'"), 1u);
  const std::size_t begin = html.find("<svg class='trajectory'");
  const std::string svg = html.substr(begin, html.find("</svg>", begin) - begin);
  EXPECT_GE(count(svg, "<polyline class='path'"), 1u);
  std::size_t loops = 0, wrong = 0;
  for (const FrameRecord& f : r.records) {
    if (f.reported.frame < 0) continue;
    ++loops;
    wrong += !(f.reported.frame < f.frame - kMinGap &&
               r.world.ground_truth().is_loop(f.frame, f.reported.frame));
  }
  EXPECT_EQ(count(svg, "<line class='tp'"), loops - wrong) << "one line per loop found";
  EXPECT_EQ(count(svg, "<line class='fp'"), wrong);
  EXPECT_EQ(tag_balance_error(html), "");
  EXPECT_NE(html.find("lines join each of the reports scoring at least"), std::string::npos);
}

// Without poses the scores over the run stand in for the trajectory: one
// dot per frame that reported a candidate, coloured by what was declared.
TEST(Report, ScoreTimelineWithoutPoses) {
  const StreetRun& r = run();
  ReportInput in = r.input();
  in.declared = true;
  std::string html = render_report(in);
  ASSERT_EQ(count(html, "<svg class='timeline'"), 1u);
  const std::size_t begin = html.find("<svg class='timeline'");
  const std::string svg = html.substr(begin, html.find("</svg>", begin) - begin);
  std::size_t reported = 0, declared = 0;
  for (const FrameRecord& f : r.records) {
    reported += f.reported.frame >= 0 ? 1 : 0;
    declared += f.loop && f.reported.frame >= 0 ? 1 : 0;
  }
  EXPECT_EQ(count(svg, "<circle"), reported + 3);  // + the legend's three dots
  EXPECT_EQ(count(svg, "r='2.6'"), declared);
  EXPECT_GT(declared, 0u);
  in.trajectory = r.trajectory;
  EXPECT_EQ(render_report(in).find("<svg class='timeline'"), std::string::npos);
  EXPECT_EQ(tag_balance_error(html), "");
}

}  // namespace
}  // namespace lsgd::eval
