// The HTML evaluation report (include/lsgd/eval/report.h): example
// thumbnails and what made the run, compared systems, hostile text, external
// detections, and invalid input.
#include "lsgd/eval/report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
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
using report_test_support::decode_base64;
using report_test_support::kMinGap;
using report_test_support::run;
using report_test_support::StreetRun;
using report_test_support::tag_balance_error;

// Thumbnails: declared true and false loops and missed revisits, query and
// match side by side, each a JPEG data URI; a frame that cannot be read is a
// note, not a failure. The header names the image size, grid, command and version.
TEST(Report, ExampleThumbnailsAndWhatMadeTheRun) {
  const StreetRun& r = run();
  ReportInput in = r.input();
  in.declared = true;
  in.width = 160;
  in.height = 120;
  in.grid_rows = 2;
  in.grid_cols = 3;
  in.command = "lsgd eval --sequence <street>";
  in.version = "lsgd 9.9.9 (commit abc)";
  in.max_examples = 3;
  int loaded = 0, gone = 0;
  in.image = [&](std::int64_t f) {
    if (f == 7) {
      ++gone;
      throw IoError("frame 7 is gone");
    }
    ++loaded;
    return r.world.render(f);
  };
  std::string html = render_report(in);
  EXPECT_NE(html.find("160 x 120 pixels, descriptor grid 2 x 3 = 6 cells"), std::string::npos);
  EXPECT_NE(html.find("lsgd eval --sequence &lt;street&gt;"), std::string::npos);
  EXPECT_NE(html.find("lsgd 9.9.9 (commit abc)"), std::string::npos);
  ASSERT_NE(html.find("<section class='examples'>"), std::string::npos);
  const std::size_t thumbs = count(html, "src='data:image/jpeg;base64,");
  EXPECT_EQ(static_cast<int>(thumbs), loaded);
  if (gone > 0) {
    EXPECT_NE(html.find("frame 7 is gone"), std::string::npos);  // a note instead
  }
  EXPECT_GE(thumbs, 6u);                                 // 3 true loops, 2 frames each
  EXPECT_LE(thumbs, 3u * 2 + 3 * 3 + 3 * 3);            // at most 3 of each kind
  EXPECT_NE(html.find("Missed revisits ("), std::string::npos);
  // A missed revisit shows the score it reached and whether it was the right place.
  const std::size_t missed = html.find("Missed revisits (");
  EXPECT_NE(html.find("score ", missed), std::string::npos) << "a missed revisit without its score";
  EXPECT_NE(html.find(" place", missed), std::string::npos);
  const std::size_t jpeg = html.find("src='data:image/jpeg;base64,") + 28;
  const std::vector<uchar> bytes = decode_base64(html.substr(jpeg, html.find('\'', jpeg) - jpeg));
  const cv::Mat thumb = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(thumb.rows, 110);
  EXPECT_EQ(thumb.cols, 146);  // 160 x 120 scaled to a height of 110
  in.image = [](std::int64_t) -> cv::Mat { throw IoError("the disk is gone"); };
  html = render_report(in);
  EXPECT_EQ(count(html, "src='data:image/jpeg"), 0u);
  EXPECT_NE(html.find("the disk is gone"), std::string::npos);
  EXPECT_EQ(tag_balance_error(html), "");
}

// Another system's detections, scored by the same evaluator, on the same PR plot.
TEST(Report, ComparedSystemsShareThePrPlot) {
  const StreetRun& r = run();
  ReportInput in = r.input();
  std::vector<FrameRecord> other = r.records;
  for (FrameRecord& f : other) f.reported.frame = f.reported.frame >= 0 ? 0 : -1;  // always frame 0
  in.compared.push_back({"always-zero", evaluate(other, r.world.ground_truth(), kMinGap)});
  in.compared.push_back({"ours <again>", r.metrics});
  const std::string html = render_report(in);
  EXPECT_EQ(count(html, "<polyline class='pr-compared'"), 2u);
  EXPECT_NE(html.find("always-zero (AP "), std::string::npos);
  EXPECT_NE(html.find("ours &lt;again&gt; (AP "), std::string::npos);
  in.compared[0].metrics.min_gap = kMinGap + 1;
  EXPECT_THROW(render_report(in), InvalidArgument);
  EXPECT_EQ(tag_balance_error(html), "");
}

