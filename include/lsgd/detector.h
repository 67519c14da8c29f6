// The online loop-closure detector: a SLAM system hands it one frame at a time
// and gets back the best loop candidate, the top-N candidates, a loop decision
// and per-stage timings.
#pragma once

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "lsgd/decision.h"
#include "lsgd/descriptor.h"
#include "lsgd/evidence.h"
#include "lsgd/frame_store.h"
#include "lsgd/image.h"
#include "lsgd/places.h"
#include "lsgd/search.h"
#include "lsgd/segmentation.h"
#include "lsgd/similarity.h"
#include "lsgd/stage.h"
#include "lsgd/state.h"
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
  double describe_ms = 0;  // storage encoding (compact) of the histograms, the place signature (places.h)
  double search_ms = 0;    // candidate search (and node assignment, index insertion)
  double insert_ms = 0;    // ... of which adding frames to the search's index (index mode)
  double evidence_ms = 0;  // ... and the appearance evidence: statistics, sequence scores, realignment
  double verify_ms = 0;    // verification stages, including feature extraction
  double total_ms = 0;     // the whole process() call
};

// Result::stamp of a frame given none.
inline constexpr double kNoStamp = std::numeric_limits<double>::quiet_NaN();

struct Result {
  std::int64_t frame = -1;  // the detector's number of the processed frame (0, 1, 2, ...)
  std::int64_t id = -1;     // the caller's id of it (process(frame, id, stamp); else its number
                            // counted on from the last id given)
  double stamp = kNoStamp;  // its time stamp as given (NaN: none)
  std::int64_t loop_id = -1;  // the caller's id of best.frame (-1: none), for a loop
  // The loop decision: best.frame >= 0 and best.score >= decision.threshold.
  bool loop = false;
  // The reported candidate: the first one (best first, up to
  // verification.max_candidates) that no enabled stage rejected, preferring
  // one the geometric stage confirmed. Its score is the loop score of
  // decision.h, in standard deviations (sigma): its appearance score plus the
  // bonuses it earned. Frame -1 when there is none: before the first scored
  // query (first_scored_query(), evidence.h), and for a young query (fewer
  // than kMinCalibration candidates) that no confirming stage confirmed.
  Candidate best;
  // Why there is a loop or none (decision.h): a program branches on it; the
  // verdicts below say it in words.
  LoopStatus status = LoopStatus::kTooFewFrames;
  LoopEvidence evidence;  // what the score of `best` is made of
  // The geometry of `best` when a stage fitted one (the geometric stage's
  // matches, inlier mask and F or H; loop_geometry.h): a loop's relative pose
  // without matching again (examples/relative_pose.cc). Null otherwise.
  std::shared_ptr<const LoopGeometry> geometry;
  // The ranking no decision setting changes (decision.h): the candidate
  // appearance ranks first through the gates, scored by appearance (sigma),
  // and whether the confirming stages accept it. lsgd::eval computes R@100P
  // and AP from it (a candidate they reject counts at no threshold); `best`'s
  // loop score gives the decision's own (Metrics::decision_*).
  Ranking ranking;
  // Candidates best first, up to search.top_n, scored by appearance (sigma):
  // sequence evidence with the temporal stage (distinct places in exhaustive
  // search), the standardised similarity without it (evidence.h).
  std::vector<Candidate> candidates;
  std::vector<StageVerdict> verification;  // every stage verdict, in the order examined
  std::int64_t node = -1;                  // dynamic node joined or created; -1 when exhaustive
  bool node_created = false;
  Timings timings;
};

