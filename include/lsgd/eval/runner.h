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
};

// The images of a sequence, read with io::read_image.
FrameSource sequence_source(const io::Sequence& sequence);

// Called after each frame with its result and the milliseconds spent loading
// it. Frame ids in the result (its frame, best, candidates, verdicts) are
// source indices, also when earlier frames were skipped.
using FrameCallback = std::function<void(const Result& result, double load_ms)>;
// Called for each skipped frame: its source index, name and the error.
using SkipCallback =
    std::function<void(std::int64_t frame, const std::string& name, const std::string& error)>;

struct RunOptions {
  // false: a frame that fails to load (missing, truncated, corrupt, not an
  // image) or that the detector rejects (other size, 16-bit) stops the run
  // with an lsgd::Error naming the frame and its source.
  // true: such a frame is skipped: `on_skip` is told, the detector never sees
  // it, and its record has no report (skipped = true), so a skipped
  // ground-truth loop counts as missed. Later frames keep their source index.
  bool skip_bad_frames = false;
};

// Feeds every frame to the detector in order. Frames already processed were
// passed to `on_frame` (a CSV writer keeps them) before any error. Throws
// InvalidArgument for an empty source.
// Warnings about a setup in which the method cannot work as intended, for
// `lsgd eval` to print (stderr), store (JSON) and show (HTML report): a grid of
// fewer than 4 cells (the descriptor is nearly a whole-image histogram),
// frames too small for geometric verification, and ground-truth loops before
// the detector calibrates its scores (frame min_gap + kMinCalibration) or a
// sequence too short to reach that frame. `detector` has run over the
// sequence (its frame size is known); empty when all is well.
std::vector<std::string> setup_warnings(const Detector& detector, const GroundTruth& gt);

std::vector<FrameRecord> run_detector(Detector& detector, const FrameSource& source,
                                      const FrameCallback& on_frame = {},
                                      const RunOptions& options = {},
                                      const SkipCallback& on_skip = {});

}  // namespace lsgd::eval
