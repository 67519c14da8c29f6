// The HTML evaluation report: structure, the embedded PNG, escaping, the
// optional sections, errors, and a real headless-browser rendering.
#include "lsgd/eval/report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/eval/runner.h"
#include "synthetic/synthetic.h"
#include "lsgd/io/config.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace lsgd::eval {
namespace {

constexpr std::int64_t kMinGap = 20;

// A short piece of the synthetic street (the first revisit included), run
// through the detector once per test process.
struct StreetRun {
  SyntheticWorld world;
  DetectorOptions options;
  std::unique_ptr<Detector> detector;
  std::vector<FrameRecord> records;
  Metrics metrics;
  std::vector<std::array<double, 2>> trajectory;  // the street bent into a circle, per frame

  StreetRun() : world(world_options()) {
    options.search.min_gap = kMinGap;
    detector = std::make_unique<Detector>(options);
    FrameSource source;
    source.frames = world.frames();
    source.load = [this](std::int64_t i) { return world.render(i); };
    records = run_detector(*detector, source);
    metrics = evaluate(records, world.ground_truth(), kMinGap);
    // Place s along a circle of radius 20 (one lap per ~126 world units), a
    // traverse-dependent offset so revisits run beside the first pass.
    for (std::int64_t f = 0; f < world.frames(); ++f) {
      const double s = world.place(f), r = 20 + 0.6 * world.segment_of(f);
      trajectory.push_back({r * std::cos(s / 20), r * std::sin(s / 20)});
    }
  }
  static SyntheticOptions world_options() {
    SyntheticOptions o;
    o.width = 160;
    o.height = 120;
    o.route_scale = 0.25;
    return o;
  }
  ReportInput input() const {
    ReportInput in;
    in.sequence = "synthetic/street.txt";
    in.ground_truth = "synthetic/groundtruth.txt";
    in.mode = "exhaustive";
    in.verification = "temporal";
    in.config_yaml = io::to_yaml(options);
    in.metrics = &metrics;
    in.records = &records;
    in.gt = &world.ground_truth();
    const Detector* d = detector.get();
    in.similarity = [d](std::int64_t a, std::int64_t b) { return d->similarity(a, b); };
    in.nodes = detector->nodes();
    in.bytes_per_frame = detector->bytes_per_frame();
    return in;
  }
};

const StreetRun& run() {
  static const StreetRun r;
  return r;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

// The value of the first attribute `name='...'` after `from`.
std::string attribute(const std::string& html, std::size_t from, const std::string& name) {
  const std::string key = name + "='";
  const std::size_t start = html.find(key, from);
  if (start == std::string::npos) return "";
  const std::size_t begin = start + key.size();
  return html.substr(begin, html.find('\'', begin) - begin);
}

std::vector<uchar> decode_base64(const std::string& text) {
  std::vector<uchar> out;
  std::uint32_t buffer = 0;
  int bits = 0;
  for (const char c : text) {
    int v;
    if (c >= 'A' && c <= 'Z')
      v = c - 'A';
    else if (c >= 'a' && c <= 'z')
      v = c - 'a' + 26;
    else if (c >= '0' && c <= '9')
      v = c - '0' + 52;
    else if (c == '+')
      v = 62;
    else if (c == '/')
      v = 63;
    else if (c == '=')
      break;
    else {
      ADD_FAILURE() << "not base64: '" << c << "'";
      return {};
    }
    buffer = (buffer << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<uchar>((buffer >> bits) & 0xFF));
    }
  }
  return out;
}

// The similarity matrix PNG of a report (empty Mat when absent).
cv::Mat heatmap(const std::string& html) {
  const std::string key = "data:image/png;base64,";
  const std::size_t p = html.find(key);
  if (p == std::string::npos) return {};
  const std::size_t begin = p + key.size();
  return cv::imdecode(decode_base64(html.substr(begin, html.find('\'', begin) - begin)),
                      cv::IMREAD_COLOR);
}

// Checks that every element is closed in order (void elements and "/>" aside),
// attribute values are quoted and no '<' appears inside text or attributes.
std::string tag_balance_error(const std::string& html) {
  std::vector<std::string> open;
  const std::vector<std::string> kVoid = {"meta", "br", "hr", "img", "input", "link"};
  for (std::size_t p = html.find('<'); p != std::string::npos; p = html.find('<', p + 1)) {
    if (html.compare(p, 9, "<!DOCTYPE") == 0) continue;
    std::size_t end = p + 1;
    char quote = 0;
    for (; end < html.size() && (quote || html[end] != '>'); ++end) {
      if (quote && html[end] == '<') return "'<' inside an attribute at " + std::to_string(end);
      if (html[end] == '\'' || html[end] == '"')
        quote = quote == html[end] ? 0 : quote ? quote : html[end];
    }
    if (end >= html.size()) return "unterminated tag at " + std::to_string(p);
    const std::string tag = html.substr(p + 1, end - p - 1);
    const std::string name =
        tag.substr(tag[0] == '/', tag.find_first_of(" />", 1) - (tag[0] == '/'));
    if (tag[0] == '/') {
      if (open.empty() || open.back() != name)
        return "unexpected </" + name + "> at " + std::to_string(p);
      open.pop_back();
    } else if (tag.back() != '/' && std::find(kVoid.begin(), kVoid.end(), name) == kVoid.end()) {
      open.push_back(name);
      if (name == "style" || name == "pre") {  // raw text: skip to its end tag
        const std::size_t close = html.find("</" + name + ">", end);
        if (html.substr(end + 1, close - end - 1).find('<') != std::string::npos)
          return "'<' in <" + name + ">";
        p = close - 1;
        continue;
      }
    }
    p = end;
  }
  return open.empty() ? "" : "<" + open.back() + "> is never closed";
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
