// Runs a Detector online over a source of frames, one frame at a time, and
// collects what it reported for the evaluation.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/eval/groundtruth.h"
#include "lsgd/eval/metrics.h"
#include "lsgd/io/sequence.h"

namespace cv {
class Mat;
}

namespace lsgd::eval {

// Frames 0 .. frames-1, loaded on demand (decoded from disk or generated).
struct FrameSource {
  std::int64_t frames = 0;
  std::function<cv::Mat(std::int64_t)> load;        // throws lsgd::Error on bad input
  std::function<std::string(std::int64_t)> name;    // e.g. the image path, for messages and CSV
  std::function<double(std::int64_t)> stamp;         // its time stamp (empty: none; KITTI's times.txt)
  // Optional: load(i) for a frame that must be width x height (the detector's
  // frames), refusing another size before decoding it (io::read_image).
  std::function<cv::Mat(std::int64_t, int width, int height)> load_sized;
};

// What the evaluation keeps of a processed frame's result (its report, loop,
// ranking, candidates and times), `load_ms` the time its image took to read.
FrameRecord record_of(Result result, double load_ms = 0);

// The images of a sequence, read with io::read_image.
FrameSource sequence_source(const io::Sequence& sequence);

// Times of one frame around Detector::process.
struct FrameTimes {
  double load_ms = 0;         // reading and decoding the image (FrameSource::load)
  double process_cpu_ms = 0;  // CPU time of this thread inside process()
};

// Called after each processed frame with its result, whose frame ids (its
// frame, best, candidates, verdicts) are the run's ids (RunOptions), also
// when earlier frames were skipped. The detector holds the frame already; an
// exception thrown here stops the run.
using FrameCallback = std::function<void(const Result& result, const FrameTimes& times)>;
// Called for each skipped frame: its id, name and the error.
using SkipCallback =
    std::function<void(std::int64_t frame, const std::string& name, const std::string& error)>;

// The one frame loop of lsgd: run, eval, sweep and bench all feed frames
// through run_detector, so they number, skip and time frames alike.
//
// Frame ids: source frame i has id first_id + i, whether or not earlier
// frames were skipped (a skipped frame keeps its id and stores nothing).
// Frames the detector already held before the run (restored from a
// database) keep the ids given in stored_ids.
struct RunOptions {
  // false: a frame that fails to load (missing, truncated, corrupt, not an
  // image) or that the detector rejects (other size, 16-bit) stops the run
  // with an lsgd::Error naming the frame and its source.
  // true: such a frame is skipped: `on_skip` is told, the detector never sees
  // it, and its record has no report (skipped = true), so a skipped
  // ground-truth loop counts as missed. Later frames keep their source index.
  bool skip_bad_frames = false;
  // Source frames before `first` are not loaded (resuming a run whose
  // earlier frames the detector holds already).
  std::int64_t first = 0;
  // Id of source frame 0.
  std::int64_t first_id = 0;
  // Ids of the frames the detector holds before the run, in its order
  // (strictly increasing, below first_id + first); empty for a new detector.
  std::vector<std::int64_t> stored_ids;
  // false: return no records (a long `lsgd run` needs none).
  bool keep_records = true;
};

// Warnings about a setup in which the method cannot work as intended, for
// `lsgd eval` to print (stderr), store (JSON) and show (HTML report): a grid of
// fewer than 4 cells (the descriptor is nearly a whole-image histogram),
// frames too small for geometric verification, and ground-truth loops before
// the detector scores candidates (first_scored_query(), evidence.h) or a
// sequence too short to reach that frame. `detector` has run over the
// sequence (its frame size is known); empty when all is well.
std::vector<std::string> setup_warnings(const Detector& detector, const GroundTruth& gt);

// Feeds frames first .. frames-1 to the detector in order and returns one
// record per frame fed (skipped ones included), record i for source frame
// first + i. Frames already processed were passed to `on_frame` (a CSV writer
// keeps them) before any error. Throws InvalidArgument for an empty source,
// `first` outside it, stored_ids that do not match the detector, or ids
// that would not increase.
std::vector<FrameRecord> run_detector(Detector& detector, const FrameSource& source,
                                      const FrameCallback& on_frame = {},
                                      const RunOptions& options = {},
                                      const SkipCallback& on_skip = {});

}  // namespace lsgd::eval
