// Helpers of the tests of the HTML evaluation report (report_test,
// report_inputs_test, report_file_test): a short piece of the synthetic
// street run once per process, counts of a text, the embedded heatmap PNG
// decoded, and a check that tags are balanced. Header-only.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/eval/report.h"
#include "lsgd/eval/runner.h"
#include "lsgd/io/config.h"
#include "synthetic/synthetic.h"

namespace lsgd::eval::report_test_support {

inline constexpr std::int64_t kMinGap = 20;

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

inline const StreetRun& run() {
  static const StreetRun r;
  return r;
}

inline std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

inline std::vector<uchar> decode_base64(const std::string& text) {
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
inline cv::Mat heatmap(const std::string& html) {
  const std::string key = "data:image/png;base64,";
  const std::size_t p = html.find(key);
  if (p == std::string::npos) return {};
  const std::size_t begin = p + key.size();
  return cv::imdecode(decode_base64(html.substr(begin, html.find('\'', begin) - begin)),
                      cv::IMREAD_COLOR);
}

// Checks that every element is closed in order (void elements and "/>" aside),
// attribute values are quoted and no '<' appears inside text or attributes.
inline std::string tag_balance_error(const std::string& html) {
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

}  // namespace lsgd::eval::report_test_support
