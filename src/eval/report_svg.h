// What the sections of the HTML report share (src/eval/report*.cc): text
// and number formatting, the SVG chart primitives, the colours and the
// operating point the charts mark. Internal to lsgd_eval.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <opencv2/core.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "internal/check.h"
#include "lsgd/eval/report.h"

namespace lsgd::eval::report {

using internal::concat;

// Colours shared by the charts, the legends and the CSS.
inline constexpr const char* kTpColour = "#1a9641";       // true positive loop
inline constexpr const char* kFpColour = "#e41a1c";       // false positive loop
inline constexpr const char* kGtColour = "#ff00ff";       // ground-truth loops (matrix outline)
inline constexpr const char* kGtFrameColour = "#f59e0b";  // frames with a GT loop (trajectory)
inline constexpr const char* kCurveColour = "#2563eb";    // PR curve
inline const cv::Vec3b kGtBgr(255, 0, 255);               // kGtColour in OpenCV's BGR order
inline constexpr int kMatrixPixels = 600;
// Curves of compared systems, in order (then repeating).
inline const char* compared_colour(std::size_t k) {
  static const char* const kColours[] = {"#f97316", "#7c3aed", "#0891b2", "#be185d", "#65a30d"};
  return kColours[k % 5];
}                 // displayed side of the similarity matrix

// ---------------------------------------------------------------- text

inline std::string escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// printf-style formatting of one number (the charts need fixed precision).
inline std::string num(double value, int decimals = 1) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

inline std::string percent(double fraction) { return num(100.0 * fraction, 1) + "&#8239;%"; }

inline std::string base64(const std::vector<uchar>& bytes) {
  static const char* const kAlphabet =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t b0 = bytes[i];
    const std::uint32_t b1 = i + 1 < bytes.size() ? bytes[i + 1] : 0;
    const std::uint32_t b2 = i + 2 < bytes.size() ? bytes[i + 2] : 0;
    const std::uint32_t v = (b0 << 16) | (b1 << 8) | b2;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[v & 63] : '=';
  }
  return out;
}

// ---------------------------------------------------------------- charts

// Linear map from data [lo, hi] to pixels [p0, p1] (p1 < p0 for a y axis).
struct Scale {
  double lo, hi, p0, p1;
  double operator()(double v) const { return p0 + (v - lo) / (hi - lo) * (p1 - p0); }
};

// The round step (1, 2 or 5 x 10^k) that puts about `target` ticks on [lo, hi].
inline double tick_step(double lo, double hi, int target) {
  const double raw = (hi - lo) / std::max(target, 1);
  if (!(raw > 0) || !std::isfinite(raw)) return 0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double best = magnitude;
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {  // nearest to raw on a log scale
    if (std::abs(std::log(m * magnitude / raw)) < std::abs(std::log(best / raw)))
      best = m * magnitude;
  }
  return best;
}

// Round tick values inside [lo, hi], about `target` of them.
inline std::vector<double> ticks(double lo, double hi, int target) {
  const double step = tick_step(lo, hi, target);
  if (step == 0) return {lo};
  std::vector<double> out;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step) {
    out.push_back(std::abs(v) < 1e-9 * step ? 0.0 : v);
  }
  return out;
}

// Decimals that print every tick of `values` distinctly.
inline int tick_decimals(const std::vector<double>& values) {
  if (values.size() < 2) return 2;
  const double step = values[1] - values[0];
  return std::clamp(static_cast<int>(std::ceil(-std::log10(step) - 1e-9)), 0, 4);
}

// A plot area in pixels: left, top, right, bottom.
struct Rect {
  double x0, y0, x1, y1;
};

// Frame, ticks (with grid lines when `grid`), tick labels and axis titles of a plot area.
inline void axes(std::ostream& svg, const Rect& r, const Scale& x, const Scale& y,
          const std::vector<double>& xt, const std::vector<double>& yt, const std::string& x_title,
          const std::string& y_title, bool grid) {
  const int xd = tick_decimals(xt), yd = tick_decimals(yt);
  for (const double v : xt) {
    const double px = x(v);
    if (grid)
      svg << "<line class='grid' x1='" << px << "' y1='" << r.y0 << "' x2='" << px << "' y2='"
          << r.y1 << "'/>";
    svg << "<line class='axis' x1='" << px << "' y1='" << r.y1 << "' x2='" << px << "' y2='"
        << r.y1 + 5 << "'/>"
        << "<text class='tick' x='" << px << "' y='" << r.y1 + 18 << "' text-anchor='middle'>"
        << num(v, xd) << "</text>";
  }
  for (const double v : yt) {
    const double py = y(v);
    if (grid)
      svg << "<line class='grid' x1='" << r.x0 << "' y1='" << py << "' x2='" << r.x1 << "' y2='"
          << py << "'/>";
    svg << "<line class='axis' x1='" << r.x0 - 5 << "' y1='" << py << "' x2='" << r.x0 << "' y2='"
        << py << "'/>"
        << "<text class='tick' x='" << r.x0 - 8 << "' y='" << py + 4 << "' text-anchor='end'>"
        << num(v, yd) << "</text>";
  }
  svg << "<rect class='frame' x='" << r.x0 << "' y='" << r.y0 << "' width='" << r.x1 - r.x0
      << "' height='" << r.y1 - r.y0 << "'/>"
      << "<text class='title' x='" << (r.x0 + r.x1) / 2 << "' y='" << r.y1 + 38
      << "' text-anchor='middle'>" << escape(x_title) << "</text>"
      << "<text class='title' transform='translate(" << r.x0 - 50 << ' ' << (r.y0 + r.y1) / 2
      << ") rotate(-90)' text-anchor='middle'>" << escape(y_title) << "</text>";
}

