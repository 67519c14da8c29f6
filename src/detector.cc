#include "lsgd/detector.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>

#include "internal/check.h"
#include "internal/clock.h"
#include "internal/names.h"
#include "lsgd/limits.h"

namespace lsgd {
using internal::ms_since;
using internal::now_ns;

const OptionTable<DetectorOptions>& DetectorOptions::fields() {
  using S = DetectorOptions;
  static const OptionTable<S> table = [] {
    OptionTable<S> t;
    nest<S, SegmentationOptions>(t, "segmentation", &S::segmentation, SegmentationOptions::fields());
    nest<S, DescriptorOptions>(t, "descriptor", &S::descriptor, DescriptorOptions::fields());
    nest<S, SimilarityOptions>(t, "similarity", &S::similarity, SimilarityOptions::fields());
    nest<S, SearchOptions>(t, "search", &S::search, SearchOptions::fields());
    nest<S, VerificationOptions>(t, "verification", &S::verification, VerificationOptions::fields());
    nest<S, DecisionOptions>(t, "decision", &S::decision, DecisionOptions::fields());
    return t;
  }();
  return table;
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
    internal::throw_invalid("unknown option '", key, "'",
                            guess.empty() ? std::string() : "; did you mean '" + guess + "'?",
                            known.empty() ? std::string(" (see lsgd options)")
                                          : " (" + section + " has " + known + ")");
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

}  // namespace

Detector::Detector(const DetectorOptions& options)
    : options_(options),
      segmenter_((options.check(), options.segmentation)),
      search_(make_search(options.search)),
      evidence_(sequence_options(options.verification), options.search.min_gap,
                !search_->scores_every_frame(), kExactStatisticsCandidates,
                search_->scores_every_frame_up_to()),
      query_evidence_(evidence_),
      stages_(make_stages(options.verification)),
      decision_(options.decision) {
  for (const auto& stage : stages_) stage_list_.push_back(stage.get());
}

const VerificationStage* Detector::stage(const std::string& name) const {
  for (const auto& stage : stages_) {
    if (name == stage->name()) return stage.get();
  }
  return nullptr;
}

// Marks the detector busy for one call that changes it; a second call while
// one runs (another thread) throws instead of corrupting the state.
class Detector::Exclusive {
 public:
  Exclusive(std::atomic<bool>& busy, const char* call) : busy_(busy) {
    if (busy_.exchange(true, std::memory_order_acquire)) {
      internal::throw_invalid(
          "Detector::", call, " was called while another call on the same Detector was running "
          "(from another thread): a Detector is used by one thread at a time (one detector per "
          "thread, or a mutex around its calls)");
    }
  }
  ~Exclusive() { busy_.store(false, std::memory_order_release); }
  Exclusive(const Exclusive&) = delete;
  Exclusive& operator=(const Exclusive&) = delete;

