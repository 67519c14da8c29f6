#include "lsgd/detector.h"

#include <chrono>

#include <opencv2/core.hpp>

#include "internal/check.h"

namespace lsgd {
namespace {

using Clock = std::chrono::steady_clock;

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

double ms_since(std::int64_t start_ns) { return (now_ns() - start_ns) * 1e-6; }

}  // namespace

void DecisionOptions::check() const {
  internal::check_range("decision.threshold", threshold, 0.0, 1.0);
}

void DetectorOptions::check() const {
  segmentation.check();
  similarity.check();
  search.check();
  decision.check();
}

Detector::Detector(const DetectorOptions& options)
    : options_(options), segmenter_((options.check(), options.segmentation)) {}

Result Detector::process(const cv::Mat& frame) {
  const std::int64_t start = now_ns();
  to_gray(frame, gray_);
  return process_gray(ms_since(start), start);
}

Result Detector::process(const ImageView& frame) {
  const std::int64_t start = now_ns();
  to_gray(frame, gray_);
  return process_gray(ms_since(start), start);
}

std::int64_t Detector::nodes() const { return nodes_.size(); }

double Detector::similarity(std::int64_t a, std::int64_t b) const {
  return lsgd::similarity(store_.view(a), store_.view(b), options_.similarity.metric);
}

Result Detector::process_gray(double convert_ms, std::int64_t start_ns) {
  if (store_.size() > 0 && (gray_.width != width_ || gray_.height != height_)) {
    internal::throw_invalid("frame ", store_.size(), " is ", gray_.width, "x", gray_.height,
                            " but the first frame was ", width_, "x", height_,
                            ": every frame must have the same size");
  }
  Result result;
  result.frame = store_.size();
  result.timings.convert_ms = convert_ms;

  std::int64_t t = now_ns();
  segmenter_.segment(gray_, segmentation_);
  result.timings.segment_ms = ms_since(t);

  t = now_ns();
  describe(gray_, segmentation_, descriptor_);
  result.timings.describe_ms = ms_since(t);

  t = now_ns();
  const SimilarityMetric metric = options_.similarity.metric;
  if (options_.search.mode == SearchMode::kDynamicNodes) {
    const auto outcome = nodes_.assign(store_, descriptor_.view(), result.frame, options_.search,
                                       metric, scratch_, result.candidates);
    result.node = outcome.node;
    result.node_created = outcome.created;
  } else {
    search_exhaustive(store_, descriptor_.view(), result.frame, options_.search, metric, scratch_,
                      result.candidates);
  }
  store_.add(descriptor_);
  if (result.frame == 0) width_ = gray_.width, height_ = gray_.height;
  result.timings.search_ms = ms_since(t);

  if (!result.candidates.empty()) result.best = result.candidates.front();
  result.loop = result.best.frame >= 0 && result.best.score >= options_.decision.threshold;
  result.timings.total_ms = ms_since(start_ns);
  return result;
}

}  // namespace lsgd
