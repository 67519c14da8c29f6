// The online loop-closure detector: a SLAM system hands it one frame at a time
// and gets back the best loop candidate, the top-N candidates, a loop decision
// and per-stage timings.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/frame_store.h"
#include "lsgd/image.h"
#include "lsgd/search.h"
#include "lsgd/segmentation.h"
#include "lsgd/similarity.h"

namespace cv {
class Mat;
}

namespace lsgd {

struct DecisionOptions {
  // A best candidate whose score is >= threshold is reported as a loop; in [0, 1].
  // Scores are similarities in [0, 1] (see SimilarityMetric).
  double threshold = 0.87;
  void check() const;
};

struct DetectorOptions {
  SegmentationOptions segmentation;
  SimilarityOptions similarity;
  SearchOptions search;
  DecisionOptions decision;
  void check() const;
};

// Wall-clock milliseconds spent per stage on one frame.
struct Timings {
  double convert_ms = 0;   // conversion to 8-bit gray
  double segment_ms = 0;   // superpixel-grid segmentation
  double describe_ms = 0;  // histograms
  double search_ms = 0;    // candidate search (and node assignment)
  double total_ms = 0;     // the whole process() call
};

struct Result {
  std::int64_t frame = -1;             // id of the processed frame (0, 1, 2, ...)
  bool loop = false;                   // best.score >= decision.threshold
  Candidate best;                      // best candidate; frame -1 when there is none
  std::vector<Candidate> candidates;   // up to search.top_n, best first
  std::int64_t node = -1;              // dynamic node joined or created; -1 when exhaustive
  bool node_created = false;
  Timings timings;
};

class Detector {
 public:
  // Validates the options (throws InvalidArgument naming the field).
  explicit Detector(const DetectorOptions& options = {});

  // Processes the next frame: describes it, searches earlier frames outside
  // the temporal window, stores it. Every frame must have the size of the
  // first; a rejected frame (bad format, other size) throws and leaves the
  // detector unchanged.
  Result process(const cv::Mat& frame);
  Result process(const ImageView& frame);

  const DetectorOptions& options() const { return options_; }
  std::int64_t size() const { return store_.size(); }
  const FrameStore& store() const { return store_; }
  // Number of dynamic nodes (0 in exhaustive mode).
  std::int64_t nodes() const;
  const DynamicNodes& dynamic_nodes() const { return nodes_; }
  // Bytes held per stored frame (descriptor storage).
  std::size_t bytes_per_frame() const { return store_.bytes_per_frame(); }

  // Similarity of two stored frames with the configured metric.
  double similarity(std::int64_t a, std::int64_t b) const;

 private:
  Result process_gray(double convert_ms, std::int64_t start_ns);

  DetectorOptions options_;
  int width_ = 0;  // size of the first frame; every later frame must match
  int height_ = 0;
  Segmenter segmenter_;
  FrameStore store_;
  DynamicNodes nodes_;
  // Scratch reused across frames (no allocation per frame once warm).
  GrayImage gray_;
  Segmentation segmentation_;
  Descriptor descriptor_;
  std::vector<Candidate> scratch_;
};

}  // namespace lsgd
