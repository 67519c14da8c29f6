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
#include "lsgd/verification.h"

namespace cv {
class Mat;
}

namespace lsgd {

struct DecisionOptions {
  // A reported candidate whose score is >= threshold is a loop; in [0, 1].
  // Scores are similarities in [0, 1] (see SimilarityMetric), averaged along
  // the sequence when temporal verification runs. 0.841 is (rounded up) the
  // smallest value with precision 1 on corridor and the synthetic street with
  // the default (temporal, 16 + 48 frames) verification in both search modes;
  // without verification use 0.87 (docs/results.md).
  double threshold = 0.841;
  void check() const;
};

struct DetectorOptions {
  SegmentationOptions segmentation;
  DescriptorOptions descriptor;
  SimilarityOptions similarity;
  SearchOptions search;
  VerificationOptions verification;
  DecisionOptions decision;
  void check() const;
};

// Wall-clock milliseconds spent per stage on one frame.
struct Timings {
  double convert_ms = 0;   // conversion to 8-bit gray
  double segment_ms = 0;   // superpixel-grid segmentation, histograms counted in its last pass
  double describe_ms = 0;  // storage encoding (compact) of the histograms
  double search_ms = 0;    // candidate search (and node assignment)
  double verify_ms = 0;    // verification stages, including feature extraction
  double total_ms = 0;     // the whole process() call
};

struct Result {
  std::int64_t frame = -1;  // id of the processed frame (0, 1, 2, ...)
  bool loop = false;        // best.frame >= 0 and best.score >= decision.threshold
  // The reported candidate: the most similar one that every enabled
  // verification stage accepted (its score is the temporal sequence score when
  // that stage runs, else the similarity); frame -1 when there is none.
  Candidate best;
  std::vector<Candidate> candidates;       // raw search result: up to search.top_n, best first
  std::vector<StageVerdict> verification;  // every stage verdict, in the order examined
  std::int64_t node = -1;                  // dynamic node joined or created; -1 when exhaustive
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

  // ---- Persistence (lsgd::io::Database): the state process() accumulates,
  // readable, and restorable into a detector with the same options so that
  // processing continues exactly as if it had never stopped.
  int width() const { return width_; }  // size of the first frame; 0 before it
  int height() const { return height_; }
  const TemporalVerifier& temporal_verifier() const { return temporal_; }
  const GeometricVerifier& geometric_verifier() const { return geometric_; }
  // Stores frame size() as process() would have, without its image: its
  // descriptor and, when geometric verification is on, its ORB features
  // (GeometricVerifier::features; must be empty when it is off). Dynamic nodes
  // and temporal places are restored separately, after the frames. `node` is
  // the frame's dynamic node in nodes mode (0 otherwise): it places the frame
  // beside the node's other frames in the store (0 <= node <= the highest
  // node given so far + 1). It is a placement only: frames restored with node
  // 0 and their nodes restored afterwards give the same results, a little
  // slower. Throws InvalidArgument (detector unchanged) for another frame
  // size, a descriptor whose grid or sizes do not match, inconsistent
  // features or a node out of range.
  void restore_frame(int width, int height, const Descriptor& descriptor,
                     const std::vector<float>& points = {},
                     const std::vector<std::uint8_t>& orb = {}, std::int64_t node = 0);
  // Node membership (DynamicNodes::restore); every id must be < size(). Only
  // in nodes mode.
  void restore_nodes(std::vector<std::vector<std::int64_t>> nodes);
  // Temporal places (TemporalVerifier::restore); last_query must be size() - 1.
  // Only with temporal verification.
  void restore_temporal(std::int64_t last_query, std::vector<std::int64_t> places);

 private:
  Result process_gray(double convert_ms, std::int64_t start_ns);
  void verify(Result& result);

  DetectorOptions options_;
  int width_ = 0;  // size of the first frame; every later frame must match
  int height_ = 0;
  Segmenter segmenter_;
  FrameStore store_;
  DynamicNodes nodes_;
  TemporalVerifier temporal_;
  GeometricVerifier geometric_;
  // Scratch reused across frames (no allocation per frame once warm).
  GrayImage gray_;
  Segmentation segmentation_;
  DescribeScratch describe_scratch_;
  Descriptor exact_;       // the frame's histograms as computed
  Descriptor descriptor_;  // ... and as stored (descriptor.storage)
  std::vector<Candidate> scratch_;
};

}  // namespace lsgd