TEST(Report, EscapesHostileText) {
  ReportInput in = run().input();
  in.sequence = "<script>alert(\"x\")</script> & 'q' <img src=x>";
  in.ground_truth = "gt\"><b>bold</b>.txt";
  in.title = "</title><h1>&amp;";
  in.mode = "<i>";
  in.config_yaml = "key: \"<pre>\" & </pre>";
  const std::string html = render_report(in);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<img"), std::string::npos);
  EXPECT_EQ(html.find("<b>bold"), std::string::npos);
  EXPECT_EQ(html.find("<i>"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt; &amp; &#39;q&#39;"),
            std::string::npos);
  EXPECT_NE(html.find("&lt;/title&gt;&lt;h1&gt;&amp;amp;"), std::string::npos);
  EXPECT_NE(html.find("key: &quot;&lt;pre&gt;&quot; &amp; &lt;/pre&gt;"), std::string::npos);
  EXPECT_EQ(tag_balance_error(html), "");
}

// Detections from another system: no similarity, no timings; the best-scored
// report is false, so R@100P is 0 and no loop is marked by default.
TEST(Report, ExternalDetectionsWithoutPerfectPrecision) {
  GroundTruth gt(40);
  for (std::int64_t q = 30; q < 40; ++q) gt.add(q, q - 30);
  std::vector<FrameRecord> records;
  for (std::int64_t q = 0; q < 40; ++q) {
    FrameRecord r;
    r.frame = q;
    if (q >= 30) r.reported = {q - 30, 0.5 + 0.01 * static_cast<double>(q - 30)};  // right
    if (q == 25) r.reported = {2, 0.99};                                           // wrong, best
    records.push_back(r);
  }
  const Metrics metrics = evaluate(records, gt, 5);
  ASSERT_EQ(metrics.recall_at_100_precision, 0.0);
  ReportInput in;
  in.sequence = "other-system.csv";
  in.metrics = &metrics;
  in.records = &records;
  in.gt = &gt;
  const std::string html = render_report(in);
  EXPECT_NE(html.find("no threshold reaches precision 1"), std::string::npos);
  EXPECT_NE(html.find("0 TP</b>, <b style='color:#e41a1c'>0 FP"), std::string::npos);
  EXPECT_NE(html.find("No similarity matrix"), std::string::npos);
  EXPECT_EQ(html.find("bytes per frame"), std::string::npos);  // unknown: not shown
  EXPECT_EQ(count(html, "<circle class='"), 0u);
  EXPECT_EQ(tag_balance_error(html), "");
  // Nothing reported at all: an empty curve, noted instead of drawn.
  for (FrameRecord& r : records) r.reported = {};
  const Metrics none = evaluate(records, gt, 5);
  in.metrics = &none;
  const std::string empty = render_report(in);
  EXPECT_EQ(empty.find("pr-curve"), std::string::npos);
  EXPECT_NE(empty.find("no loop reported"), std::string::npos);
  EXPECT_NE(empty.find("No loop reported."), std::string::npos);
  EXPECT_EQ(tag_balance_error(empty), "");
}

TEST(Report, InvalidInputThrows) {
  GroundTruth gt(10);
  gt.add(9, 1);
  std::vector<FrameRecord> records(10);
  for (std::int64_t q = 0; q < 10; ++q) records[static_cast<std::size_t>(q)].frame = q;
  const Metrics metrics = evaluate(records, gt, 2);
  const auto valid = [&] {
    ReportInput in;
    in.metrics = &metrics;
    in.records = &records;
    in.gt = &gt;
    return in;
  };
  EXPECT_NO_THROW(render_report(valid()));
  ReportInput in = valid();
  in.metrics = nullptr;
  EXPECT_NE(test::message_of<InvalidArgument>([&] { render_report(in); }).find("metrics"),
            std::string::npos);
  in = valid();
  in.trajectory.assign(3, {0.0, 0.0});
  EXPECT_NE(test::message_of<InvalidArgument>([&] { render_report(in); }).find("trajectory has 3"),
            std::string::npos);
  in = valid();
  in.trajectory.assign(10, {0.0, std::nan("")});
  EXPECT_THROW(render_report(in), InvalidArgument);
  // Finite positions whose span is not: the map's scale was NaN, every
  // point '-nan'. A span just below a double's range is drawn.
  in = valid();
  for (int i = 0; i < 10; ++i) in.trajectory.push_back({0.0, i % 2 ? 1e308 : -1e308});
  EXPECT_NE(test::message_of<InvalidArgument>([&] { render_report(in); })
                .find("trajectory's positions span z from -1e+308 to 1e+308, more than a double holds"),
            std::string::npos);
  for (auto& p : in.trajectory) p[1] *= 0.8;
  EXPECT_EQ(render_report(in).find("'-nan'"), std::string::npos);
  in = valid();
  in.max_matrix_frames = 1;
  EXPECT_NE(test::message_of<InvalidArgument>([&] { render_report(in); }).find("max_matrix_frames"),
            std::string::npos);
  in = valid();
  in.threshold = std::nan("");
  EXPECT_THROW(render_report(in), InvalidArgument);
  const GroundTruth small(5);
  in = valid();
  in.gt = &small;
  EXPECT_NE(test::message_of<InvalidArgument>([&] {
              render_report(in);
            }).find("outside the ground truth"),
            std::string::npos);
}

}  // namespace
}  // namespace lsgd::eval
