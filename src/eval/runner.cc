#include "lsgd/eval/runner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include <opencv2/core.hpp>

#include "internal/check.h"
#include "lsgd/error.h"

namespace lsgd::eval {
namespace {

// Re-throws `e` (an lsgd error) with the frame and its source prefixed, keeping its type.
[[noreturn]] void rethrow_for_frame(const Error& e, std::int64_t frame, const std::string& name) {
  const std::string message = internal::concat("frame ", frame, " (", name, "): ", e.what());
  if (dynamic_cast<const IoError*>(&e)) throw IoError(message);
  if (dynamic_cast<const FormatError*>(&e)) throw FormatError(message);
  if (dynamic_cast<const InvalidArgument*>(&e)) throw InvalidArgument(message);
  throw Error(message);
}

}  // namespace

FrameSource sequence_source(const io::Sequence& sequence) {
  FrameSource source;
  source.frames = static_cast<std::int64_t>(sequence.images.size());
  const auto images = std::make_shared<std::vector<std::string>>(sequence.images);
  source.load = [images](std::int64_t i) { return io::read_image(images->at(i)); };
  source.name = [images](std::int64_t i) { return images->at(i); };
  return source;
}

std::vector<std::string> setup_warnings(const Detector& detector, const GroundTruth& gt) {
  std::vector<std::string> out;
  const DetectorOptions& o = detector.options();
  const std::int64_t min_gap = o.search.min_gap;
  const int w = detector.width(), h = detector.height();
  if (w > 0 && h > 0) {
    const int sp = o.segmentation.superpixel_size;
    const GridSize grid = grid_size(w, h, sp);
    if (grid.cells() < 4) {
      out.push_back(internal::concat(
          "frames of ", w, "x", h, " give a ", grid.rows, "x", grid.cols,
          " grid at segmentation.superpixel_size ", sp, " (", grid.cells(),
          " cell", grid.cells() == 1 ? "" : "s", ", fewer than 4): the descriptor is almost a "
          "whole-image histogram and cannot tell places apart; use superpixel_size <= ",
          std::max(2, std::min(w, h) / 2)));
    }
    if (o.verification.geometric && std::min(w, h) < 100) {
      out.push_back(internal::concat(
          "frames of ", w, "x", h, " are too small for geometric verification (ORB works on them "
          "upscaled ", std::lround(detector.geometric_verifier().working_scale(w, h)),
          "x): it will confirm few loops"));
    }
  }
  const std::int64_t calibrated = min_gap + kMinCalibration;
  std::int64_t early = 0, positives = 0;
  for (std::int64_t q = 0; q < gt.frames(); ++q) {
    if (!gt.has_loop(q, min_gap)) continue;
    ++positives;
    early += q < calibrated ? 1 : 0;
  }
  if (gt.frames() <= calibrated) {
    out.push_back(internal::concat("the sequence has ", gt.frames(),
                                   " frames: the detector calibrates its scores from frame ",
                                   calibrated, " (search.min_gap + ", kMinCalibration,
                                   " candidates) and cannot report a loop before"));
  } else if (early > 0) {
    out.push_back(internal::concat(early, " of ", positives,
                                   " ground-truth loop queries come before frame ", calibrated,
                                   ", where the detector starts reporting (search.min_gap + ",
                                   kMinCalibration, " candidates to calibrate its scores)"));
  }
  return out;
}

std::vector<FrameRecord> run_detector(Detector& detector, const FrameSource& source,
                                      const FrameCallback& on_frame, const RunOptions& options,
                                      const SkipCallback& on_skip) {
  if (source.frames <= 0 || !source.load) {
    internal::throw_invalid("run_detector: the frame source is empty (", source.frames,
                            " frames)");
  }
  std::vector<FrameRecord> records;
  records.reserve(static_cast<std::size_t>(source.frames));
  // Source index of every frame the detector stored (its ids are dense).
  std::vector<std::int64_t> source_of;
  source_of.reserve(static_cast<std::size_t>(source.frames));
  const auto to_source = [&](std::int64_t id) {
    return id >= 0 && id < static_cast<std::int64_t>(source_of.size())
               ? source_of[static_cast<std::size_t>(id)]
               : id;
  };
  for (std::int64_t i = 0; i < source.frames; ++i) {
    const auto start = std::chrono::steady_clock::now();
    Result result;
    double load_ms = 0;
    try {
      const cv::Mat image = source.load(i);
      load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                    .count();
      result = detector.process(image);
    } catch (const Error& e) {
      const std::string name = source.name ? source.name(i) : std::to_string(i);
      if (!options.skip_bad_frames) rethrow_for_frame(e, i, name);
      if (on_skip) on_skip(i, name, e.what());
      FrameRecord skipped;
      skipped.frame = i;
      skipped.load_ms = load_ms;
      skipped.skipped = true;
      records.push_back(skipped);
      continue;
    }
    source_of.push_back(i);
    result.frame = i;
    result.best.frame = to_source(result.best.frame);
    for (Candidate& c : result.candidates) c.frame = to_source(c.frame);
    for (StageVerdict& v : result.verification) v.candidate = to_source(v.candidate);
    if (on_frame) on_frame(result, load_ms);
    FrameRecord record;
    record.frame = result.frame;
    record.reported = result.best;
    record.loop = result.loop;
    record.candidates = result.candidates;
    record.timings = result.timings;
    record.load_ms = load_ms;
    records.push_back(std::move(record));
  }
  return records;
}

}  // namespace lsgd::eval
