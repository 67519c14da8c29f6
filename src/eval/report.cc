#include "lsgd/io/files.h"
#include "lsgd/eval/report.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "eval/report_svg.h"
#include "internal/check.h"
#include "lsgd/error.h"

namespace lsgd::eval {
namespace report {

// ---------------------------------------------------------------- sections

void header(std::ostream& html, const ReportInput& in, const Operating& op) {
  const Metrics& m = *in.metrics;
  html << "<header><h1>" << escape(in.title.empty() ? "lsgd evaluation: " + in.sequence : in.title)
       << "</h1>\n<table class='facts'>"
       << "<tr><th>Sequence</th><td class='path'>" << escape(in.sequence) << "</td></tr>"
       << "<tr><th>Ground truth</th><td class='path'>" << escape(in.ground_truth) << "</td></tr>"
       << "<tr><th>Protocol</th><td>" << escape(in.protocol)
       << ", temporal window w = " << m.min_gap
       << " frames (candidates j &lt; i &minus; w)</td></tr>"
       << "<tr><th>Search</th><td>mode " << escape(in.mode) << ", verification "
       << escape(in.verification) << "</td></tr>"
       << (in.width > 0 ? concat("<tr><th>Images</th><td>", in.width, " x ", in.height, " pixels",
                                 in.grid_rows > 0 ? concat(", descriptor grid ", in.grid_rows, " x ",
                                                           in.grid_cols, " = ", in.grid_rows * in.grid_cols,
                                                           " cells")
                                                  : std::string(),
                                 "</td></tr>")
                          : std::string())
       << (in.version.empty() ? std::string()
                              : "<tr><th>Made by</th><td>" + escape(in.version) + "</td></tr>")
       << (in.command.empty() ? std::string()
                              : "<tr><th>Command</th><td class='path'><code>" + escape(in.command) +
                                    "</code></td></tr>")
       << "<tr><th>Frames</th><td>" << m.frames << " evaluated of " << in.gt->frames() << "; "
       << m.positives << " positives (queries with a GT loop outside the window); "
       << in.gt->pairs() << " GT pairs</td></tr>"
       << "<tr><th>Loops marked</th><td>" << op.marked << ": <b style='color:" << kTpColour
       << "'>" << op.tp << " TP</b>, <b style='color:" << kFpColour << "'>" << op.fp
       << " FP</b></td></tr></table>\n";
  for (const std::string& w : in.warnings) {
    html << "<p class='warning'><b>Warning:</b> " << escape(w) << "</p>\n";
  }
  html << "<div class='cards'>";
  const std::pair<const char*, std::string> cards[] = {
      {"loops declared", std::to_string(m.declared_loops)},
      {"false loops declared", std::to_string(m.declared_false)},
      {"precision (declared)", percent(m.precision_at_decision)},
      {"recall (declared)", percent(m.recall_at_decision)},
      {"R@100P", percent(m.recall_at_100_precision)},
      {"P@100R", percent(m.precision_at_100_recall)},
      {"AP", percent(m.average_precision)},
      {"R@1", percent(m.recall_at_1)},
      {"R@5", percent(m.recall_at_5)},
      {"R@10", percent(m.recall_at_10)},
      {"PRT", num(m.prt, 3)},
      {"ms / frame", num(m.ms_per_frame_median, 2)}};
  for (const auto& [name, value] : cards) {
    html << "<div class='card'><div class='value'>" << value << "</div><div class='name'>" << name
         << "</div></div>";
  }
  html << "</div><p class='caption'>Declared: the loops the system declared with its own "
       << "settings. R@100P: the recall at 100 % precision, P@100R: the precision at 100 % "
       << "recall, AP: the average precision, all three over the ranking no decision setting "
       << "changes (docs/evaluation.md). R@N: queries with a true match among their N best "
       << "candidates, of the positives. PRT: AP / (1 + 10 t), t the mean seconds per frame "
       << "(the paper's Sec. IV-D).</p></header>\n";
}

void pr_curve(std::ostream& html, const ReportInput& in, const Operating& op) {
  const Metrics& m = *in.metrics;
  const Scale x = chart_x(0, 1), y = chart_y(0, 1);
  std::ostringstream svg;
  svg << "<svg class='pr' width='560' height='480' viewBox='0 0 560 480' role='img'>";
  const std::vector<double> t = ticks(0, 1, 10);
  axes(svg, kChart, x, y, t, t, "recall", "precision", true);
  if (m.curve.empty()) {
    svg << "<text class='note' x='305' y='200' text-anchor='middle'>no loop reported</text>";
  } else {
    svg << "<polyline class='pr-curve' fill='none' stroke='" << kCurveColour
        << "' stroke-width='2' stroke-linejoin='round' points='";
    for (const PrPoint& p : m.curve)
      svg << num(x(p.recall), 2) << ',' << num(y(p.precision), 2) << ' ';
    svg << "'/>";
  }
  // Other systems, scored by the same evaluator, under ours.
  for (std::size_t k = 0; k < in.compared.size(); ++k) {
    const Metrics& c = in.compared[k].metrics;
    svg << "<polyline class='pr-compared' fill='none' stroke='" << compared_colour(k)
        << "' stroke-width='1.6' stroke-dasharray='6 3' points='";
    for (const PrPoint& p : c.curve) svg << num(x(p.recall), 2) << ',' << num(y(p.precision), 2) << ' ';
    svg << "'/>";
  }
  if (m.recall_at_100_precision > 0) {
    svg << "<circle cx='" << x(m.recall_at_100_precision) << "' cy='" << y(1) << "' r='6' fill='"
        << kTpColour << "' stroke='#fff' stroke-width='1.5'/>";
  }
  // The operating point: the precision and recall of the loops it marks (the
  // decision's, which the ranking's curve need not pass through).
  std::optional<PrPoint> at;
  if (op.tp + op.fp > 0 && m.positives > 0) {
    at = PrPoint{};
    at->precision = static_cast<double>(op.tp) / static_cast<double>(op.tp + op.fp);
    at->recall = static_cast<double>(op.tp) / static_cast<double>(m.positives);
    svg << "<rect x='" << x(at->recall) - 5 << "' y='" << y(at->precision) - 5
        << "' width='10' height='10' fill='none' stroke='#111' stroke-width='2'/>";
  }
  legend_row(svg, 84, 300, "line", kCurveColour,
             "precision-recall (AP " + percent(m.average_precision) + ")");
  legend_row(svg, 84, 322, "dot", kTpColour,
             m.recall_at_100_precision > 0
                 ? "R@100P " + percent(m.recall_at_100_precision) + " at threshold " +
                       num(m.threshold_at_100_precision, 4)
                 : std::string("R@100P 0: the best-scored report is false"));
  double row = 344;
  if (at) {
    legend_row(svg, 84, row, "box", "#111",
               "operating point: P " + percent(at->precision) + ", R " + percent(at->recall));
    row += 22;
  }
  for (std::size_t k = 0; k < in.compared.size(); ++k, row += 22) {
    const Metrics& c = in.compared[k].metrics;
    legend_row(svg, 84, row, "line", compared_colour(k),
               escape(in.compared[k].name) + " (AP " + percent(c.average_precision) + ", R@100P " +
                   percent(c.recall_at_100_precision) + ", " + std::to_string(c.declared_false) +
                   " false of " + std::to_string(c.declared_loops) + " declared)");
  }
  svg << "</svg>";
  html << "<figure class='chart'><h2>Precision-recall</h2>" << svg.str() << "<figcaption>"
       << m.curve.size() << " sweep points, one per distinct score of the "
       << "reported loops (threshold decreasing to the right).</figcaption></figure>\n";
}

// Reported scores in 40 bins over [lo, hi] (rounded to 0.02), TP and FP apart.
struct Histogram {
  double lo = 1, hi = 0;
  std::vector<int> tp, fp;
  std::size_t reports = 0;
};

Histogram score_bins(const ReportInput& in) {
  constexpr int kBins = 40;
  Histogram h;
  h.tp.assign(kBins, 0);
  h.fp.assign(kBins, 0);
  for (const FrameRecord& r : *in.records) {
    if (r.reported.frame < 0) continue;
    h.lo = std::min(h.lo, r.reported.score), h.hi = std::max(h.hi, r.reported.score);
    ++h.reports;
  }
  h.lo = std::floor(h.lo * 50) / 50;
  h.hi = std::max(std::ceil(h.hi * 50) / 50, h.lo + 0.02);
  for (const FrameRecord& r : *in.records) {
    if (r.reported.frame < 0) continue;
    const double at = (r.reported.score - h.lo) / (h.hi - h.lo) * kBins;
    const auto b = static_cast<std::size_t>(std::clamp(static_cast<int>(at), 0, kBins - 1));
    (correct_loop(*in.gt, r.frame, r.reported.frame, in.metrics->min_gap) ? h.tp : h.fp)[b] += 1;
  }
  return h;
}

void score_histogram(std::ostream& html, const ReportInput& in, const Operating& op) {
  const Histogram h = score_bins(in);
  html << "<figure class='chart'><h2>Scores of the reported loops</h2>";
  if (h.reports == 0) {
    html << "<p class='note'>No loop reported.</p></figure>\n";
    return;
  }
  int peak = 1;
  for (std::size_t b = 0; b < h.tp.size(); ++b) peak = std::max(peak, h.tp[b] + h.fp[b]);
  const double step = std::max(1.0, std::round(tick_step(0, peak, 5)));
  const double top = std::ceil(peak / step) * step;  // the axis ends on a tick
  const Scale x = chart_x(h.lo, h.hi), y = chart_y(0, top);
  std::ostringstream svg;
  svg << "<svg class='hist' width='560' height='480' viewBox='0 0 560 480' role='img'>";
  std::vector<double> yt;
  for (double v = 0; v <= top; v += step) yt.push_back(v);
  axes(svg, kChart, x, y, ticks(h.lo, h.hi, 8), yt, "score", "reported loops", true);
  const double w = (x.p1 - x.p0) / static_cast<double>(h.tp.size());
  for (std::size_t b = 0; b < h.tp.size(); ++b) {  // stacked: TP below, FP on top
    const double bx = x.p0 + static_cast<double>(b) * w + 0.5, both = h.tp[b] + h.fp[b];
    svg << "<rect x='" << bx << "' y='" << y(h.tp[b]) << "' width='" << w - 1 << "' height='"
        << y.p0 - y(h.tp[b]) << "' fill='" << kTpColour << "'/><rect x='" << bx << "' y='"
        << y(both) << "' width='" << w - 1 << "' height='" << y(h.tp[b]) - y(both) << "' fill='"
        << kFpColour << "'/>";
  }
  if (op.threshold >= h.lo && op.threshold <= h.hi) {
    svg << "<line x1='" << x(op.threshold) << "' y1='" << y.p0 << "' x2='" << x(op.threshold)
        << "' y2='" << y.p1 << "' stroke='#111' stroke-width='1.5' stroke-dasharray='5 3'/>";
  }
  std::vector<LegendItem> entries = {{"dot", kTpColour, "right place"}, {"dot", kFpColour, "wrong place"}};
  if (!op.line.empty()) entries.push_back({"line", "#111", "operating threshold"});
  legend(svg, entries, kLegendX, kLegendY, kLegendWidth);
  html << svg.str() << "</svg><figcaption>The best verified candidate of each query that "
       << "reported one (" << h.reports << " queries), stacked by whether it is the right place, "
       << "loop or not: a wrong place scored below the loops marked is no false loop"
       << (op.line.empty() ? std::string() : "; dashed: " + op.line) << ".</figcaption></figure>\n";
}

// Uniform sample of n of the `frames` frame ids, and the map back.
struct Sampling {
  std::int64_t frames = 0;
  int n = 0;
  std::int64_t frame(int k) const {
    return n < 2 ? 0
                 : static_cast<std::int64_t>(
                       std::llround(static_cast<double>(k) * (frames - 1) / (n - 1)));
  }
  double cell(double f) const {
    return frames < 2 ? 0 : f * (n - 1) / static_cast<double>(frames - 1);
  }
};

// The similarity of the sampled frames as an 8-bit image scaled to [lo, hi].
cv::Mat similarity_image(const ReportInput& in, const Sampling& s, double& lo, double& hi) {
  cv::Mat sim(s.n, s.n, CV_64F, cv::Scalar(0));
  std::vector<double> values;
  values.reserve(static_cast<std::size_t>(s.n) * (s.n - 1) / 2);
  for (int a = 0; a < s.n; ++a) {
    for (int b = 0; b < a; ++b) {
      const double v = in.similarity(s.frame(a), s.frame(b));  // NaN: a frame never described
      sim.at<double>(a, b) = sim.at<double>(b, a) = v;
      if (!std::isnan(v)) values.push_back(v);
    }
  }
  // Scale from the 1st percentile to the maximum, so a few outliers do not flatten the contrast.
  lo = values.empty() ? 0 : percentile(values, 0.01);
  hi = values.empty() ? 1 : *std::max_element(values.begin(), values.end());
  if (!(hi > lo)) hi = lo + 1e-6;
  for (int a = 0; a < s.n; ++a) sim.at<double>(a, a) = hi;
  sim.forEach<double>([lo](double& v, const int*) {
    if (std::isnan(v)) v = lo;  // shown as the least similar
  });
  cv::Mat gray;
  sim.convertTo(gray, CV_8U, 255.0 / (hi - lo), -255.0 * lo / (hi - lo));
  return gray;
}

// Ground-truth loops (q, m) outside the temporal window, per matrix cell, in
// the upper triangle only (row m < column q): the lower one shows the
// similarity unobstructed.
cv::Mat gt_mask(const ReportInput& in, const Sampling& s) {
  cv::Mat mask(s.n, s.n, CV_8U, cv::Scalar(0));
  for (const std::int64_t q : in.gt->queries()) {
    const int column = static_cast<int>(std::lround(s.cell(static_cast<double>(q))));
    for (const std::int64_t m : in.gt->matches(q)) {
      if (q - m <= in.metrics->min_gap) continue;
      mask.at<uchar>(static_cast<int>(std::lround(s.cell(static_cast<double>(m)))), column) = 255;
    }
  }
  return mask;
}

// Heat-map (cividis) of the sampled matrix, upscaled by `k`, with the GT cells outlined.
std::string matrix_png(const ReportInput& in, const Sampling& s, int k, double& lo, double& hi) {
  cv::Mat gray = similarity_image(in, s, lo, hi), colour, mask = gt_mask(in, s);
  cv::resize(gray, gray, cv::Size(), k, k, cv::INTER_NEAREST);
  cv::resize(mask, mask, cv::Size(), k, k, cv::INTER_NEAREST);
  cv::applyColorMap(gray, colour, cv::COLORMAP_CIVIDIS);
  cv::Mat inner;  // the outline is the part of the mask its erosion removes
  cv::erode(mask, inner, cv::Mat(), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  colour.setTo(kGtBgr, mask - inner);
  std::vector<uchar> png;
  if (!cv::imencode(".png", colour, png))
    throw IoError("report: PNG encoding of the similarity matrix failed");
  return base64(png);
}

// A vertical colour bar of the cividis map labelled with similarities lo..hi.
void colour_bar(std::ostream& svg, double x0, double y0, double height, double lo, double hi) {
  cv::Mat ramp(1, 256, CV_8U), colours;
  for (int i = 0; i < 256; ++i) ramp.at<uchar>(0, i) = static_cast<uchar>(i);
  cv::applyColorMap(ramp, colours, cv::COLORMAP_CIVIDIS);
  svg << "<defs><linearGradient id='cividis' x1='0' y1='1' x2='0' y2='0'>";
  for (int i = 0; i <= 8; ++i) {
    const cv::Vec3b c = colours.at<cv::Vec3b>(0, std::min(255, i * 32));
    char hex[8];
    std::snprintf(hex, sizeof hex, "#%02x%02x%02x", c[2], c[1], c[0]);
    svg << "<stop offset='" << i / 8.0 << "' stop-color='" << hex << "'/>";
  }
  svg << "</linearGradient></defs><rect x='" << x0 << "' y='" << y0 << "' width='16' height='"
      << height << "' fill='url(#cividis)' stroke='#555'/>";
  const Scale y{lo, hi, y0 + height, y0};
  const std::vector<double> t = ticks(lo, hi, 6);
  for (const double v : t) {
    svg << "<text class='tick' x='" << x0 + 22 << "' y='" << y(v) + 4 << "'>"
        << num(v, tick_decimals(t)) << "</text>";
  }
  svg << "<text class='title' transform='translate(" << x0 + 70 << ' ' << y0 + height / 2
      << ") rotate(-90)' text-anchor='middle'>similarity</text>";
}

// The matrix image with its axes, window edge, loop markers and colour bar.
std::string matrix_svg(const ReportInput& in, const Operating& op, const Sampling& s, double& lo,
                       double& hi) {
  const int k = std::max(1, kMatrixPixels / s.n);  // integer upscaling keeps the cells crisp
  const std::string png = matrix_png(in, s, k, lo, hi);
  const double side = static_cast<double>(s.n) * k, x0 = 70, y0 = 20, unit = side / s.n;
  const double last = static_cast<double>(s.frames - 1);
  // Frame f at the centre of its cell; frame 0 at the top left, like the matrix rows.
  const Scale x{0, last, x0 + unit / 2, x0 + side - unit / 2},
      y{0, last, y0 + unit / 2, y0 + side - unit / 2};
  std::ostringstream svg;
  svg << "<svg class='heatmap' width='" << side + 190 << "' height='" << side + 70
      << "' role='img'>"
      << "<image x='" << x0 << "' y='" << y0 << "' width='" << side << "' height='" << side
      << "' style='image-rendering:pixelated' href='data:image/png;base64," << png << "'/>";
  const std::vector<double> t = ticks(0, last, 8);
  axes(svg, {x0, y0, x0 + side, y0 + side}, x, y, t, t, "frame (query i above the diagonal)",
       "frame (match j above the diagonal)", false);
  const double w = static_cast<double>(in.metrics->min_gap);
  if (w < last) {  // the temporal window's edge j = i - w, above the diagonal
    svg << "<line x1='" << x(w) << "' y1='" << y(0) << "' x2='" << x(last) << "' y2='"
        << y(last - w) << "' stroke='#fff' stroke-width='1' stroke-dasharray='4 4' opacity='0.8'/>";
  }
  for (const Loop& l : op.loops) {  // at column i, row j: on the GT outline when correct
    svg << "<circle class='" << (l.correct ? "tp" : "fp") << "' cx='" << num(x(l.query), 1)
        << "' cy='" << num(y(l.match), 1) << "' r='3' fill='" << (l.correct ? kTpColour : kFpColour)
        << "' stroke='#fff' stroke-width='0.8'/>";
  }
  colour_bar(svg, x0 + side + 18, y0, side, lo, hi);
  svg << "</svg>";
  return svg.str();
}

void matrix_section(std::ostream& html, const ReportInput& in, const Operating& op) {
  html << "<section class='matrix'><h2>Similarity matrix</h2>";
  const std::int64_t frames = in.gt->frames();
  if (!in.similarity || frames < 2) {
    html << "<p class='note'>No similarity matrix: "
         << (frames < 2 ? "the sequence has one frame."
                        : "no similarity function was given (e.g. detections from another "
                          "system, without the detector's descriptors).")
         << "</p></section>\n";
    return;
  }
  const Sampling s{frames, static_cast<int>(std::min<std::int64_t>(frames, in.max_matrix_frames))};
  double lo = 0, hi = 1;
  html << matrix_svg(in, op, s, lo, hi)
       << "<div class='legend-html'><span class='sw' style='border:2px solid " << kGtColour
       << "'></span> ground-truth loops outside the window &nbsp; <span class='dot' "
       << "style='background:" << kTpColour << "'></span> true positive &nbsp; <span class='dot' "
       << "style='background:" << kFpColour << "'></span> false positive &nbsp; <span class='sw' "
       << "style='height:0;width:18px;border-top:2px dashed #999'></span> window edge j = i "
          "&minus; w"
       << "</div><p class='caption'>Similarity of every pair of frames ("
       << (s.n < frames ? concat(s.n, " of ", frames, " frames sampled uniformly, one cell per ",
                                 num(static_cast<double>(frames) / s.n, 1), " frames")
                        : concat("all ", frames, " frames"))
       << "), symmetric; colour from the 1st percentile (" << num(lo, 3) << ") to the maximum ("
       << num(hi, 3)
       << ") of the off-diagonal values. Above the diagonal, column i and row j &lt; i: "
       << "the ground-truth loops (outlined) and " << op.marked
       << " (dots); below it the similarity alone.</p></section>\n";
}

// The camera path as polylines, broken where one step is far longer than the
// median (a gap in the recording), so that a jump is not drawn as a road.
void path(std::ostream& svg, const std::vector<std::array<double, 2>>& p, const Scale& x,
          const Scale& z) {
  std::vector<double> steps, moving;
  for (std::size_t i = 1; i < p.size(); ++i) {
    steps.push_back(std::hypot(p[i][0] - p[i - 1][0], p[i][1] - p[i - 1][1]));
    if (steps.back() > 0) moving.push_back(steps.back());
  }
  const double gap =
      moving.empty() ? std::numeric_limits<double>::infinity() : 25 * percentile(moving, 0.5);
  const char* const kOpen =
      "<polyline class='path' fill='none' stroke='#9ca3af' stroke-width='1.5' points='";
  svg << kOpen;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (i > 0 && steps[i - 1] > gap) svg << "'/>" << kOpen;
    svg << num(x(p[i][0]), 1) << ',' << num(z(p[i][1]), 1) << ' ';
  }
  svg << "'/>";
}

void trajectory_section(std::ostream& html, const ReportInput& in, const Operating& op) {
  const auto& p = in.trajectory;
  double x_lo = p[0][0], x_hi = p[0][0], z_lo = p[0][1], z_hi = p[0][1];
  for (const auto& q : p) {
    x_lo = std::min(x_lo, q[0]), x_hi = std::max(x_hi, q[0]);
    z_lo = std::min(z_lo, q[1]), z_hi = std::max(z_hi, q[1]);
  }
  // Equal scale on both axes inside the plot area, centred.
  const double w = kChart.x1 - kChart.x0, h = kChart.y1 - kChart.y0;
  const double span = std::max({(x_hi - x_lo) / w, (z_hi - z_lo) / h, 1e-9});
  const double xc = (x_lo + x_hi) / 2, zc = (z_lo + z_hi) / 2;
  const Scale x = chart_x(xc - w / 2 * span, xc + w / 2 * span),
              z = chart_y(zc - h / 2 * span, zc + h / 2 * span);
  std::ostringstream svg;
  svg << "<svg class='trajectory' width='560' height='480' viewBox='0 0 560 480' role='img'>";
  axes(svg, kChart, x, z, ticks(x.lo, x.hi, 6), ticks(z.lo, z.hi, 5), "x", "z", true);
  path(svg, p, x, z);
  for (std::int64_t f = 0; f < in.gt->frames(); ++f) {
    if (!in.gt->has_loop(f, in.metrics->min_gap)) continue;
    const auto& q = p[static_cast<std::size_t>(f)];
    svg << "<circle cx='" << num(x(q[0]), 1) << "' cy='" << num(z(q[1]), 1) << "' r='2.5' fill='"
        << kGtFrameColour << "'/>";
  }
  for (const Loop& l : op.loops) {
    const auto& a = p[static_cast<std::size_t>(l.query)];
    const auto& b = p[static_cast<std::size_t>(l.match)];
    const char* c = l.correct ? kTpColour : kFpColour;
    svg << "<line class='" << (l.correct ? "tp" : "fp") << "' x1='" << num(x(a[0]), 1) << "' y1='"
        << num(z(a[1]), 1) << "' x2='" << num(x(b[0]), 1) << "' y2='" << num(z(b[1]), 1)
        << "' stroke='" << c << "' stroke-width='1.5'/><circle cx='" << num(x(a[0]), 1) << "' cy='"
        << num(z(a[1]), 1) << "' r='2' fill='" << c << "'/>";
  }
  svg << "<circle cx='" << x(p[0][0]) << "' cy='" << z(p[0][1]) << "' r='5' fill='#111'/>";
  legend(svg,
         {{"dot", kGtFrameColour, "frame with a GT loop"},
          {"line", kTpColour, "true loop"},
          {"line", kFpColour, "false loop"},
          {"dot", "#111", "start"}},
         kLegendX, kLegendY, kLegendWidth);
  svg << "</svg>";
  html << "<figure class='chart'><h2>Trajectory</h2>" << svg.str()
       << "<figcaption>Camera positions (x, z), equal scale; lines join each of "
       << op.marked << " to its match.</figcaption></figure>\n";
}

void timing_section(std::ostream& html, const ReportInput& in) {
  const Metrics& m = *in.metrics;
  struct Row {
    const char* name;
    double median;
    double Timings::*field;  // nullptr: image loading (FrameRecord::load_ms)
  };
  const Row rows[] = {{"load image", m.load_ms_median, nullptr},
                      {"convert to gray", m.convert_ms_median, &Timings::convert_ms},
                      {"segment", m.segment_ms_median, &Timings::segment_ms},
                      {"describe", m.describe_ms_median, &Timings::describe_ms},
                      {"search", m.search_ms_median, &Timings::search_ms},
                      {"verify", m.verify_ms_median, &Timings::verify_ms},
                      {"process() total", m.ms_per_frame_median, &Timings::total_ms}};
  double longest = 1e-9;
  for (const Row& r : rows) longest = std::max(longest, r.median);
  html << "<section class='timing'><h2>Time per frame</h2><table class='numbers'><tr><th>stage</th>"
          "<th>median ms</th><th>p95 ms</th><th></th></tr>";
  for (const Row& r : rows) {
    std::vector<double> values;
    for (const FrameRecord& f : *in.records)
      values.push_back(r.field ? f.timings.*r.field : f.load_ms);
    html << "<tr><td>" << r.name << "</td><td>" << num(r.median, 3) << "</td><td>"
         << num(percentile(values, 0.95), 3)
         << "</td><td><span class='bar' style='width:" << num(120 * r.median / longest, 0)
         << "px'></span></td></tr>";
  }
  html << "</table><p class='caption'>Wall time on one thread, " << in.records->size()
       << " frames; p95 by nearest rank; loading the image is outside process(); mean of process() "
       << num(m.ms_per_frame_mean, 3)
       << " ms (the t of PRT).</p><h2>Resources</h2><table class='numbers'>"
       << "<tr><td>dynamic nodes</td><td>" << in.nodes << "</td></tr>";
  if (in.bytes_per_frame > 0) {
    html << "<tr><td>bytes per frame</td><td>" << in.bytes_per_frame << "</td></tr><tr><td>"
         << "descriptor memory</td><td>"
         << num(static_cast<double>(in.bytes_per_frame) * m.frames / (1024.0 * 1024.0), 1)
         << " MiB</td></tr>";
  }
  html << "</table></section>\n";
}

const char* const kStyle = R"(
body{font:14px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0}
body{color:#1f2937;background:#fff}
main{max-width:1180px;margin:0 auto;padding:18px 16px}
h1{font-size:22px;margin:0 0 10px;word-break:break-all}h2{font-size:16px;margin:0 0 6px}
.facts{border-collapse:collapse;margin-bottom:12px}
.facts th{text-align:left;color:#6b7280;font-weight:500;padding:1px 14px 1px 0;vertical-align:top}
.facts td{padding:1px 0}
.path{font-family:ui-monospace,Menlo,Consolas,monospace;word-break:break-all}
.cards{display:flex;flex-wrap:wrap;gap:10px;margin:6px 0 16px}
.card{border:1px solid #e5e7eb;border-radius:8px;padding:8px 14px;min-width:96px}
.card{background:#f9fafb}
.warning{background:#fef3c7;border-left:4px solid #d97706;padding:6px 10px;max-width:760px}
.card .value{font-size:22px;font-weight:600}.card .name{color:#6b7280;font-size:12px}
.row{display:flex;flex-wrap:wrap;gap:20px;margin-bottom:18px}figure{margin:0;width:560px}
figcaption,.caption,.note{color:#4b5563;font-size:13px;max-width:760px}.note{font-style:italic}
section{margin-bottom:18px}svg text{font-family:system-ui,sans-serif;fill:#374151}
svg .tick{font-size:11px}svg .title{font-size:13px}svg .legend{font-size:12px}
svg .grid{stroke:#e5e7eb}svg .axis{stroke:#6b7280}svg .frame{fill:none;stroke:#6b7280}
.legend-html{font-size:13px;margin:2px 0 4px 70px}
.legend-html .sw{display:inline-block;width:14px;height:10px;vertical-align:middle}
.legend-html .dot{display:inline-block;width:10px;height:10px;border-radius:50%}
.legend-html .dot{vertical-align:middle}
.timing{width:560px;margin:0}table.numbers{border-collapse:collapse;margin-bottom:14px}
table.numbers th,table.numbers td{padding:3px 10px;white-space:nowrap;text-align:right}
table.numbers th,table.numbers td{border-bottom:1px solid #e5e7eb}
table.numbers th:first-child,table.numbers td:first-child{text-align:left}
.bar{display:inline-block;height:10px;background:#93c5fd;border-radius:2px}
pre{background:#f3f4f6;border-radius:6px;padding:10px 14px;font-size:12px;overflow:auto}
.gallery{display:flex;flex-wrap:wrap;gap:10px}.example{margin:0;border:2px solid;border-radius:6px;padding:6px}
.thumbs{display:flex;gap:6px}.thumb .caption{font-size:11px}.nothumb{font-size:11px;max-width:160px;color:#6b7280}
)";

}  // namespace report

using namespace report;  // the sections and their helpers (report_svg.h)

void ReportInput::check() const {
  if (!metrics || !records || !gt) {
    internal::throw_invalid("report: metrics, records and gt are required (",
                            !metrics   ? "metrics"
                            : !records ? "records"
                                       : "gt",
                            " is null)");
  }
  if (gt->frames() < 1) internal::throw_invalid("report: the ground truth has no frame");
  internal::check_range("report: max_matrix_frames", max_matrix_frames, 2, 4000);
  if (!trajectory.empty() && static_cast<std::int64_t>(trajectory.size()) != gt->frames()) {
    internal::throw_invalid("report: trajectory has ", trajectory.size(),
                            " positions but the ground truth ", gt->frames(), " frames");
  }
  for (const auto& p : trajectory) {
    if (!std::isfinite(p[0]) || !std::isfinite(p[1])) {
      internal::throw_invalid("report: trajectory position (", p[0], ", ", p[1], ") is not finite");
    }
  }
  // Positions of +-1e308 are finite, but their span is not: the map's
  // scale was NaN and every point '-nan'.
  if (const std::string span = trajectory_span_beyond_doubles(trajectory); !span.empty()) {
    internal::throw_invalid("report: the trajectory's ", span);
  }
  internal::check_range("report: max_examples", max_examples, 0, 50);
  if (width < 0 || height < 0 || grid_rows < 0 || grid_cols < 0) {
    internal::throw_invalid("report: image size ", width, "x", height, " or grid ", grid_rows, "x",
                            grid_cols, " is negative");
  }
  for (const ComparedSystem& c : compared) {
    if (c.metrics.min_gap != metrics->min_gap || c.metrics.protocol != metrics->protocol) {
      internal::throw_invalid("report: compared system '", c.name, "' was scored with window ",
                              c.metrics.min_gap, " (", c.metrics.protocol, "), not ",
                              metrics->min_gap, " (", metrics->protocol, ")");
    }
  }
  if (threshold && !std::isfinite(*threshold)) {
    internal::throw_invalid("report: threshold = ", *threshold, " is not finite");
  }
  for (const FrameRecord& r : *records) {
    if (r.frame < 0 || r.frame >= gt->frames() || r.reported.frame >= gt->frames()) {
      internal::throw_invalid("report: record of frame ", r.frame, " (reported ", r.reported.frame,
                              ") is outside the ground truth's ", gt->frames(), " frames");
    }
  }
}

std::string render_report(const ReportInput& in) {
  in.check();
  const Operating op = operating_point(in);
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'><title>"
       << escape(in.title.empty() ? "lsgd evaluation: " + in.sequence : in.title)
       << "</title><style>" << kStyle << "</style></head><body><main>\n";
  header(html, in, op);
  html << "<div class='row'>";
  pr_curve(html, in, op);
  if (!in.trajectory.empty()) {
    trajectory_section(html, in, op);
  } else {
    timeline_section(html, in, op);
  }
  score_histogram(html, in, op);
  timing_section(html, in);
  html << "</div>\n";
  if (in.image) examples_section(html, in, op);
  matrix_section(html, in, op);
  if (!in.config_yaml.empty()) {
    html << "<section><h2>Configuration</h2><pre>" << escape(in.config_yaml)
         << "</pre></section>\n";
  }
  html << "<footer class='caption'>Written by lsgd; self-contained (no script, no external "
          "resource).</footer></main></body></html>\n";
  return html.str();
}

void write_report(const ReportInput& input, const std::string& path) {
  io::write_output_file(path, render_report(input), "report");
}

}  // namespace lsgd::eval
