#include "lsgd/search/index.h"

// hnswlib 0.6.2's SSE path prefetches one link past the end of a node's link
// list (an out-of-bounds read AddressSanitizer reports in searchBaseLayer);
// its vector kernels are for its own L2/IP spaces, which we do not use.
#define NO_MANUAL_VECTORIZATION
#include <hnswlib/hnswlib.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>

#include "internal/check.h"
#include "internal/clock.h"
#include "lsgd/state.h"
#include "search/scoring.h"

namespace lsgd {
namespace {

// The graph's key of a frame: per cell, its histogram pooled into kKeyBins
// bins of kBins / kKeyBins intensities, normalised to kKeyMass (rounded), so
// a cell's key is 16 bytes and a frame's key cells * 16 bytes (1,280 bytes for
// a 1241x376 frame at 80 cells, an eighth of its compact descriptor). Pooling
// adjacent bins never increases an L1 distance, so the key distance
// sum_k sqrt(SAD_k) (reference metric; sum_k SAD_k for the L1 metrics) is a
// coarse lower-bound-like proxy of the metric that reads 1/8 (compact) or 1/32
// (exact) of the bytes, from the graph's own memory next to the links.
constexpr int kKeyBins = 16;
constexpr int kKeyMass = 255;
// A cell's key sums to at most kKeyMass plus half a unit of rounding per bin.
constexpr int kMaxKeySad = 2 * (kKeyMass + kKeyBins / 2);

void make_key(const DescriptorView& d, std::uint8_t* key) {
  for (int c = 0; c < d.cells; ++c) {
    std::uint32_t pooled[kKeyBins] = {};
    double mass = 0;
    if (d.compact != nullptr) {
      const CompactBin* h = d.compact + static_cast<std::size_t>(c) * kCompactBins;
      constexpr int per = kCompactBins / kKeyBins;
      for (int b = 0; b < kCompactBins; ++b) pooled[b / per] += h[b];
      for (const std::uint32_t v : pooled) mass += v;
    } else {
      const Bin* h = d.hist + static_cast<std::size_t>(c) * kBins;
      constexpr int per = kBins / kKeyBins;
      for (int b = 0; b < kBins; ++b) pooled[b / per] += h[b];
      mass = d.pixels[c];
    }
    for (int b = 0; b < kKeyBins; ++b) {
      const double v = mass > 0 ? std::round(pooled[b] * kKeyMass / mass) : 0.0;
      key[static_cast<std::size_t>(c) * kKeyBins + b] = static_cast<std::uint8_t>(std::min(v, 255.0));
    }
  }
}

// What the graph's distance function reads: the key length and the per-cell
// cost of a SAD (its square root for the reference metric).
struct KeySpaceParam {
  int cells = 0;
  float cost[kMaxKeySad + 1] = {};
};

float key_distance(const void* a, const void* b, const void* param) {
  const auto& p = *static_cast<const KeySpaceParam*>(param);
  const auto* x = static_cast<const std::uint8_t*>(a);
  const auto* y = static_cast<const std::uint8_t*>(b);
  float sum = 0;
  for (int c = 0; c < p.cells; ++c, x += kKeyBins, y += kKeyBins) {
#if defined(__SSE2__)
    // One psadbw per cell (SSE2 is the x86-64 baseline: no dispatch needed).
    const __m128i d = _mm_sad_epu8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(x)),
                                   _mm_loadu_si128(reinterpret_cast<const __m128i*>(y)));
    const int sad = _mm_cvtsi128_si32(d) + _mm_extract_epi16(d, 4);
#else
    int sad = 0;
    for (int i = 0; i < kKeyBins; ++i) sad += std::abs(int{x[i]} - int{y[i]});
#endif
    sum += p.cost[sad];
  }
  return sum;
}

// hnswlib's space: the frame's key as the data, key_distance as the distance.
class KeySpace final : public hnswlib::SpaceInterface<float> {
 public:
  KeySpace(int cells, SimilarityMetric metric) {
    param_.cells = cells;
    for (int s = 0; s <= kMaxKeySad; ++s) {
      param_.cost[s] = metric == SimilarityMetric::kReference ? std::sqrt(static_cast<float>(s))
                                                              : static_cast<float>(s);
    }
  }
  size_t get_data_size() override { return static_cast<std::size_t>(param_.cells) * kKeyBins; }
  hnswlib::DISTFUNC<float> get_dist_func() override { return key_distance; }
  void* get_dist_func_param() override { return &param_; }
  int cells() const { return param_.cells; }

 private:
  KeySpaceParam param_;
};

class IndexSearch final : public CandidateSearch {
 public:
  explicit IndexSearch(const SearchOptions& options) : options_(options) {}
  const char* name() const override { return kIndexSearch; }
  bool scores_every_frame() const override { return false; }

