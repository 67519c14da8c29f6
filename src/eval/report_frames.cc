// The report's sections about single frames: example loops as thumbnails
// and the score of every frame over time; whether a trajectory's positions
// can be drawn to scale.
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "eval/report_svg.h"
#include "internal/check.h"
#include "lsgd/error.h"

namespace lsgd::eval::report {
namespace {

constexpr int kThumbHeight = 110;  // pixels; width follows the image's aspect

// Frame f as an <img> with a JPEG data URI, or a note saying why there is none.
std::string thumbnail(const ReportInput& in, std::int64_t f) {
  try {
    const cv::Mat image = in.image(f);
    if (image.empty() || image.depth() != CV_8U) return "<div class='nothumb'>no image</div>";
    const int width = std::max(1, image.cols * kThumbHeight / std::max(1, image.rows));
    cv::Mat small;
    cv::resize(image, small, cv::Size(width, kThumbHeight), 0, 0,
               image.rows > kThumbHeight ? cv::INTER_AREA : cv::INTER_LINEAR);
    std::vector<uchar> jpeg;
    cv::imencode(".jpg", small, jpeg, {cv::IMWRITE_JPEG_QUALITY, 80});
    return "<img alt='frame " + std::to_string(f) + "' width='" + std::to_string(width) +
           "' height='" + std::to_string(kThumbHeight) + "' src='data:image/jpeg;base64," +
           base64(jpeg) + "'/>";
  } catch (const lsgd::Error& e) {
    return "<div class='nothumb'>frame " + std::to_string(f) + ": " + escape(e.what()) + "</div>";
  } catch (const cv::Exception& e) {
    return "<div class='nothumb'>frame " + std::to_string(f) + ": " + escape(e.what()) + "</div>";
  }
}

// One example: the query and the frames beside it, with a caption.
void pair(std::ostream& html, const ReportInput& in, const std::string& colour,
          const std::vector<std::pair<std::int64_t, std::string>>& frames, const std::string& caption) {
  html << "<figure class='example' style='border-color:" << colour << "'><div class='thumbs'>";
  for (const auto& [f, label] : frames) {
    html << "<div class='thumb'>" << thumbnail(in, f) << "<div class='caption'>" << escape(label)
         << "</div></div>";
  }
  html << "</div><figcaption>" << caption << "</figcaption></figure>";
}

// `n` items of `items` spread over it (all when there are fewer).
template <typename T>
std::vector<T> spread(const std::vector<T>& items, int n) {
  if (static_cast<int>(items.size()) <= n) return items;
  std::vector<T> out;
  for (int i = 0; i < n; ++i) out.push_back(items[items.size() * i / n]);
  return out;
}

}  // namespace

void examples_section(std::ostream& html, const ReportInput& in, const Operating& op) {
  const Metrics& m = *in.metrics;
  const int n = in.max_examples;
  std::vector<Loop> right, wrong;
  for (const Loop& l : op.loops) (l.correct ? right : wrong).push_back(l);
  // The false loops with the highest scores are the ones to look at first.
  std::stable_sort(wrong.begin(), wrong.end(), [](const Loop& a, const Loop& b) { return a.score > b.score; });
  wrong.resize(std::min<std::size_t>(wrong.size(), static_cast<std::size_t>(n)));
  // Missed revisits: positive queries without a correct marked loop.
  // Held per record and per loop, not per frame: detections may name frames
  // far beyond their rows.
  std::unordered_set<std::int64_t> found;
  for (const Loop& l : right) found.insert(l.query);
  std::unordered_map<std::int64_t, Candidate> reported;
  for (const FrameRecord& r : *in.records) reported[r.frame] = r.reported;
  std::vector<std::int64_t> missed;
  // Every ground-truth frame is a query, with a record or not (evaluate()).
  for (const std::int64_t q : in.gt->queries()) {
    if (!found.count(q) && in.gt->has_loop(q, m.min_gap)) missed.push_back(q);
  }

  html << "<section class='examples'><h2>Example loops</h2><p class='caption'>Query on the left, "
       << "the frame it was matched with on the right (loops: " << op.marked << "). Up to " << n
       << " of each kind: declared true loops spread over the run, the highest-scored false "
       << "ones, and missed revisits spread over the run.</p>";
  html << "<h3>True loops (" << right.size() << ")</h3><div class='gallery'>";
  for (const Loop& l : spread(right, n)) {
    pair(html, in, kTpColour, {{l.query, "query " + std::to_string(l.query)}, {l.match, "frame " + std::to_string(l.match)}},
         "score " + num(l.score, 2));
  }
  html << "</div><h3>False loops (" << op.fp << ")</h3><div class='gallery'>";
  if (wrong.empty()) html << "<p class='caption'>none</p>";
  for (const Loop& l : wrong) {
    const std::vector<std::int64_t>& truth = in.gt->matches(l.query);
    std::vector<std::pair<std::int64_t, std::string>> frames = {
        {l.query, "query " + std::to_string(l.query)}, {l.match, "declared " + std::to_string(l.match)}};
    if (!truth.empty()) frames.push_back({truth.back(), "true match " + std::to_string(truth.back())});
    pair(html, in, kFpColour, frames, "score " + num(l.score, 2) + (truth.empty() ? ", the query has no loop" : ""));
  }
  html << "</div><h3>Missed revisits (" << missed.size() << " of " << m.positives << " positives)</h3>"
       << "<div class='gallery'>";
  if (missed.empty()) html << "<p class='caption'>none</p>";
  for (const std::int64_t q : spread(missed, n)) {
    // The latest true match outside the window: the revisit a map would want.
    std::int64_t truth = -1;
    for (const std::int64_t j : in.gt->matches(q)) {
      if (j < q - m.min_gap) truth = j;
    }
    std::vector<std::pair<std::int64_t, std::string>> frames = {
        {q, "query " + std::to_string(q)}, {truth, "true match " + std::to_string(truth)}};
    const auto it = reported.find(q);
    const Candidate rep_of = it == reported.end() ? Candidate{} : it->second;
    const std::int64_t rep = rep_of.frame;
    if (rep >= 0 && rep != truth) frames.push_back({rep, "reported " + std::to_string(rep)});
    // Its score, against the loops marked: how far from a loop it was.
    const std::string score = rep >= 0 ? "score " + num(rep_of.score, 2) +
                                             (rep == truth ? ", the right place" : ", another place")
                                       : "nothing reported";
    pair(html, in, kGtFrameColour, frames,
         score + (rep >= 0 && op.threshold < std::numeric_limits<double>::infinity()
                      ? " (loops from " + num(op.threshold, 2) + ")"
                      : std::string()));
  }
  html << "</div></section>\n";
}

void timeline_section(std::ostream& html, const ReportInput& in, const Operating& op) {
  const Metrics& m = *in.metrics;
  const std::int64_t frames = in.gt->frames();
  double lo = 0, hi = 1;
  bool any = false;
  for (const FrameRecord& r : *in.records) {
    if (r.reported.frame < 0 || !std::isfinite(r.reported.score)) continue;
    lo = any ? std::min(lo, r.reported.score) : r.reported.score;
    hi = any ? std::max(hi, r.reported.score) : r.reported.score;
    any = true;
  }
  if (std::isfinite(op.threshold)) lo = std::min(lo, op.threshold), hi = std::max(hi, op.threshold);
  if (!(hi > lo)) hi = lo + 1;
  const Scale x = chart_x(0, static_cast<double>(std::max<std::int64_t>(frames - 1, 1)));
  const Scale y = chart_y(lo, hi);
  std::ostringstream svg;
  svg << "<svg class='timeline' width='560' height='480' viewBox='0 0 560 480' role='img'>";
  // Frames with a ground-truth loop outside the window: a band along the bottom.
  for (const std::int64_t q : in.gt->queries()) {
    if (!in.gt->has_loop(q, m.min_gap)) continue;
    svg << "<rect x='" << num(x(static_cast<double>(q)) - 0.5, 1) << "' y='" << kChart.y1 - 6
        << "' width='1.5' height='6' fill='" << kGtFrameColour << "'/>";
  }
  axes(svg, kChart, x, y, ticks(0, static_cast<double>(frames - 1), 8), ticks(lo, hi, 6), "frame",
       "score of the reported candidate", true);
  std::vector<char> declared(static_cast<std::size_t>(frames), 0);
  for (const Loop& l : op.loops) declared[static_cast<std::size_t>(l.query)] = l.correct ? 1 : 2;
  for (const FrameRecord& r : *in.records) {
    if (r.reported.frame < 0 || !std::isfinite(r.reported.score)) continue;
    const char d = declared[static_cast<std::size_t>(r.frame)];
    svg << "<circle cx='" << num(x(static_cast<double>(r.frame)), 1) << "' cy='"
        << num(y(r.reported.score), 1) << "' r='" << (d ? 2.6 : 1.6) << "' fill='"
        << (d == 1 ? kTpColour : d == 2 ? kFpColour : "#9ca3af") << "'/>";
  }
  if (std::isfinite(op.threshold)) {
    svg << "<line x1='" << kChart.x0 << "' y1='" << y(op.threshold) << "' x2='" << kChart.x1
        << "' y2='" << y(op.threshold) << "' stroke='#111' stroke-width='1.2' stroke-dasharray='5 3'/>";
  }
  legend(svg,
         {{"dot", kTpColour, "true loop"},
          {"dot", kFpColour, "false loop"},
          {"dot", "#9ca3af", "not a loop"},
          {"box", kGtFrameColour, "frame with a GT loop"}},
         kLegendX, kLegendY, kLegendWidth);
  svg << "</svg>";
  html << "<figure class='chart'><h2>Scores over the run</h2>" << svg.str()
       << "<figcaption>The score of each frame's reported candidate"
       << (op.line.empty() ? std::string() : "; dashed: " + op.line) << ".</figcaption></figure>\n";
}

}  // namespace lsgd::eval::report

namespace lsgd::eval {

std::string trajectory_span_beyond_doubles(const std::vector<std::array<double, 2>>& positions) {
  for (const int axis : {0, 1}) {
    double lo = 0, hi = 0;
    for (std::size_t k = 0; k < positions.size(); ++k) {
      lo = k == 0 ? positions[k][axis] : std::min(lo, positions[k][axis]);
      hi = k == 0 ? positions[k][axis] : std::max(hi, positions[k][axis]);
    }
    if (!std::isfinite(hi - lo)) {
      return internal::concat("positions span ", axis == 0 ? "x" : "z", " from ", lo, " to ", hi,
                              ", more than a double holds");
    }
  }
  return "";
}

}  // namespace lsgd::eval