// The plot area of the 560 x 480 charts (the legend goes under the axis title).
inline constexpr Rect kChart{70, 20, 540, 380};
// Where the legend of a chart starts (x, y) and how wide it may run.
inline constexpr double kLegendX = kChart.x0, kLegendY = kChart.y1 + 66, kLegendWidth = 550;
// Scales onto the chart's plot area: x left to right, y bottom to top.
inline Scale chart_x(double lo, double hi) { return {lo, hi, kChart.x0, kChart.x1}; }
inline Scale chart_y(double lo, double hi) { return {lo, hi, kChart.y1, kChart.y0}; }

// One legend entry: a swatch (line, dot or box) and its label; returns its width in pixels.
inline double legend_row(std::ostream& svg, double x, double y, const std::string& swatch,
                  const std::string& colour, const std::string& label) {
  if (swatch == "line") {
    svg << "<line class='swatch' x1='" << x << "' y1='" << y << "' x2='" << x + 22 << "' y2='" << y
        << "' stroke='" << colour << "' stroke-width='2.5'/>";
  } else if (swatch == "box") {
    svg << "<rect x='" << x + 4 << "' y='" << y - 6
        << "' width='14' height='12' fill='none' stroke='" << colour << "' stroke-width='2'/>";
  } else {
    svg << "<circle cx='" << x + 11 << "' cy='" << y << "' r='5' fill='" << colour
        << "' stroke='#fff' stroke-width='1'/>";
  }
  svg << "<text class='legend' x='" << x + 30 << "' y='" << y + 4 << "'>" << label << "</text>";
  return 30 + 6.8 * static_cast<double>(label.size()) + 18;  // ~6.8 px per character at 12 px
}

struct LegendItem {
  const char* swatch;
  const char* colour;
  std::string label;
};

// A horizontal legend under a chart, wrapped at x = right.
inline void legend(std::ostream& svg, const std::vector<LegendItem>& items, double x0, double y,
            double right) {
  double x = x0;
  for (const LegendItem& item : items) {
    const double width = 48 + 6.8 * static_cast<double>(item.label.size());
    if (x > x0 && x + width > right) x = x0, y += 20;
    x += legend_row(svg, x, y, item.swatch, item.colour, item.label);
  }
}

// ---------------------------------------------------------------- loops

struct Loop {
  std::int64_t query, match;
  double score;
  bool correct;
};

// The reported loops at the operating threshold, with how the threshold was chosen.
struct Operating {
  double threshold = std::numeric_limits<double>::infinity();
  // HTML noun phrases for sentences: the loops the charts mark ("the loops
  // the system declared ...", "the reports scoring at least ..."), and what
  // the dashed line is ("" when there is none).
  std::string marked;
  std::string line;
  std::vector<Loop> loops;
  std::int64_t tp = 0, fp = 0;
};

inline bool correct_loop(const GroundTruth& gt, std::int64_t query, std::int64_t match,
                  std::int64_t min_gap) {
  return match >= 0 && match < query - min_gap && gt.is_loop(query, match);
}

inline Operating operating_point(const ReportInput& in) {
  Operating op;
  const Metrics& m = *in.metrics;
  if (in.declared) {
    op.marked = "the loops the system declared with its own settings (no ground truth involved)";
  } else if (in.threshold) {
    op.threshold = *in.threshold;
    op.line = escape(in.threshold_name) + " " + num(op.threshold, 4);
    op.marked = "the reports scoring at least " + op.line;
  } else if (m.decision_recall_at_100_precision > 0) {
    // The loops are the decision's (their loop scores): its own R@100P threshold.
    op.threshold = m.decision_threshold_at_100_precision;
    op.line = "the loop score's R@100P threshold " + num(op.threshold, 4);
    op.marked = "the reports scoring at least " + op.line;
  } else {
    op.marked = "no loop (no threshold reaches precision 1)";
  }
  for (const FrameRecord& r : *in.records) {
    if (r.reported.frame < 0) continue;
    if (in.declared ? !r.loop : !(r.reported.score >= op.threshold)) continue;
    const bool ok = correct_loop(*in.gt, r.frame, r.reported.frame, m.min_gap);
    op.loops.push_back({r.frame, r.reported.frame, r.reported.score, ok});
    (ok ? op.tp : op.fp) += 1;
  }
  // Declared loops: the charts mark the lowest score declared.
  if (in.declared) {
    for (const Loop& l : op.loops) op.threshold = std::min(op.threshold, l.score);
    if (!op.loops.empty()) op.line = "the lowest loop score declared, " + num(op.threshold, 4);
  }
  return op;
}

// Sections written in report_frames.cc: example loops as thumbnails, and the
// score of every frame over time (when no trajectory is given).
void examples_section(std::ostream& html, const ReportInput& in, const Operating& op);
void timeline_section(std::ostream& html, const ReportInput& in, const Operating& op);

}  // namespace lsgd::eval::report
