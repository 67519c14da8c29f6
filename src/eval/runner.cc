#include "lsgd/eval/runner.h"

#include <chrono>
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
    records.push_back({result.frame, result.best, result.candidates, result.timings, load_ms});
  }
  return records;
}

}  // namespace lsgd::eval
