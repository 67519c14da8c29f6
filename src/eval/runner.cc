#include "lsgd/eval/runner.h"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <memory>
#include <new>

#include <opencv2/core.hpp>

#include "internal/check.h"
#include "lsgd/error.h"
#include "lsgd/limits.h"

namespace lsgd::eval {
namespace {

// Re-throws `e` (an lsgd error) with the frame and its source prefixed, keeping its type.
[[noreturn]] void rethrow_for_frame(const Error& e, std::int64_t frame, const std::string& name) {
  const std::string message = internal::concat("frame ", frame, " (", name, "): ", e.what());
  if (dynamic_cast<const ResourceError*>(&e)) {
    throw ResourceError(message + "; the run stops here, the frames before it are done");
  }
  if (dynamic_cast<const IoError*>(&e)) throw IoError(message);
  if (dynamic_cast<const FormatError*>(&e)) throw FormatError(message);
  if (dynamic_cast<const InvalidArgument*>(&e)) throw InvalidArgument(message);
  throw Error(message);
}

// CPU time of the calling thread, milliseconds.
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// Throws unless the source has frames, `options.first` lies in it, the stored ids
// are the detector's and increase below the first new id, and the new ids fit.
void check_run(const Detector& detector, const FrameSource& source, const RunOptions& options) {
  if (source.frames <= 0 || !source.load) {
    internal::throw_invalid("run_detector: the frame source is empty (", source.frames,
                            " frames)");
  }
  if (options.first < 0 || options.first > source.frames) {
    internal::throw_invalid("run_detector: first frame ", options.first, " is outside the ",
                            source.frames, " frames of the source");
  }
  const std::vector<std::int64_t>& ids = options.stored_ids;
  if (static_cast<std::int64_t>(ids.size()) != detector.size()) {
    internal::throw_invalid("run_detector: ", ids.size(), " stored ids for a detector holding ",
                            detector.size(), " frames");
  }
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const std::int64_t bound = k + 1 < ids.size() ? ids[k + 1] : options.first_id + options.first;
    if (ids[k] < 0 || ids[k] >= bound) {
      internal::throw_invalid("run_detector: stored id ", ids[k], " is negative or not below ",
                              "the next id ", bound);
    }
    // The detector keeps the ids it was given (Detector::id_of): the same.
    if (ids[k] != detector.id_of(static_cast<std::int64_t>(k))) {
      internal::throw_invalid("run_detector: stored id ", ids[k], " of frame ", k, " is not the detector's ",
                              detector.id_of(static_cast<std::int64_t>(k)));
    }
  }
  if (options.first_id < 0 || options.first_id > kMaxFrameId - source.frames) {
    internal::throw_invalid("run_detector: first id ", options.first_id, " is outside [0, ",
                            kMaxFrameId - source.frames, "]");
  }
}

// Loads source frame `i` and gives it to the detector as `id`; sets the load and CPU times.
Result load_and_process(Detector& detector, const FrameSource& source, std::int64_t i,
                        std::int64_t id, FrameTimes& times) {
  const auto start = std::chrono::steady_clock::now();
  const cv::Mat image = source.load_sized && detector.size() > 0
                            ? source.load_sized(i, detector.width(), detector.height())
                            : source.load(i);
  times.load_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const double cpu_start = thread_cpu_ms();
  Result result = detector.process(image, id, source.stamp ? source.stamp(i) : kNoStamp);
  times.process_cpu_ms = thread_cpu_ms() - cpu_start;
  return result;
}

// A frame the detector refused: re-thrown, or reported and (kept records) marked skipped.
void skip_frame(const Error& e, const FrameSource& source, std::int64_t i, std::int64_t id,
                const FrameTimes& times, const RunOptions& options, const SkipCallback& on_skip,
                std::vector<FrameRecord>& records) {
  const std::string name = source.name ? source.name(i) : std::to_string(i);
  // A resource the system ran out of (file descriptors) is not a bad image:
  // skipping would drop good frames one after the other.
  if (!options.skip_bad_frames || dynamic_cast<const ResourceError*>(&e)) rethrow_for_frame(e, id, name);
  if (on_skip) on_skip(id, name, e.what());
  if (options.keep_records) {
    FrameRecord skipped;
    skipped.frame = id;
    skipped.load_ms = times.load_ms;
    skipped.skipped = true;
    records.push_back(skipped);
  }
}

// The detector ran out of memory on frame `id` (a memory limit, a frame too
// large for it): the run stops there, naming the frame, rather than in
// std::bad_alloc or OpenCV's bare message. Not a skip: the detector may be
// part way through the frame. Frames given to the callback before it stay.
[[noreturn]] void out_of_memory(const FrameSource& source, std::int64_t i, std::int64_t id) {
  const std::string name = source.name ? source.name(i) : std::to_string(i);
  throw Error(internal::concat("frame ", id, " (", name, "): out of memory while processing it; "
                               "the frames before it are done"));
}

// Renames the detector's dense frame numbers in `result` to the run's ids.
void to_run_ids(Result& result, const std::vector<std::int64_t>& ids) {
  const auto to_id = [&](std::int64_t dense) {
    return dense >= 0 && dense < static_cast<std::int64_t>(ids.size())
               ? ids[static_cast<std::size_t>(dense)]
               : dense;
  };
  result.best.frame = to_id(result.best.frame);
  result.ranking.best.frame = to_id(result.ranking.best.frame);
  for (Candidate& c : result.candidates) c.frame = to_id(c.frame);
  for (StageVerdict& v : result.verification) v.candidate = to_id(v.candidate);
}

}  // namespace

