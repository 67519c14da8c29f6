#include "lsgd/detector.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>

#include "internal/check.h"
#include "internal/clock.h"
#include "internal/names.h"
#include "internal/option_tables.h"
#include "detector_internal.h"
#include "lsgd/limits.h"

namespace lsgd {
using internal::ms_since;
using internal::now_ns;

namespace {

OptionTable<DetectorOptions> detector_table() {
  using S = DetectorOptions;
  OptionTable<S> t;
  nest<S, SegmentationOptions>(t, "segmentation", &S::segmentation, SegmentationOptions::fields());
  nest<S, DescriptorOptions>(t, "descriptor", &S::descriptor, DescriptorOptions::fields());
  nest<S, SimilarityOptions>(t, "similarity", &S::similarity, SimilarityOptions::fields());
  nest<S, SearchOptions>(t, "search", &S::search, SearchOptions::fields());
  nest<S, VerificationOptions>(t, "verification", &S::verification, VerificationOptions::fields());
  nest<S, DecisionOptions>(t, "decision", &S::decision, DecisionOptions::fields());
  return t;
}

}  // namespace

// Built again after a registration: a registered mode's or stage's options.
const OptionTable<DetectorOptions>& DetectorOptions::fields() {
  return internal::current_table(detector_table);
}

namespace {

const OptionField<DetectorOptions>& field(const std::string& key) {
  const OptionField<DetectorOptions>* f = find_option(DetectorOptions::fields(), key);
  if (f == nullptr) {
    // The keys of the same section, to help with a misspelt one.
    const std::string section = key.substr(0, key.find('.'));
    std::string known;
    for (const auto& g : DetectorOptions::fields()) {
      if (g.name.compare(0, section.size() + 1, section + ".") == 0) {
        known += (known.empty() ? "" : ", ") + g.name;
      }
    }
    std::vector<std::string> keys;
    for (const auto& g : DetectorOptions::fields()) keys.push_back(g.name);
    const std::string guess = internal::nearest(key, keys);
    internal::throw_invalid("unknown option '", internal::shown_value(key), "'",
                            guess.empty() ? std::string() : "; did you mean '" + guess + "'?",
                            known.empty() ? std::string(" (see lsgd options)")
                                          : " (" + internal::shown_value(section) + " has " + known + ")");
  }
  return *f;
}

}  // namespace

void set_option(DetectorOptions& options, const std::string& key, const std::string& value) {
  const OptionField<DetectorOptions>& f = field(key);
  try {
    set_option_text(f, options, value);
  } catch (const InvalidArgument& e) {
    const std::string message = e.what();
    if (message.compare(0, key.size(), key) == 0) throw;
    internal::throw_invalid(key, ": ", message);
  }
}

std::string option_text(const DetectorOptions& options, const std::string& key) {
  return field(key).text(options);
}

void DetectorOptions::check() const {
  segmentation.check();
  descriptor.check();
  similarity.check();
  search.check();
  verification.check();
  decision.check();
}

namespace {

SequenceOptions sequence_options(const VerificationOptions& v) {
  SequenceOptions s;
  s.enabled = v.has(kTemporalStage);
  s.frames = v.temporal_options.frames;
  s.long_frames = v.temporal_options.long_frames;
  s.tolerance = v.temporal_options.tolerance;
  return s;
}

// The place_cut the detector finds places with (0: none; the temporal stage's).
double place_cut(const DetectorOptions& options) {
  return options.verification.has(kTemporalStage) ? options.verification.temporal_options.place_cut : 0.0;
}

}  // namespace

Detector::Detector(const DetectorOptions& options)
    : options_(options),
      describing_key_((options.check(), describing_options_key(options))),  // validated first
      segmenter_(options.segmentation),
      search_(make_search(options.search)),
      evidence_(sequence_options(options.verification), options.search.min_gap,
                !search_->scores_every_frame(), kExactStatisticsCandidates,
                search_->scores_every_frame_up_to()),
      query_evidence_(evidence_),
      stages_(make_stages(options.verification)),
      decision_(options.decision),
      place_cuts_(place_cut(options)) {
  for (const auto& stage : stages_) stage_list_.push_back(stage.get());
}

const VerificationStage* Detector::stage(const std::string& name) const {
  for (const auto& stage : stages_) {
    if (name == stage->name()) return stage.get();
  }
  return nullptr;
}

Result Detector::process(const cv::Mat& frame) { return process(frame, -1, kNoStamp); }
Result Detector::process(const ImageView& frame) { return process(frame, -1, kNoStamp); }
Result Detector::query(const cv::Mat& frame) { return query(frame, -1, kNoStamp); }
Result Detector::query(const ImageView& frame) { return query(frame, -1, kNoStamp); }

// process() (store) and query(), from either kind of image.
template <typename Image>
Result Detector::run_frame(const Image& frame, bool store, std::int64_t id, double stamp) {
  const Exclusive exclusive(busy_, store ? "process" : "query");
  if (!store) check_answers_queries();
  const std::int64_t start = now_ns();
  const std::int64_t given = next_id(id, stamp);
  to_gray(frame, gray_);
  return process_gray(ms_since(start), start, store, given, stamp);
}

Result Detector::process(const cv::Mat& frame, std::int64_t id, double stamp) {
  return run_frame(frame, true, id, stamp);
}
Result Detector::process(const ImageView& frame, std::int64_t id, double stamp) {
  return run_frame(frame, true, id, stamp);
}
Result Detector::query(const cv::Mat& frame, std::int64_t id, double stamp) {
  return run_frame(frame, false, id, stamp);
}
Result Detector::query(const ImageView& frame, std::int64_t id, double stamp) {
  return run_frame(frame, false, id, stamp);
}

Descriptor Detector::describe(const cv::Mat& frame) {
  const Exclusive exclusive(busy_, "describe");
  to_gray(frame, gray_);
  return describe_gray();
}

Descriptor Detector::describe(const ImageView& frame) {
  const Exclusive exclusive(busy_, "describe");
  to_gray(frame, gray_);
  return describe_gray();
}

void Detector::check_size(int width, int height) const {
  if (store_.size() > 0 && (width != width_ || height != height_)) {
    internal::throw_invalid("the frame is ", width, "x", height, " but the stored frames are ",
                            width_, "x", height_, ": every frame must have the same size");
  }
}

Descriptor Detector::describe_gray() {
  check_size(gray_.width, gray_.height);
  segment_and_describe(segmenter_, gray_, segmentation_, exact_, describe_scratch_, options_.descriptor);
  if (options_.descriptor.storage == HistogramStorage::kCompact) {
    Descriptor out;
    compact(exact_, out);
    return out;
  }
  return exact_;
}

std::int64_t Detector::next_id(std::int64_t id, double stamp) const {
  if (std::isinf(stamp)) internal::throw_invalid("the frame's time stamp is ", stamp, ": give a finite one, or none");
  const std::int64_t last = tags_.last();
  if (id < 0) {
    if (id != -1) internal::throw_invalid("frame id ", id, " is negative (-1: the one after the last)");
    if (last >= kMaxFrameId) internal::throw_invalid("frame ids are exhausted (the last is ", last, ")");
    return last + 1;
  }
  if (id <= last || id > kMaxFrameId) {
    internal::throw_invalid("frame id ", id, " must be above the last frame's id ", last,
                            " and at most ", kMaxFrameId);
  }
  return id;
}

std::int64_t Detector::id_of(std::int64_t frame) const {
  if (frame < 0 || frame >= store_.size()) {
    internal::throw_invalid("id_of: frame ", frame, " is not stored (", store_.size(), " frames)");
  }
  return tags_.ids[static_cast<std::size_t>(frame)];
}

double Detector::stamp_of(std::int64_t frame) const {
  if (frame < 0 || frame >= store_.size()) {
    internal::throw_invalid("stamp_of: frame ", frame, " is not stored (", store_.size(), " frames)");
  }
  return tags_.stamps[static_cast<std::size_t>(frame)];
}

std::int64_t Detector::frame_of(std::int64_t id) const {
  const auto at = std::lower_bound(tags_.ids.begin(), tags_.ids.end(), id);
  return at != tags_.ids.end() && *at == id ? static_cast<std::int64_t>(at - tags_.ids.begin()) : -1;
}

void Detector::check_answers_queries() const {
  for (const auto& stage : stages_) {
    if (!stage->answers_queries()) {
      internal::throw_invalid("Detector::query: verification stage ", stage->name(),
                              " keeps per-frame state and cannot forget a query "
                              "(VerificationStage::answers_queries())");
    }
  }
}

void Detector::cut() {
  const Exclusive exclusive(busy_, "cut");
  decision_.cut();
}

std::int64_t Detector::nodes() const { return search_->groups(); }

double Detector::similarity(std::int64_t a, std::int64_t b) const {
  return lsgd::similarity(store_.view(a), store_.view(b), options_.similarity.metric);
}

Result Detector::process_gray(double convert_ms, std::int64_t start_ns, bool store, std::int64_t id,
                               double stamp) {
  check_size(gray_.width, gray_.height);
  Result result;
  result.frame = store_.size();
  result.id = id;
  result.stamp = stamp;
  result.timings.convert_ms = convert_ms;

  // The histograms are counted during the segmentation's last pass, so
  // segment_ms includes them and describe_ms is the storage encoding.
  std::int64_t t = now_ns();
  segment_and_describe(segmenter_, gray_, segmentation_, exact_, describe_scratch_, options_.descriptor);
  result.timings.segment_ms = ms_since(t);

  t = now_ns();
  if (options_.descriptor.storage == HistogramStorage::kCompact) {
    compact(exact_, descriptor_);
  } else {
    std::swap(exact_, descriptor_);  // descriptor_ is the frame's descriptor as stored
  }
  // A query not stored keeps its signature for its leap (decision.leap) only.
  if (place_cuts_.enabled()) signature_ = place_signature(gray_);
  result.timings.describe_ms = ms_since(t);
  return process_described(std::move(result), start_ns, store, nullptr, gray_.width, gray_.height);
}

Result Detector::process_described(Result result, std::int64_t start_ns, bool store,
                                   const FrameDescription* described, int width, int height) {
  std::int64_t t = now_ns();
  const SimilarityMetric metric = options_.similarity.metric;
  const CandidateSearch::Query search_query{store_, descriptor_.view(), result.frame, metric};
  const CandidateSearch::Outcome outcome = store ? search_->search(search_query, raw_, row_)
                                                 : search_->query(search_query, raw_, row_);
  result.node = outcome.group;
  result.node_created = outcome.created;
  result.timings.insert_ms = outcome.insert_ms;
  // After a restore the evidence is recomputed from the stored frames first.
  const std::int64_t evidence_start = now_ns();
  if (evidence_.last_query() != result.frame - 1) {
    evidence_.set_places(place_cuts_.cuts());
    evidence_.rebuild(store_, metric);
  }
  // A query that is not stored adds itself to a copy of the evidence: its
  // rows, sums and cached terms (kept by query id) stay out of the map's.
  if (!store) query_evidence_ = evidence_;
  AppearanceEvidence& evidence = store ? evidence_ : query_evidence_;
  const bool every_frame = search_->scores_every_frame_for(
      std::max<std::int64_t>(0, result.frame - options_.search.min_gap));
  evidence.add_query(store_, descriptor_.view(), result.frame, metric, every_frame ? &row_ : nullptr);
  score_candidates(evidence, every_frame, result);
  result.timings.evidence_ms = ms_since(evidence_start);
  result.timings.search_ms = ms_since(t);

  t = now_ns();
  verify(evidence, store, result, described, width, height);
  result.timings.verify_ms = ms_since(t);
  result.loop_id = result.best.frame >= 0 ? tags_.ids[static_cast<std::size_t>(result.best.frame)] : -1;
  if (!store) {
    result.timings.total_ms = ms_since(start_ns);
    return result;
  }
  // A node's frames sit together in the store: scoring its members reads one
  // run of memory (FrameStore groups). The group is only a placement, so a
  // node the store has no group for (frames restored without their nodes)
  // gets a new one rather than an error.
  store_.add(descriptor_, std::clamp<std::int64_t>(result.node, 0, store_.groups()));
  search_->end(result.frame, places_);
  // A new place found (with its ninth frame, places.h): the kept rows are
  // recomputed with each candidate's place, as a restored map computes them.
  if (place_cuts_.add(result.frame, signature_) >= 0) {
    evidence_.set_places(place_cuts_.cuts());
    evidence_.rebuild(store_, metric);
  }
  tags_.ids.push_back(result.id);
  tags_.stamps.push_back(result.stamp);
  if (result.frame == 0) width_ = width, height_ = height;

  result.timings.total_ms = ms_since(start_ns);
  return result;
}

// Appearance scores in sigma (evidence.h): the temporal stage's sequence
// evidence, else (or for a young query) the standardised similarity of the
// search's candidates.
void Detector::score_candidates(AppearanceEvidence& evidence, bool every_frame, Result& result) {
  const SimilarityMetric metric = options_.similarity.metric;
  const int top_n = options_.search.top_n;
  if (options_.verification.has(kTemporalStage) && !evidence.young()) {
    if (every_frame) {
      evidence.best_places(top_n, result.candidates);
      places_ = result.candidates;
    } else {
      // The top_n places, then those the search follows to the next query.
      evidence.realign(store_, descriptor_.view(), raw_, search_->followed(), metric, top_n,
                        search_->realign_reach(), top_n + search_->follow(), places_);
      result.candidates.assign(places_.begin(),
                               places_.begin() + static_cast<std::ptrdiff_t>(std::min(
                                                     places_.size(), static_cast<std::size_t>(top_n))));
    }
    return;
  }
  // Single-frame scores: without the temporal stage, and for a young query
  // (too few candidates for sequence evidence; standardised with the prior).
  result.candidates.clear();
  if (evidence.similarity_statistics().valid()) {
    const std::size_t n = std::min(raw_.size(), static_cast<std::size_t>(top_n));
    for (std::size_t i = 0; i < n; ++i) {
      result.candidates.push_back({raw_[i].frame, evidence.single_frame(raw_[i].score)});
    }
  }
  places_ = result.candidates;
}

// The verification stages and the loop decision (decision.h).
void Detector::verify(AppearanceEvidence& evidence, bool store, Result& result,
                      const FrameDescription* described, int width, int height) {
  static const GrayImage kNoImage;  // a described frame's: its records stand for it
  const StageQuery query{result.frame, described != nullptr ? kNoImage : gray_, store_,
                         descriptor_.view(), width, height};
  // A query that is not stored: every stage begun forgets it again, and the
  // decision is put back, however the query ends.
  std::size_t begun = 0;
  const LoopDecision::Checkpoint checkpoint = decision_.checkpoint();
  struct Undo {
    Detector& d;
    const std::size_t& begun;
    std::int64_t frame;
    const LoopDecision::Checkpoint& checkpoint;
    bool active;
    ~Undo() {
      if (!active) return;
      for (std::size_t k = begun; k-- > 0;) d.stages_[k]->discard(frame);
      d.decision_.restore(checkpoint);
    }
  } undo{*this, begun, result.frame, checkpoint, !store};
  for (std::size_t k = 0; k < stages_.size(); ++k) {
    if (described != nullptr) {
      const std::vector<std::uint8_t>& record = described->records[k];
      stages_[k]->begin_described(
          query, StateReader(record.data(), record.size(),
                             std::string("the frame description's ") + stages_[k]->name() + " record"));
    } else {
      stages_[k]->begin(query);
    }
    ++begun;
  }
  const bool sequence = options_.verification.has(kTemporalStage);
  const SimilarityMetric metric = options_.similarity.metric;
  DecisionQuery q;
  q.frame = result.frame;
  q.candidates = &result.candidates;
  q.max_candidates = options_.verification.max_candidates;
  q.min_gap = options_.search.min_gap;
  q.continuity = sequence;
  q.tolerance = options_.verification.temporal_options.tolerance;
  q.cells = descriptor_.grid.cells();
  q.young = evidence.young();
  q.places = &place_cuts_.cuts();
  q.leap = [&](std::int64_t f) {
    return f == result.frame ? place_cuts_.leap(signature_) : place_cuts_.leap(f);
  };
  q.single_frame = [&](std::int64_t j) {
    return evidence.single_frame(lsgd::similarity(descriptor_.view(), store_.view(j), metric));
  };
  q.appearance = [&](std::int64_t j) {
    return sequence ? evidence.sequence(store_, descriptor_.view(), j, metric)
                    : evidence.single_frame(
                          lsgd::similarity(descriptor_.view(), store_.view(j), metric));
  };
  Decision decision = decision_.decide(q, stage_list_);
  result.loop = decision.loop;
  result.status = decision.status;
  result.geometry = std::move(decision.geometry);
  result.best = decision.best;
  result.evidence = decision.evidence;
  result.ranking = decision.ranking;
  result.verification = std::move(decision.verdicts);
  if (store) {
    for (const auto& stage : stages_) stage->end(result.frame, result.candidates);
  }
}

std::int64_t estimated_map_bytes(const DetectorOptions& options, std::int64_t frames, int cells) {
  const SearchMode mode = find_search_mode(options.search.mode);
  const auto descriptor =
      static_cast<std::int64_t>(Descriptor::bytes_per_frame(options.descriptor.storage, cells));
  const std::int64_t extra = mode.bytes_per_frame != nullptr ? mode.bytes_per_frame(options, cells) : 0;
  // The place signatures, with their contrast and cut found (places.h).
  const std::int64_t signature = place_cut(options) > 0 ? kPlaceBytesPerFrame : 0;
  return frames * (descriptor + extra + signature);
}

}  // namespace lsgd
