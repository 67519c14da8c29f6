#include "lsgd/detector.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>

#include "internal/check.h"

namespace lsgd {
namespace {

using Clock = std::chrono::steady_clock;

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

double ms_since(std::int64_t start_ns) { return (now_ns() - start_ns) * 1e-6; }

}  // namespace

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
    internal::throw_invalid("unknown option '", key, "'",
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
  s.enabled = v.temporal;
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
                !search_->scores_every_frame()),
      temporal_(options.verification.temporal_options),
      geometric_(options.verification.geometric_options) {}

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

Result Detector::process(const cv::Mat& frame) {
  const Exclusive exclusive(busy_, "process");
  const std::int64_t start = now_ns();
  to_gray(frame, gray_);
  return process_gray(ms_since(start), start);
}

Result Detector::process(const ImageView& frame) {
  const Exclusive exclusive(busy_, "process");
  const std::int64_t start = now_ns();
  to_gray(frame, gray_);
  return process_gray(ms_since(start), start);
}

std::int64_t Detector::nodes() const { return search_->groups(); }

double Detector::similarity(std::int64_t a, std::int64_t b) const {
  return lsgd::similarity(store_.view(a), store_.view(b), options_.similarity.metric);
}

Result Detector::process_gray(double convert_ms, std::int64_t start_ns) {
  if (store_.size() > 0 && (gray_.width != width_ || gray_.height != height_)) {
    internal::throw_invalid("the frame is ", gray_.width, "x", gray_.height,
                            " but the first frame was ", width_, "x", height_,
                            ": every frame must have the same size");
  }
  Result result;
  result.frame = store_.size();
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
  const CandidateSearch::Outcome outcome =
      search_->search({store_, descriptor_.view(), result.frame, metric}, raw_, row_);
  result.node = outcome.group;
  result.node_created = outcome.created;
  // After a restore the evidence is recomputed from the stored frames first.
  if (evidence_.last_query() != result.frame - 1) evidence_.rebuild(store_, metric);
  evidence_.add_query(store_, descriptor_.view(), result.frame, metric,
                      search_->scores_every_frame() ? &row_ : nullptr);
  score_candidates(result);
  result.timings.search_ms = ms_since(t);

  t = now_ns();
  verify(result);
  result.timings.verify_ms = ms_since(t);
  // A node's frames sit together in the store: scoring its members reads one
  // run of memory (FrameStore groups). The group is only a placement, so a
  // node the store has no group for (frames restored without their nodes)
  // gets a new one rather than an error.
  store_.add(descriptor_, std::clamp<std::int64_t>(result.node, 0, store_.groups()));
  if (result.frame == 0) width_ = gray_.width, height_ = gray_.height;

  result.timings.total_ms = ms_since(start_ns);
  return result;
}

// Appearance scores in sigma (evidence.h): the temporal stage's sequence
// evidence, else the standardised similarity of the search's candidates.
void Detector::score_candidates(Result& result) {
  const SimilarityMetric metric = options_.similarity.metric;
  const int top_n = options_.search.top_n;
  if (options_.verification.temporal) {
    if (search_->scores_every_frame()) {
      evidence_.best_places(top_n, result.candidates);
    } else {
      evidence_.realign(store_, descriptor_.view(), raw_, metric, top_n, result.candidates);
    }
    return;
  }
  result.candidates.clear();
  if (!evidence_.similarity_statistics().valid()) return;
  for (const Candidate& c : raw_) result.candidates.push_back({c.frame, evidence_.single_frame(c.score)});
}

// Examines the best candidates (decision.h): the agreement gate (temporal,
// agree > 0) and the geometric check can reject a candidate; a confirmed one
// earns the bonuses. Geometry is only checked for a candidate that could
// reach the threshold with them. When the previous frame declared a loop, the
// best frame that continues it stands in for every candidate that does, and
// is examined even when no candidate does (dynamic nodes may not hold it; a
// weak continuation may rank low); the candidate that could earn the highest
// score goes first. The first confirmed candidate is reported; when none is,
// the best candidate the agreement gate let through is reported with its
// appearance score (below the threshold if geometry rejected it), so that the
// ranking of unconfirmed reports is the temporal stage's own.
void Detector::verify(Result& result) {
  const VerificationOptions& v = options_.verification;
  const DecisionOptions& d = options_.decision;
  const int tolerance = v.temporal_options.tolerance;
  if (v.geometric) geometric_.add(gray_);
  result.evidence.appearance = std::numeric_limits<double>::quiet_NaN();
  const std::size_t n =
      std::min(result.candidates.size(), static_cast<std::size_t>(v.max_candidates));

  // 1. The agreement gate.
  gated_.assign(n, 0);  // 1: the gate rejected it
  if (v.temporal && v.temporal_options.agree > 0) {
    for (std::size_t i = 0; i < n; ++i) {
      const Candidate& c = result.candidates[i];
      const std::int64_t start = now_ns();
      const auto check = temporal_.agree(result.frame, c);
      result.verification.push_back(
          {c.frame, "temporal", check.accepted, check.reason, ms_since(start)});
      gated_[i] = check.accepted ? 0 : 1;
    }
  }
  std::size_t first = 0;  // the best candidate the gate let through
  while (first < n && gated_[first]) ++first;

  // 2. Geometric confirmation, continuation first when it could score higher.
  int first_inliers = -1;   // inliers of result.candidates[first] when checked
  bool first_rejected = false;
  if (v.geometric) {
    const bool continuity = v.temporal && d.continuity_bonus > 0;
    const auto continues = [&](const Candidate& c) {
      return continuity && continuity_.continues(result.frame, c.frame, tolerance);
    };
    const Candidate continuation =
        continuity && continuity_.continues(result.frame, continuity_.loop + 1, tolerance)
            ? continuation_candidate(result.frame)
            : Candidate{};
    examined_.clear();
    bool has_continuation = false;
    for (std::size_t i = 0; i < n; ++i) {
      if (gated_[i]) continue;
      const Candidate& c = result.candidates[i];
      if (continuation.frame >= 0 && continues(c)) {
        if (has_continuation) continue;  // the window is examined once
        has_continuation = true;
        examined_.push_back(better(continuation, c) ? continuation : c);
      } else {
        examined_.push_back(c);
      }
    }
    if (continuation.frame >= 0 && !has_continuation) examined_.push_back(continuation);
    const auto potential = [&](const Candidate& c) {
      return c.score + d.geometric_bonus + (continues(c) ? d.continuity_bonus : 0.0);
    };
    std::stable_sort(examined_.begin(), examined_.end(),
                     [&](const Candidate& a, const Candidate& b) { return potential(a) > potential(b); });
    for (const Candidate& c : examined_) {
      const double score = potential(c);
      if (score < d.threshold) break;  // sorted: no later one can reach it either
      GeometricCheck check = geometric_.verify(result.frame, c.frame);
      const bool continuing = continues(c);
      if (continuing) {
        const double needed = d.continuity_inliers * continuity_.inliers;
        check.accepted = check.inliers > 0 && check.inliers >= needed;
        check.reason += internal::concat("; continues the loop of frame ", result.frame - 1,
                                         ": needs ", needed, " inliers (", d.continuity_inliers,
                                         " of its average ", continuity_.inliers, ")");
      }
      result.verification.push_back({c.frame, "geometric", check.accepted, check.reason, check.ms});
      if (first < n && c.frame == result.candidates[first].frame) {
        first_inliers = check.inliers;
        first_rejected = !check.accepted;
      }
      if (check.accepted) {
        result.best = {c.frame, score};
        result.evidence = {c.score, check.inliers, true, continuing};
        break;
      }
    }
  }

  // 3. Nothing confirmed: the best candidate through the gate, unconfirmed.
  if (result.best.frame < 0 && first < n) {
    const Candidate& c = result.candidates[first];
    double score = c.score;
    // Rejected by geometry, or appearance alone on a degenerate grid: never a loop.
    const bool untrusted = !v.geometric && descriptor_.grid.cells() < kMinAppearanceCells;
    if (first_rejected || untrusted) score = std::min(score, std::nextafter(d.threshold, -1.0));
    result.best = {c.frame, score};
    result.evidence.appearance = c.score;
    result.evidence.inliers = first_inliers;
  }
  result.loop = result.best.frame >= 0 && result.best.score >= d.threshold;
  continuity_.record(result.frame, result.loop ? result.best.frame : -1, result.evidence.inliers,
                     result.loop && result.evidence.continues);
  if (v.temporal) {
    temporal_.push(result.frame, result.candidates.empty() ? -1 : result.candidates.front().frame);
  }
}

// The best-scored frame that continues the previous frame's loop
// (ContinuityState::continues; outside the temporal window), scored as the
// candidates are; frame -1 when there is none.
Candidate Detector::continuation_candidate(std::int64_t query) {
  const SimilarityMetric metric = options_.similarity.metric;
  const int tolerance = options_.verification.temporal_options.tolerance;
  const std::int64_t limit = query - options_.search.min_gap;
  Candidate best;
  for (std::int64_t j = continuity_.loop; j <= std::min(limit - 1, continuity_.loop + 1 + tolerance);
       ++j) {
    const double score =
        options_.verification.temporal
            ? evidence_.sequence(store_, descriptor_.view(), j, metric)
            : evidence_.single_frame(lsgd::similarity(descriptor_.view(), store_.view(j), metric));
    if (std::isnan(score)) return {};
    const Candidate c{j, score};
    if (best.frame < 0 || better(c, best)) best = c;
  }
  return best;
}

void Detector::restore_frame(int width, int height, const Descriptor& descriptor,
                             const std::vector<float>& points, const std::vector<std::uint8_t>& orb,
                             std::int64_t node) {
  const Exclusive exclusive(busy_, "restore_frame");
  const std::int64_t frame = store_.size();
  const bool groups = search_->has_groups();
  const std::int64_t max_node = groups ? store_.groups() : 0;
  if (node < 0 || node > max_node) {
    internal::throw_invalid("restore_frame: frame ", frame, " has node ", node, ": expected 0 to ",
                            max_node,
                            groups ? " (an earlier node or the next new one)"
                                   : internal::concat(" (the search mode ", search_->name(),
                                                      " has no groups)"));
  }
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
  if (!options_.verification.geometric && (!points.empty() || !orb.empty())) {
    internal::throw_invalid("restore_frame: frame ", frame,
                            " has ORB features but geometric verification is off");
  }
  // add_features() below validates too; checked here first so that a bad
  // frame leaves the store unchanged.
  if (points.size() % 2 != 0 || orb.size() != points.size() / 2 * kOrbBytes ||
      !std::all_of(points.begin(), points.end(), [](float v) { return std::isfinite(v); })) {
    internal::throw_invalid("restore_frame: frame ", frame, " has ", points.size(),
                            " keypoint coordinates and ", orb.size(),
                            " ORB bytes: not 2 finite coordinates and ", kOrbBytes,
                            " bytes per keypoint");
  }
  store_.add(descriptor, node);
  if (options_.verification.geometric) geometric_.add_features(points, orb, width, height);
  width_ = width;
  height_ = height;
}

void Detector::restore_nodes(std::vector<std::vector<std::int64_t>> nodes) {
  const Exclusive exclusive(busy_, "restore_nodes");
  search_->restore_groups(std::move(nodes), store_.size());
}

void Detector::restore_continuity(const ContinuityState& state) {
  const Exclusive exclusive(busy_, "restore_continuity");
  if (state.query != store_.size() - 1 || state.loop < -1 || state.loop >= state.query ||
      !std::isfinite(state.inliers) || state.inliers < 0) {
    internal::throw_invalid("restore_continuity: frame ", state.query, " with loop ", state.loop,
                            " and ", state.inliers, " inliers, but ", store_.size(),
                            " frames are stored");
  }
  continuity_ = state;
}

void Detector::restore_temporal(std::int64_t last_query, std::vector<std::int64_t> places) {
  const Exclusive exclusive(busy_, "restore_temporal");
  if (!options_.verification.temporal) {
    internal::throw_invalid("restore_temporal: temporal verification is off");
  }
  if (last_query != store_.size() - 1) {
    internal::throw_invalid("restore_temporal: last query ", last_query, " but ", store_.size(),
                            " frames are stored");
  }
  for (const std::int64_t place : places) {
    if (place >= store_.size()) {
      internal::throw_invalid("restore_temporal: place ", place, " is not stored");
    }
  }
  temporal_.restore(last_query, std::move(places));
}

}  // namespace lsgd
