// The online loop-closure detector: a SLAM system hands it one frame at a time
// and gets back the best loop candidate, the top-N candidates, a loop decision
// and per-stage timings.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "lsgd/decision.h"
#include "lsgd/descriptor.h"
#include "lsgd/evidence.h"
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

struct DetectorOptions {
  SegmentationOptions segmentation;
  DescriptorOptions descriptor;
  SimilarityOptions similarity;
  SearchOptions search;
  VerificationOptions verification;
  DecisionOptions decision;
  void check() const;
  // Every option of every stage, keys from the root ("search.min_gap"), in
  // the order of the YAML (lsgd/options.h).
  static const OptionTable<DetectorOptions>& fields();
};

// Sets option `key` (a key of DetectorOptions::fields()) from text as a user
// types it, e.g. set_option(o, "search.nodes.beta", "1.1"). InvalidArgument
// naming the key for an unknown key or a value of the wrong kind; the range
// is checked by DetectorOptions::check().
void set_option(DetectorOptions& options, const std::string& key, const std::string& value);
// The value of option `key` as text (InvalidArgument for an unknown key).
std::string option_text(const DetectorOptions& options, const std::string& key);

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
  // The loop decision: best.frame >= 0 and best.score >= decision.threshold.
  bool loop = false;
  // The reported candidate: the first one (best first, up to
  // verification.max_candidates) that no enabled stage rejected, preferring
  // one the geometric stage confirmed. Its score is the loop score of
  // decision.h, in standard deviations (sigma): its appearance score plus the
  // bonuses it earned. Frame -1 when there is none (also while the map is too
  // short to calibrate scores: kMinCalibration candidates).
  Candidate best;
  LoopEvidence evidence;  // what the score of `best` is made of
  // Candidates best first, up to search.top_n, scored by appearance (sigma):
  // sequence evidence with the temporal stage (distinct places in exhaustive
  // search), the standardised similarity without it (evidence.h).
  std::vector<Candidate> candidates;
  std::vector<StageVerdict> verification;  // every stage verdict, in the order examined
  std::int64_t node = -1;                  // dynamic node joined or created; -1 when exhaustive
  bool node_created = false;
  Timings timings;
};

// Threads: a Detector is used by one thread at a time, its const calls
// included (process() changes what they read). Use one Detector per thread,
// or a mutex around every call. process() and the restore_*() calls detect an
// overlapping call on the same Detector and throw InvalidArgument instead of
// corrupting it (the call already running completes normally). Different
// Detectors share nothing and run in parallel freely. Not copyable.
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
  // Number of groups of the search mode (dynamic nodes; 0 in exhaustive mode).
  std::int64_t nodes() const;
  // The search mode (search.mode), e.g. its groups.
  const CandidateSearch& search() const { return *search_; }
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
  // The decision's state after the last frame (loop declared for it, its
  // loop's inliers).
  const ContinuityState& continuity() const { return continuity_; }
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
  // The search's groups (CandidateSearch::restore_groups; dynamic nodes) as
  // process() builds them: in nodes mode every stored frame in exactly one
  // node, nodes in the order of their first frames. InvalidArgument
  // otherwise (or for a mode without groups), detector unchanged.
  void restore_nodes(std::vector<std::vector<std::int64_t>> nodes);
  // Temporal places (TemporalVerifier::restore); last_query must be size() - 1.
  // Only with temporal verification.
  void restore_temporal(std::int64_t last_query, std::vector<std::int64_t> places);
  // The decision's state (continuity()); state.query must be size() - 1 and
  // state.loop an earlier frame or -1. The appearance statistics need no
  // restoring: the next process() recomputes them from the stored frames.
  void restore_continuity(const ContinuityState& state);

 private:
  Result process_gray(double convert_ms, std::int64_t start_ns);
  void score_candidates(Result& result);
  void verify(Result& result);
  Candidate continuation_candidate(std::int64_t query);

  DetectorOptions options_;
  int width_ = 0;  // size of the first frame; every later frame must match
  int height_ = 0;
  Segmenter segmenter_;
  FrameStore store_;
  std::unique_ptr<CandidateSearch> search_;  // made from options_.search
  AppearanceEvidence evidence_;
  TemporalVerifier temporal_;
  GeometricVerifier geometric_;
  ContinuityState continuity_;
  // Scratch reused across frames (no allocation per frame once warm).
  GrayImage gray_;
  Segmentation segmentation_;
  DescribeScratch describe_scratch_;
  Descriptor exact_;       // the frame's histograms as computed
  Descriptor descriptor_;  // ... and as stored (descriptor.storage)
  std::vector<Candidate> raw_;  // the search's candidates, by similarity
  std::vector<Candidate> examined_;  // candidates verify() checks geometrically, in order
  std::vector<char> gated_;          // verify(): 1 for a candidate the agreement gate rejected
  std::vector<double> row_;     // exhaustive: the query's similarity to every candidate
  // Set while process() or a restore_*() call runs: a second, overlapping
  // call throws (class Exclusive in detector.cc).
  std::atomic<bool> busy_{false};
  class Exclusive;
};

}  // namespace lsgd
