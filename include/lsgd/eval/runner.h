// Runs a Detector online over a source of frames, one frame at a time, and
// collects what it reported for the evaluation.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lsgd/detector.h"
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

// Called after each frame with its result and the milliseconds spent loading it.
using FrameCallback = std::function<void(const Result& result, double load_ms)>;

// Feeds every frame to the detector in order. A frame that fails to load or is
// rejected by the detector stops the run with an lsgd::Error whose message
// names the frame and its source; frames already processed were already
// passed to `on_frame` (a CSV writer keeps them). Throws InvalidArgument for
// an empty source.
std::vector<FrameRecord> run_detector(Detector& detector, const FrameSource& source,
                                      const FrameCallback& on_frame = {});

}  // namespace lsgd::eval