// A frame described apart from the map (Detector::describe_frame()): what
// process() computes from the image before it reads any stored frame, so
// that one process (a robot) describes its frames and another (the map)
// stores and searches them, with the Results process(image) gives. Its
// bytes (encode_frame_description) are the compact descriptor's plus each
// stage's record (geometric: the ORB features, ~40 bytes a keypoint).
struct FrameDescription {
  int width = 0;  // the image's size
  int height = 0;
  // describing_options_key() of the options that described it: a map
  // refuses a description made under other segmentation, descriptor or
  // verification options.
  std::uint64_t options_key = 0;
  Descriptor descriptor;  // as the map stores it (descriptor.storage)
  // Each verification stage's record (VerificationStage::describe()), in
  // the order of verification.stages, named.
  std::vector<std::string> stages;
  std::vector<std::vector<std::uint8_t>> records;
  // The frame's place signature (lsgd/places.h), with
  // verification.temporal.place_cut on; empty otherwise.
  std::vector<std::uint8_t> signature;
  // What describing took: convert, segment and describe (the histograms'
  // encoding and the stages' records); Result::timings reports them, and
  // its total_ms is the describing plus the process() or query() call.
  double convert_ms = 0;
  double segment_ms = 0;
  double describe_ms = 0;
};
// A hash of every option a description depends on (segmentation.*,
// descriptor.*, verification.*), as their option texts.
std::uint64_t describing_options_key(const DetectorOptions& options);
// Bytes a description travels or is kept as (little-endian, versioned), and
// back: decode throws FormatError naming what is wrong for bytes that are
// not one (truncated, another version, sizes that do not add up); nothing
// it allocates exceeds the bytes given.
std::vector<std::uint8_t> encode_frame_description(const FrameDescription& description);
FrameDescription decode_frame_description(const std::uint8_t* data, std::size_t size);