  Outcome search(const Query& q, std::vector<Candidate>& out, std::vector<double>&) override {
    out.clear();
    // Frames that left the temporal window join the graph.
    const std::int64_t limit = std::max<std::int64_t>(0, std::min(q.store.size(), q.id - options_.min_gap));
    Outcome outcome;
    try {
      if (inserted_ < limit) {
        const std::int64_t start = internal::now_ns();
        outcome.inserted = limit - inserted_;
        while (inserted_ < limit) insert(q.store, q.metric, inserted_++);
        outcome.insert_ms = internal::ms_since(start);
      }
      if (inserted_ == 0) return outcome;
      const auto k = static_cast<std::size_t>(std::min<std::int64_t>(
          inserted_, std::max<std::int64_t>(options_.index.shortlist, options_.top_n)));
      graph_->setEf(std::max<std::size_t>(k, static_cast<std::size_t>(options_.index.ef_search)));
      key_.resize(space_->get_data_size());
      make_key(q.descriptor, key_.data());
      auto found = graph_->searchKnn(key_.data(), k);
      ids_.clear();
      while (!found.empty()) {
        ids_.push_back(static_cast<std::int64_t>(found.top().second));
        found.pop();
      }
      // The previous frame's places, one frame on along their diagonals: a
      // revisit whose sequence stands out stays in the shortlist even where
      // single frames look alike elsewhere.
      if (previous_frame_ == q.id - 1) {
        for (const std::int64_t j : previous_) {
          if (j >= 0 && j + 1 < limit) ids_.push_back(j + 1);
        }
      }
      std::sort(ids_.begin(), ids_.end());
      ids_.erase(std::unique(ids_.begin(), ids_.end()), ids_.end());
      scratch_.clear();
      // Re-scored exactly: the candidates' scores are the metric's own.
      for (const std::int64_t j : ids_) {
        scratch_.push_back({j, similarity(q.descriptor, q.store.view(j), q.metric)});
      }
    } catch (const InvalidArgument&) {
      throw;
    } catch (const std::exception& e) {  // hnswlib reports allocation failures as runtime_error
      internal::throw_invalid("search mode index: the graph failed (", e.what(), ") at frame ", q.id);
    }
    // The whole shortlist, best first: the temporal stage realigns every one
    // (a place whose sequence stands out may rank low on one frame) and keeps
    // top_n (Detector::score_candidates).
    internal::keep_best(scratch_, static_cast<int>(scratch_.size()), out);
    return outcome;
  }

  void end(std::int64_t frame, const std::vector<Candidate>& candidates) override {
    previous_frame_ = frame;
    previous_.clear();
    for (const Candidate& c : candidates) previous_.push_back(c.frame);
  }

  // State, version 1: the places the frame's candidates pointed to (count,
  // then int64 ids), for the frame after it; written for the last frame ended
  // (older frames: an empty record, as only the last one is read). The graph
  // itself is rebuilt from the stored frames at the first query.
  bool has_state() const override { return true; }
  void save_frame(std::int64_t frame, StateWriter& out) const override {
    if (frame != previous_frame_) return;
    out.put_i64(static_cast<std::int64_t>(previous_.size()));
    for (const std::int64_t j : previous_) out.put_i64(j);
  }
  void check_frame(std::int64_t frame, int, int, std::uint32_t version,
                   StateReader in) const override {
    if (!in.present() || in.empty()) return;
    check_state_version(in.what(), name(), version, 1);
    const std::int64_t n = in.get_i64();
    if (n < 0 || static_cast<std::uint64_t>(n) > in.remaining() / 8) {
      internal::throw_invalid(in.what(), ": ", n, " candidates do not fit the record");
    }
    for (std::int64_t k = 0; k < n; ++k) {
      const std::int64_t j = in.get_i64();
      if (j < -1 || j >= frame) internal::throw_invalid(in.what(), ": candidate ", j, " is not an earlier frame");
    }
    in.finish();
  }
  void restore_frame(std::int64_t frame, int, int, std::uint32_t, StateReader in) override {
    previous_frame_ = frame;
    previous_.clear();
    if (!in.present() || in.empty()) return;
    const std::int64_t n = in.get_i64();
    for (std::int64_t k = 0; k < n; ++k) previous_.push_back(in.get_i64());
  }

 private:
  void insert(const FrameStore& store, SimilarityMetric metric, std::int64_t frame) {
    const DescriptorView d = store.view(frame);
    if (!space_) space_ = std::make_unique<KeySpace>(d.cells, metric);
    if (d.cells != space_->cells()) {
      internal::throw_invalid("search mode index: frame ", frame, " has ", d.cells,
                              " cells, the graph's frames ", space_->cells());
    }
    key_.resize(space_->get_data_size());
    make_key(d, key_.data());
    if (!graph_ || graph_->cur_element_count >= graph_->max_elements_) {
      const std::size_t capacity = graph_ ? 2 * graph_->max_elements_ : 1024;
      if (!graph_) {
        graph_ = std::make_unique<hnswlib::HierarchicalNSW<float>>(
            space_.get(), capacity, static_cast<std::size_t>(options_.index.m),
            static_cast<std::size_t>(options_.index.ef_construction), /*random_seed=*/100);
      } else {
        graph_->resizeIndex(capacity);
      }
    }
    graph_->addPoint(key_.data(), static_cast<hnswlib::labeltype>(frame));
  }

  SearchOptions options_;
  std::unique_ptr<KeySpace> space_;  // made at the first insertion (it needs the cell count)
  std::unique_ptr<hnswlib::HierarchicalNSW<float>> graph_;
  std::int64_t inserted_ = 0;  // frames 0 .. inserted_-1 are in the graph
  std::int64_t previous_frame_ = -1;    // the last frame ended
  std::vector<std::int64_t> previous_;  // ... and its candidates' frames, best first
  std::vector<std::int64_t> ids_;
  std::vector<std::uint8_t> key_;
  std::vector<Candidate> scratch_;
};

}  // namespace

std::unique_ptr<CandidateSearch> make_index_search(const SearchOptions& options) {
  return std::make_unique<IndexSearch>(options);
}

}  // namespace lsgd