FrameRecord record_of(Result result, double load_ms) {
  FrameRecord record;
  record.frame = result.frame;
  record.reported = result.best;
  record.loop = result.loop;
  record.ranking = result.ranking;
  record.candidates = std::move(result.candidates);
  record.timings = result.timings;
  record.load_ms = load_ms;
  return record;
}

FrameSource sequence_source(const io::Sequence& sequence) {
  FrameSource source;
  source.frames = static_cast<std::int64_t>(sequence.images.size());
  const auto images = std::make_shared<std::vector<std::string>>(sequence.images);
  source.load = [images](std::int64_t i) { return io::read_image(images->at(i)); };
  source.load_sized = [images](std::int64_t i, int width, int height) {
    return io::read_image(images->at(i), width, height);
  };
  source.name = [images](std::int64_t i) { return images->at(i); };
  if (!sequence.stamps.empty()) {
    const auto stamps = std::make_shared<std::vector<double>>(sequence.stamps);
    source.stamp = [stamps](std::int64_t i) { return stamps->at(static_cast<std::size_t>(i)); };
  }
  return source;
}

std::vector<std::string> setup_warnings(const Detector& detector, const GroundTruth& gt) {
  std::vector<std::string> out;
  const DetectorOptions& o = detector.options();
  const std::int64_t min_gap = o.search.min_gap;
  const int w = detector.width(), h = detector.height();
  if (w > 0 && h > 0) {
    const int sp = o.segmentation.superpixel_size;
    const FrameSize work = working_size(w, h, o.segmentation);
    const GridSize grid = grid_size(work.width, work.height, sp);
    if (grid.cells() < 4) {
      out.push_back(internal::concat(
          "frames of ", w, "x", h,
          work.width != w || work.height != h
              ? internal::concat(" (segmented at ", work.width, "x", work.height, ")")
              : std::string(),
          " give a ", grid.rows, "x", grid.cols, " grid at segmentation.superpixel_size ", sp, " (",
          grid.cells(), " cell", grid.cells() == 1 ? "" : "s",
          ", fewer than 4): the descriptor is almost a whole-image histogram and cannot tell places "
          "apart; use superpixel_size <= ",
          std::max(2, std::min(work.width, work.height) / 2)));
    }
    if (o.verification.has(kGeometricStage) && std::min(w, h) < 100) {
      out.push_back(internal::concat(
          "frames of ", w, "x", h, " are too small for geometric verification (ORB works on them "
          "upscaled ", std::lround(o.verification.geometric_options.working_scale(w, h)),
          "x): it will confirm few loops"));
    }
  }
  const std::int64_t scored = first_scored_query(min_gap);
  std::int64_t early = 0, positives = 0;
  for (std::int64_t q = 0; q < gt.frames(); ++q) {
    if (!gt.has_loop(q, min_gap)) continue;
    ++positives;
    early += q < scored ? 1 : 0;
  }
  if (gt.frames() <= scored) {
    out.push_back(internal::concat("the sequence has ", gt.frames(),
                                   " frames: the detector scores candidates from frame ", scored,
                                   " (search.min_gap + enough candidates for ", kMinCalibration,
                                   " similarities) and cannot report a loop before"));
  } else if (early > 0) {
    out.push_back(internal::concat(early, " of ", positives,
                                   " ground-truth loop queries come before frame ", scored,
                                   ", where the detector starts scoring candidates (search.min_gap "
                                   "+ enough candidates for ", kMinCalibration, " similarities)"));
  }
  return out;
}

std::vector<FrameRecord> run_detector(Detector& detector, const FrameSource& source,
                                      const FrameCallback& on_frame, const RunOptions& options,
                                      const SkipCallback& on_skip) {
  check_run(detector, source, options);
  // The run's id of every frame the detector holds (the detector's frame
  // numbers are dense; its ids, Detector::id_of, are these).
  std::vector<std::int64_t> ids = options.stored_ids;
  std::vector<FrameRecord> records;
  if (options.keep_records) records.reserve(static_cast<std::size_t>(source.frames - options.first));
  ids.reserve(ids.size() + static_cast<std::size_t>(source.frames - options.first));
  for (std::int64_t i = options.first; i < source.frames; ++i) {
    const std::int64_t id = options.first_id + i;
    Result result;
    FrameTimes times;
    try {
      result = load_and_process(detector, source, i, id, times);
    } catch (const Error& e) {
      skip_frame(e, source, i, id, times, options, on_skip, records);
      continue;
    } catch (const std::bad_alloc&) {
      out_of_memory(source, i, id);
    } catch (const cv::Exception& e) {
      if (e.code != cv::Error::StsNoMem) throw;
      out_of_memory(source, i, id);
    }
    ids.push_back(id);
    result.frame = id;
    to_run_ids(result, ids);
    if (on_frame) on_frame(result, times);
    if (options.keep_records) records.push_back(record_of(std::move(result), times.load_ms));
  }
  return records;
}

}  // namespace lsgd::eval