 private:
  std::atomic<bool>& busy_;
};

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

Descriptor Detector::describe_gray() {
  if (store_.size() > 0 && (gray_.width != width_ || gray_.height != height_)) {
    internal::throw_invalid("the frame is ", gray_.width, "x", gray_.height,
                            " but the stored frames are ", width_, "x", height_,
                            ": every frame must have the same size");
  }
  segment_and_describe(segmenter_, gray_, segmentation_, exact_, describe_scratch_);
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

void Detector::FrameTags::save_frame(std::int64_t frame, StateWriter& out) const {
  out.put_i64(ids.at(static_cast<std::size_t>(frame)));
  out.put_f64(stamps.at(static_cast<std::size_t>(frame)));
}

void Detector::FrameTags::check_frame(std::int64_t, int, int, std::uint32_t version,
                                      StateReader in) const {
  if (!in.present()) return;
  check_state_version(in.what(), name(), version, 1);
  const std::int64_t id = in.get_i64();
  const double stamp = in.get_f64();
  in.finish();
  if (id <= last() || id > kMaxFrameId) {
    internal::throw_invalid(in.what(), ": id ", id, " is not above the last frame's id ", last());
  }
  if (given_id >= 0 && id != given_id) {
    internal::throw_invalid(in.what(), ": id ", id, ", but its row says ", given_id);
  }
  if (std::isinf(stamp)) internal::throw_invalid(in.what(), ": time stamp ", stamp);
}

void Detector::FrameTags::restore_frame(std::int64_t, int, int, std::uint32_t, StateReader in) {
  if (in.present()) {
    ids.push_back(in.get_i64());
    stamps.push_back(in.get_f64());
    return;
  }
  ids.push_back(given_id >= 0 ? given_id : last() + 1);
  stamps.push_back(kNoStamp);
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

std::int64_t Detector::forget(std::int64_t first_id, std::int64_t last_id) {
  const Exclusive exclusive(busy_, "forget");
  if (first_id > last_id) {
    internal::throw_invalid("Detector::forget: the first id ", first_id, " is above the last ",
                            last_id);
  }
  for (const Stateful* c : stateful()) {
    if (!c->forgets()) {
      internal::throw_invalid("Detector::forget: ", c->name(), " keeps per-frame state and cannot "
                              "forget frames (Stateful::forgets())");
    }
  }
  const auto first = std::lower_bound(tags_.ids.begin(), tags_.ids.end(), first_id);
  const auto last = std::upper_bound(first, tags_.ids.end(), last_id);
  const std::int64_t forgotten = last - first;
  if (forgotten == 0) return 0;
  std::vector<std::int64_t> after(static_cast<std::size_t>(size()));
  const auto from = static_cast<std::int64_t>(first - tags_.ids.begin());
  for (std::int64_t f = 0; f < size(); ++f) {
    after[static_cast<std::size_t>(f)] = f < from ? f : f < from + forgotten ? -1 : f - forgotten;
  }
  const bool last_kept = after.back() >= 0;
  const bool cut_pending = continuity().held.loop < 0 && decision_.ranking_track().held.loop < 0;
  auto kept = std::make_unique<Detector>(options_);
  kept->restore_kept(*this, FrameRenumbering(std::move(after)));
  // A cut() since the last frame still holds for the next one.
  if (last_kept && cut_pending) kept->decision_.cut();
  // Everything allocated: nothing below throws.
  std::swap(store_, kept->store_);
  std::swap(search_, kept->search_);
  std::swap(evidence_, kept->evidence_);
  std::swap(query_evidence_, kept->query_evidence_);
  std::swap(stages_, kept->stages_);
  std::swap(stage_list_, kept->stage_list_);
  std::swap(decision_, kept->decision_);
  std::swap(tags_, kept->tags_);
  return forgotten;
}

namespace {

// A stored frame's descriptor as one to store again.
Descriptor copy_of(const DescriptorView& v, const GridSize& grid) {
  Descriptor d;
  d.grid = grid;
  const auto cells = static_cast<std::size_t>(v.cells);
  if (v.storage() == HistogramStorage::kCompact) {
    d.storage = HistogramStorage::kCompact;
    d.compact.assign(v.compact, v.compact + cells * kCompactBins);
    d.cell_pixels = v.cell_pixels;
  } else {
    d.hist.assign(v.hist, v.hist + cells * kBins);
    d.pixels.assign(v.pixels, v.pixels + cells);
  }
  return d;
}

}  // namespace

void Detector::restore_kept(const Detector& from, const FrameRenumbering& renumbered) {
  const std::vector<Stateful*> mine = stateful(), theirs = from.stateful();
  StateWriter writer;
  std::int64_t frame = 0;
  for (std::int64_t f = 0; f < from.size(); ++f) {
    if (renumbered.after(f) < 0) continue;
    for (std::size_t c = 0; c < mine.size(); ++c) {
      writer.clear();
      theirs[c]->save_frame(f, writer);
      const std::string what =
          internal::concat("forget: frame ", f, "'s ", theirs[c]->name(), " state");
      mine[c]->restore_renumbered(frame, from.width_, from.height_, theirs[c]->state_version(),
                                  StateReader(writer.bytes().data(), writer.bytes().size(), what),
                                  renumbered);
    }
    const std::int64_t group = search_->has_groups() ? search_->group_of(frame) : 0;
    store_.add(copy_of(from.store_.view(f), from.store_.grid()),
               std::clamp<std::int64_t>(group, 0, store_.groups()));
    ++frame;
  }
  width_ = from.width_;
  height_ = from.height_;
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
  if (store_.size() > 0 && (gray_.width != width_ || gray_.height != height_)) {
    internal::throw_invalid("the frame is ", gray_.width, "x", gray_.height,
                            " but the first frame was ", width_, "x", height_,
                            ": every frame must have the same size");
  }
  Result result;
  result.frame = store_.size();
  result.id = id;
  result.stamp = stamp;
  result.timings.convert_ms = convert_ms;

  // The histograms are counted during the segmentation's last pass, so
  // segment_ms includes them and describe_ms is the storage encoding.
  std::int64_t t = now_ns();
  segment_and_describe(segmenter_, gray_, segmentation_, exact_, describe_scratch_);
  result.timings.segment_ms = ms_since(t);

  t = now_ns();
  if (options_.descriptor.storage == HistogramStorage::kCompact) {
    compact(exact_, descriptor_);
  } else {
    std::swap(exact_, descriptor_);  // descriptor_ is the frame's descriptor as stored
  }
  result.timings.describe_ms = ms_since(t);

  t = now_ns();
  const SimilarityMetric metric = options_.similarity.metric;
  const CandidateSearch::Query search_query{store_, descriptor_.view(), result.frame, metric};
  const CandidateSearch::Outcome outcome = store ? search_->search(search_query, raw_, row_)
                                                 : search_->query(search_query, raw_, row_);
  result.node = outcome.group;
  result.node_created = outcome.created;
  result.timings.insert_ms = outcome.insert_ms;
  // After a restore the evidence is recomputed from the stored frames first.
  const std::int64_t evidence_start = now_ns();
  if (evidence_.last_query() != result.frame - 1) evidence_.rebuild(store_, metric);
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
  verify(evidence, store, result);
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
  tags_.ids.push_back(id);
  tags_.stamps.push_back(stamp);
  if (result.frame == 0) width_ = gray_.width, height_ = gray_.height;

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
void Detector::verify(AppearanceEvidence& evidence, bool store, Result& result) {
  const StageQuery query{result.frame, gray_, store_, descriptor_.view()};
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
  for (const auto& stage : stages_) {
    stage->begin(query);
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

std::vector<Stateful*> Detector::stateful() const {
  std::vector<Stateful*> out;
  if (search_->has_state()) out.push_back(search_.get());
  for (const auto& stage : stages_) {
    if (stage->has_state()) out.push_back(stage.get());
  }
  out.push_back(const_cast<LoopDecision*>(&decision_));
  out.push_back(const_cast<FrameTags*>(&tags_));
  return out;
}

std::vector<std::uint8_t> Detector::frame_state(std::int64_t frame) const {
  if (frame < 0 || frame >= store_.size()) {
    internal::throw_invalid("frame_state: frame ", frame, " is not stored (", store_.size(),
                            " frames)");
  }
  std::vector<StateRecord> records;
  StateWriter writer;
  for (const Stateful* c : stateful()) {
    writer.clear();
    c->save_frame(frame, writer);
    records.push_back({c->name(), c->state_version(), writer.bytes()});
  }
  return encode_records(records);
}

void Detector::restore_index(const std::uint8_t* data, std::size_t size) {
  const Exclusive exclusive(busy_, "restore_index");
  search_->restore_index(store_, options_.similarity.metric, data, size);
}

void Detector::restore_frame(int width, int height, const Descriptor& descriptor,
                             const std::vector<std::uint8_t>& state, std::int64_t id) {
  const Exclusive exclusive(busy_, "restore_frame");
  const std::int64_t frame = store_.size();
  if (width <= 0 || height <= 0 || (frame > 0 && (width != width_ || height != height_))) {
    internal::throw_invalid("restore_frame: frame ", frame, " is ", width, "x", height,
                            " but the detector holds ", width_, "x", height_, " frames");
  }
  const GridSize expected = grid_size(width, height, options_.segmentation.superpixel_size);
  if (descriptor.grid != expected) {
    internal::throw_invalid("restore_frame: frame ", frame, " has a ", descriptor.grid.rows, "x",
                            descriptor.grid.cols, " grid, but ", width, "x", height,
                            " frames have a ", expected.rows, "x", expected.cols, " grid");
  }
  if (descriptor.storage != options_.descriptor.storage) {
    internal::throw_invalid("restore_frame: frame ", frame, " has a ",
                            to_string(descriptor.storage), " descriptor but descriptor.storage is ",
                            to_string(options_.descriptor.storage));
  }
  descriptor.check_consistent("restore_frame");
  if (descriptor.storage == HistogramStorage::kCompact &&
      std::fabs(descriptor.cell_pixels * expected.cells() - static_cast<double>(width) * height) >
          0.5) {
    internal::throw_invalid("restore_frame: frame ", frame, " has ", descriptor.cell_pixels,
                            " pixels per cell, but ", width, "x", height, " frames have ",
                            static_cast<double>(width) * height / expected.cells());
  }
  std::vector<StateRecord> records;
  try {
    records = decode_records(state.data(), state.size());
  } catch (const InvalidArgument& e) {
    internal::throw_invalid("restore_frame: frame ", frame, ": ", e.what());
  }
  const std::vector<Stateful*> components = stateful();
  for (const StateRecord& r : records) {
    if (std::none_of(components.begin(), components.end(),
                     [&](const Stateful* c) { return r.component == c->name(); })) {
      internal::throw_invalid("restore_frame: frame ", frame, " has state of '", r.component,
                              "', which these options do not have (search mode ", search_->name(),
                              ", verification stages ", verification_stages(options_.verification),
                              ")");
    }
  }
  // Every component checks its record before any changes, so that a
  // refused frame leaves the detector unchanged.
  const auto reader = [&](const Stateful* c) {
    const std::string what = internal::concat("restore_frame: frame ", frame, "'s ", c->name(),
                                              " state");
    for (const StateRecord& r : records) {
      if (r.component == c->name()) return StateReader(r.bytes.data(), r.bytes.size(), what);
    }
    return StateReader(what);
  };
  const auto version = [&](const Stateful* c) {
    for (const StateRecord& r : records) {
      if (r.component == c->name()) return r.version;
    }
    return c->state_version();
  };
  if (id < -1 || id > kMaxFrameId || (id >= 0 && id <= tags_.last())) {
    internal::throw_invalid("restore_frame: frame ", frame, "'s id ", id, " is not above the last frame's id ",
                            tags_.last());
  }
  tags_.given_id = id;
  for (const Stateful* c : components) c->check_frame(frame, width, height, version(c), reader(c));
  for (Stateful* c : components) c->restore_frame(frame, width, height, version(c), reader(c));
  // The search's group places the frame beside the group's other frames.
  const std::int64_t group = search_->has_groups() ? search_->group_of(frame) : 0;
  store_.add(descriptor, std::clamp<std::int64_t>(group, 0, store_.groups()));
  width_ = width;
  height_ = height;
}

std::int64_t estimated_map_bytes(const DetectorOptions& options, std::int64_t frames, int cells) {
  const SearchMode mode = find_search_mode(options.search.mode);
  const auto descriptor =
      static_cast<std::int64_t>(Descriptor::bytes_per_frame(options.descriptor.storage, cells));
  const std::int64_t extra = mode.bytes_per_frame != nullptr ? mode.bytes_per_frame(options, cells) : 0;
  return frames * (descriptor + extra);
}

}  // namespace lsgd
