#include "lsgd/detector.h"

#include <algorithm>
#include <chrono>
#include <cmath>
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
  descriptor.check();
  similarity.check();
  search.check();
  verification.check();
  decision.check();
}

Detector::Detector(const DetectorOptions& options)
    : options_(options),
      segmenter_((options.check(), options.segmentation)),
      temporal_(options.verification.temporal_options),
      geometric_(options.verification.geometric_options) {}

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

  // The histograms are counted during the segmentation's last pass, so
  // segment_ms includes them and describe_ms is the storage encoding.
  std::int64_t t = now_ns();
  segment_and_describe(segmenter_, gray_, segmentation_, exact_, describe_scratch_);
  result.timings.segment_ms = ms_since(t);

  t = now_ns();
  if (options_.descriptor.storage == HistogramStorage::kCompact) {
    compact(exact_, descriptor_);
  } else {
    std::swap(exact_, descriptor_);  // descriptor_ is the frame's descriptor as stored
  }
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
  result.timings.search_ms = ms_since(t);

  t = now_ns();
  verify(result);
  result.timings.verify_ms = ms_since(t);
  // A node's frames sit together in the store: scoring its members reads one
  // run of memory (FrameStore groups). The group is only a placement, so a
  // node the store has no group for (frames restored without their nodes)
  // gets a new one rather than an error.
  store_.add(descriptor_, std::clamp<std::int64_t>(result.node, 0, store_.groups()));
  if (result.frame == 0) width_ = gray_.width, height_ = gray_.height;

  result.loop = result.best.frame >= 0 && result.best.score >= options_.decision.threshold;
  result.timings.total_ms = ms_since(start_ns);
  return result;
}

// Re-ranks the candidates by sequence score (temporal), then examines the
// best ones in order and reports the first that every enabled gate accepts
// (the temporal agreement first: it is the cheaper one).
void Detector::verify(Result& result) {
  const VerificationOptions& v = options_.verification;
  if (v.geometric) geometric_.add(gray_);
  if (v.temporal) {
    temporal_.rescore(store_, descriptor_.view(), result.frame, result.candidates,
                      options_.search.min_gap, options_.similarity.metric, options_.search.top_n,
                      scratch_);
    result.candidates.swap(scratch_);
  }
  if (!v.temporal && !v.geometric) {
    if (!result.candidates.empty()) result.best = result.candidates.front();
    return;
  }
  const std::size_t n =
      std::min(result.candidates.size(), static_cast<std::size_t>(v.max_candidates));
  for (std::size_t i = 0; i < n && result.best.frame < 0; ++i) {
    const Candidate& candidate = result.candidates[i];
    bool accepted = true;
    if (v.temporal) {
      const std::int64_t start = now_ns();
      const auto check = temporal_.agree(result.frame, candidate);
      result.verification.push_back(
          {candidate.frame, "temporal", check.accepted, check.reason, ms_since(start)});
      accepted = check.accepted;
    }
    if (accepted && v.geometric) {
      const auto check = geometric_.verify(result.frame, candidate.frame);
      result.verification.push_back(
          {candidate.frame, "geometric", check.accepted, check.reason, check.ms});
      accepted = check.accepted;
    }
    if (accepted) result.best = candidate;
  }
  if (v.temporal) {
    temporal_.push(result.frame, result.candidates.empty() ? -1 : result.candidates.front().frame);
  }
}

void Detector::restore_frame(int width, int height, const Descriptor& descriptor,
                             const std::vector<float>& points, const std::vector<std::uint8_t>& orb,
                             std::int64_t node) {
  const std::int64_t frame = store_.size();
  const std::int64_t max_node =
      options_.search.mode == SearchMode::kDynamicNodes ? store_.groups() : 0;
  if (node < 0 || node > max_node) {
    internal::throw_invalid(
        "restore_frame: frame ", frame, " has node ", node, ": expected 0 to ", max_node,
        options_.search.mode == SearchMode::kDynamicNodes ? " (an earlier node or the next new one)"
                                                          : " (the search mode is exhaustive)");
  }
  if (width <= 0 || height <= 0 || (frame > 0 && (width != width_ || height != height_))) {
    internal::throw_invalid("restore_frame: frame ", frame, " is ", width, "x", height,
                            " but the detector holds ", width_, "x", height_, " frames");
  }
  const GridSize expected = grid_size(width, height, options_.segmentation.superpixel_size);
  if (descriptor.grid != expected) {
    internal::throw_invalid("restore_frame: frame ", frame, " has a ", descriptor.grid.rows, "x",
                            descriptor.grid.cols, " grid, but ", width, "x", height,
                            " frames have a ", expected.rows, "x", expected.cols, " grid");
  }
  if (descriptor.storage != options_.descriptor.storage) {
    internal::throw_invalid("restore_frame: frame ", frame, " has a ",
                            to_string(descriptor.storage), " descriptor but descriptor.storage is ",
                            to_string(options_.descriptor.storage));
  }
  descriptor.check_consistent("restore_frame");
  if (descriptor.storage == HistogramStorage::kCompact &&
      std::fabs(descriptor.cell_pixels * expected.cells() - static_cast<double>(width) * height) >
          0.5) {
    internal::throw_invalid("restore_frame: frame ", frame, " has ", descriptor.cell_pixels,
                            " pixels per cell, but ", width, "x", height, " frames have ",
                            static_cast<double>(width) * height / expected.cells());
  }
  if (!options_.verification.geometric && (!points.empty() || !orb.empty())) {
    internal::throw_invalid("restore_frame: frame ", frame,
                            " has ORB features but geometric verification is off");
  }
  // add_features() below validates too; checked here first so that a bad
  // frame leaves the store unchanged.
  if (points.size() % 2 != 0 || orb.size() != points.size() / 2 * 32 ||
      !std::all_of(points.begin(), points.end(), [](float v) { return std::isfinite(v); })) {
    internal::throw_invalid("restore_frame: frame ", frame, " has ", points.size(),
                            " keypoint coordinates and ", orb.size(),
                            " ORB bytes: not 2 finite coordinates and 32 bytes per keypoint");
  }
  store_.add(descriptor, node);
  if (options_.verification.geometric) geometric_.add_features(points, orb);
  width_ = width;
  height_ = height;
}

void Detector::restore_nodes(std::vector<std::vector<std::int64_t>> nodes) {
  if (options_.search.mode != SearchMode::kDynamicNodes) {
    internal::throw_invalid("restore_nodes: the search mode is ", to_string(options_.search.mode));
  }
  for (const auto& node : nodes) {
    for (const std::int64_t id : node) {
      if (id >= store_.size()) {
        internal::throw_invalid("restore_nodes: frame ", id, " is not stored (", store_.size(),
                                " frames)");
      }
    }
  }
  nodes_.restore(std::move(nodes));
}

void Detector::restore_temporal(std::int64_t last_query, std::vector<std::int64_t> places) {
  if (!options_.verification.temporal) {
    internal::throw_invalid("restore_temporal: temporal verification is off");
  }
  if (last_query != store_.size() - 1) {
    internal::throw_invalid("restore_temporal: last query ", last_query, " but ", store_.size(),
                            " frames are stored");
  }
  for (const std::int64_t place : places) {
    if (place >= store_.size()) {
      internal::throw_invalid("restore_temporal: place ", place, " is not stored");
    }
  }
  temporal_.restore(last_query, std::move(places));
}

}  // namespace lsgd