// Threads: a Detector is used by one thread at a time, its const calls
// included (process() changes what they read). Use one Detector per thread,
// or a mutex around every call. process() and restore_frame() detect an
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
  // The same, with the caller's id of the frame (above every earlier one's,
  // at most kMaxFrameId: keyframe ids, image indices with gaps) and its
  // time stamp (any finite value, seconds by convention; NaN: none). Result
  // carries them (id, stamp, loop_id), id_of() / frame_of() map between
  // them and the detector's frame numbers, and the database keeps them.
  // Without an id a frame gets the one after the last (0 first).
  Result process(const cv::Mat& frame, std::int64_t id, double stamp = kNoStamp);
  Result process(const ImageView& frame, std::int64_t id, double stamp = kNoStamp);

  // The answer process() would give for the frame as the next one, with
  // nothing stored and nothing changed: relocalisation, or localising in a
  // map opened read-only (lsgd run --localize). Result::frame is the id
  // process() would give it. Every later answer is as if the query never
  // happened (index mode may insert stored frames into its graph earlier
  // than process() would, the same graph: CandidateSearch::query). Throws
  // InvalidArgument, detector unchanged, for a frame process() would refuse
  // or a search mode or stage that cannot answer without storing.
  Result query(const cv::Mat& frame);
  Result query(const ImageView& frame);
  Result query(const cv::Mat& frame, std::int64_t id, double stamp = kNoStamp);
  Result query(const ImageView& frame, std::int64_t id, double stamp = kNoStamp);

  // The frame's descriptor as the detector would store it (its options'
  // segmentation and descriptor.storage), nothing stored: place recognition
  // between traverses (lsgd match), descriptors for one's own index. Compare
  // two with lsgd::similarity(a.view(), b.view(), options().similarity.metric).
  // Throws InvalidArgument for a frame process() would refuse (bad format;
  // a size other than the stored frames').
  Descriptor describe(const cv::Mat& frame);
  Descriptor describe(const ImageView& frame);

  // The frame as process() would take it, nothing stored or changed: its
  // descriptor and each stage's record (FrameDescription). process() and
  // query() of it give the Results process() and query() of the image give,
  // in this detector or another made with the same options (a robot
  // describes, the map stores). InvalidArgument for a frame process() would
  // refuse, or a stage that cannot describe (VerificationStage::describes()).
  FrameDescription describe_frame(const cv::Mat& frame);
  FrameDescription describe_frame(const ImageView& frame);
  // process() and query() of a described frame. InvalidArgument, with
  // nothing changed, for a description made under other options
  // (describing_options_key()), of another size than the stored frames, or
  // whose descriptor or records do not fit (each stage's
  // check_description()).
  Result process(const FrameDescription& frame, std::int64_t id = -1, double stamp = kNoStamp);
  Result query(const FrameDescription& frame, std::int64_t id = -1, double stamp = kNoStamp);

  // The caller's id and time stamp of stored frame `frame` (InvalidArgument
  // for one not stored), and the stored frame of caller id `id` (-1: none).
  std::int64_t id_of(std::int64_t frame) const;
  double stamp_of(std::int64_t frame) const;
  std::int64_t frame_of(std::int64_t id) const;

  // Forgets the stored frames whose caller ids lie in [first_id, last_id]
  // (bounded working memory; a session a map no longer needs); returns how
  // many. They are never candidates again, and the detector is the one that
  // restoring the kept frames' state gives (io::Database::restore), each
  // component's records renumbered (Stateful::restore_renumbered):
  //  - kept frames keep their ids and stamps; their frame numbers close up
  //    (Result::frame, candidates), so keep ids, not numbers, across a forget;
  //  - a dynamic node keeps its kept frames (its first kept frame leads it;
  //    nodes left empty are gone); temporal places and declared loops that
  //    were forgotten frames are none;
  //  - the appearance statistics are computed again from the kept frames at
  //    the next frame, index mode's graph at the next query;
  //  - forgetting the last frames gives the detector as it was before it
  //    processed them, its next id included: process() without an id gives
  //    the frame after the last kept one the id after that frame's, so the
  //    ids of forgotten last frames are given again (a forgotten tail
  //    re-run gives the same ids and Results). A caller whose records must
  //    never see an id twice passes its own ids (above the last kept one).
  // Costs a copy of the kept frames (and index mode's graph rebuilt).
  // Throws InvalidArgument, detector unchanged, for first_id > last_id or a
  // component that cannot forget (Stateful::forgets()).
  std::int64_t forget(std::int64_t first_id, std::int64_t last_id);

  // The next frame starts a new sequence (a new session of a map, a robot
  // put down elsewhere, the next place of a map of several): it continues no
  // loop declared for the frame before it (decision.h, continuity). `lsgd run
  // --database` calls it when it starts a new session on stored frames.
  void cut();

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

  // The verification stages (verification.stages), in the order they run;
  // nullptr for a stage the options do not name.
  const VerificationStage* stage(const std::string& name) const;
  // The decision's state after the last frame (the loop declared for it).
  const ContinuityState& continuity() const { return decision_.continuity(); }
  // The first frames of the places found after the first, ascending
  // (verification.temporal.place_cut; lsgd/places.h): each is found when
  // its frame c + kPlaceBlock (its ninth) is stored. Empty with place_cut 0.
  const std::vector<std::int64_t>& place_starts() const { return place_cuts_.cuts(); }

  // ---- Persistence (lsgd::io::Database): a stored frame is its descriptor
  // plus the per-frame state of every component that keeps state (the search
  // mode, the verification stages, the decision; state.h), so that a
  // detector with the same options restored frame by frame continues exactly
  // as if it had never stopped.
  int width() const { return width_; }  // size of the first frame; 0 before it
  int height() const { return height_; }
  // The components' records for stored frame `frame` (any stored frame), as
  // one blob (encode_records). InvalidArgument for a frame not stored.
  std::vector<std::uint8_t> frame_state(std::int64_t frame) const;
  // Stores frame size() as process() would have, without its image: its
  // descriptor and frame_state()'s blob, each record handed to the component
  // of its name (check_frame() of every one first). Throws InvalidArgument,
  // detector unchanged, for another frame size, a descriptor whose grid or
  // sizes do not match, a damaged blob, a record of a component these options
  // do not have, or a record its component refuses.
  // `id`: the caller's id of the frame as its store knows it (the database's
  // row), for a state saved before ids were kept in it (-1: the one after the
  // last); a state that holds another id is refused.
  void restore_frame(int width, int height, const Descriptor& descriptor,
                     const std::vector<std::uint8_t>& state, std::int64_t id = -1);
  // The search mode's index as one blob (CandidateSearch::save_index: index
  // mode's graph), so that a restored detector need not rebuild it; returns
  // the frames it covers (0 and an empty blob for a mode without one).
  std::int64_t save_index(std::vector<std::uint8_t>& out) const { return search_->save_index(out); }
  // Hands save_index()'s blob back after the frames were restored, before
  // the next process(). InvalidArgument for a damaged blob or one that does
  // not fit the stored frames; the next query then rebuilds the index.
  void restore_index(const std::uint8_t* data, std::size_t size);

 private:
  // store: process(), else query() (nothing stored or changed); id -1: the next.
  Result process_gray(double convert_ms, std::int64_t start_ns, bool store, std::int64_t id,
                      double stamp);
  // The rest of process() once descriptor_ holds the frame's descriptor;
  // `described`: the stages' records (a FrameDescription's), else gray_.
  Result process_described(Result result, std::int64_t start_ns, bool store,
                           const FrameDescription* described, int width, int height);
  Result run_described(const FrameDescription& frame, bool store, std::int64_t id, double stamp);
  template <typename Image>
  FrameDescription describe_image(const Image& frame);
  void check_description(const FrameDescription& frame) const;
  // InvalidArgument unless a width x height frame fits the stored frames' size.
  void check_size(int width, int height) const;
  void check_stages_describe(const char* call) const;
  // The id a frame given `id` gets (-1: the one after the last); InvalidArgument
  // for one not above the last or a stamp that is infinite.
  std::int64_t next_id(std::int64_t id, double stamp) const;
  void check_answers_queries() const;
  template <typename Image>
  Result run_frame(const Image& frame, bool store, std::int64_t id, double stamp);
  Descriptor describe_gray();
  // every_frame: the search scored every frame for this query (row_ written),
  // so its places are ranked over every diagonal; else its shortlist is realigned.
  void score_candidates(AppearanceEvidence& evidence, bool every_frame, Result& result);
  void verify(AppearanceEvidence& evidence, bool store, Result& result,
              const FrameDescription* described, int width, int height);
  // The components with per-frame state, in the order their records are saved.
  std::vector<Stateful*> stateful() const;
  // Restores this (new) detector from `from`'s frames for which after(f) >= 0.
  void restore_kept(const Detector& from, const FrameRenumbering& renumbered);

  DetectorOptions options_;
  std::uint64_t describing_key_ = 0;  // describing_options_key(options_)
  int width_ = 0;  // size of the first frame; every later frame must match
  int height_ = 0;
  Segmenter segmenter_;
  FrameStore store_;
  std::unique_ptr<CandidateSearch> search_;  // made from options_.search
  AppearanceEvidence evidence_;
  AppearanceEvidence query_evidence_;  // query(): a copy of evidence_ the query adds itself to
  std::vector<std::unique_ptr<VerificationStage>> stages_;  // made from options_.verification
  std::vector<VerificationStage*> stage_list_;              // the same, for the decision
  LoopDecision decision_;
  PlaceCuts place_cuts_;                // verification.temporal.place_cut
  std::vector<std::uint8_t> signature_;  // the frame's place signature (with place_cut)
  // The caller's id and time stamp of every stored frame, kept with the
  // frame's state as the component "frame" (record version 1: id int64,
  // stamp float64; a frame saved without it gets the id the database row
  // holds, or the one after the last, and no stamp).
  class FrameTags final : public Stateful {
   public:
    const char* name() const override { return "frame"; }
    bool has_state() const override { return true; }
    void save_frame(std::int64_t frame, StateWriter& out) const override;
    void check_frame(std::int64_t frame, int width, int height, std::uint32_t version,
                     StateReader in) const override;
    void restore_frame(std::int64_t frame, int width, int height, std::uint32_t version,
                       StateReader in) override;
    bool forgets() const override { return true; }  // its records name no frame
    std::int64_t last() const { return ids.empty() ? -1 : ids.back(); }
    std::vector<std::int64_t> ids;  // increasing
    std::vector<double> stamps;     // NaN: none
    std::int64_t given_id = -1;     // restore_frame()'s id for a frame without a record
  };
  FrameTags tags_;
  // Scratch reused across frames (no allocation per frame once warm).
  GrayImage gray_;
  Segmentation segmentation_;
  DescribeScratch describe_scratch_;
  Descriptor exact_;       // the frame's histograms as computed
  Descriptor descriptor_;  // ... and as stored (descriptor.storage)
  std::vector<Candidate> raw_;  // the search's candidates, by similarity
  std::vector<Candidate> places_;  // the ranked places, top_n and those the search follows
  std::vector<double> row_;     // exhaustive: the query's similarity to every candidate
  // Set while process() or restore_frame() runs: a second, overlapping
  // call throws (class Exclusive in src/detector_internal.h).
  std::atomic<bool> busy_{false};
  class Exclusive;
};

// The memory a detector with `options` takes for `frames` stored frames of
// `cells` cells, bytes: each frame's descriptor in options.descriptor.storage
// and what its search mode keeps per frame (SearchMode::bytes_per_frame), as
// measured in docs/performance.md. For planning a map's size (lsgd bench
// --distractors refuses a run that would not fit).
std::int64_t estimated_map_bytes(const DetectorOptions& options, std::int64_t frames, int cells);

}  // namespace lsgd
