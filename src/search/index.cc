#include "lsgd/search/index.h"

// hnswlib 0.6.2's SSE path prefetches one link past the end of a node's link
// list (an out-of-bounds read AddressSanitizer reports in searchBaseLayer);
// its vector kernels are for its own L2/IP spaces, which we do not use.
#define NO_MANUAL_VECTORIZATION
#include <hnswlib/hnswlib.h>

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

// What the graph's distance function reads: the stored frames, and the
// query (id -1), which is searched before it is stored.
struct Frames {
  const FrameStore* store = nullptr;
  DescriptorView query;
  SimilarityMetric metric = SimilarityMetric::kReference;
};

constexpr std::int64_t kQuery = -1;

float frame_distance(const void* a, const void* b, const void* param) {
  const auto& f = *static_cast<const Frames*>(param);
  std::int64_t ia = 0, ib = 0;
  std::memcpy(&ia, a, sizeof ia);
  std::memcpy(&ib, b, sizeof ib);
  const DescriptorView va = ia == kQuery ? f.query : f.store->view(ia);
  const DescriptorView vb = ib == kQuery ? f.query : f.store->view(ib);
  const double s = similarity(va, vb, f.metric);
  return s > 0 ? static_cast<float>(1.0 / s - 1.0) : std::numeric_limits<float>::max();
}

// hnswlib's space: 8-byte frame ids as the data, frame_distance as the distance.
class FrameSpace final : public hnswlib::SpaceInterface<float> {
 public:
  explicit FrameSpace(const Frames* frames) : frames_(frames) {}
  size_t get_data_size() override { return sizeof(std::int64_t); }
  hnswlib::DISTFUNC<float> get_dist_func() override { return frame_distance; }
  void* get_dist_func_param() override { return const_cast<Frames*>(frames_); }

 private:
  const Frames* frames_;
};

class IndexSearch final : public CandidateSearch {
 public:
  explicit IndexSearch(const SearchOptions& options) : options_(options), space_(&frames_) {}
  const char* name() const override { return kIndexSearch; }
  bool scores_every_frame() const override { return false; }

  Outcome search(const Query& q, std::vector<Candidate>& out, std::vector<double>&) override {
    out.clear();
    frames_.store = &q.store;
    frames_.query = q.descriptor;
    frames_.metric = q.metric;
    // Frames that left the temporal window join the graph.
    const std::int64_t limit = std::max<std::int64_t>(0, std::min(q.store.size(), q.id - options_.min_gap));
    Outcome outcome;
    try {
      if (inserted_ < limit) {
        const std::int64_t start = internal::now_ns();
        outcome.inserted = limit - inserted_;
        while (inserted_ < limit) insert(inserted_++);
        outcome.insert_ms = internal::ms_since(start);
      }
      if (inserted_ == 0) return outcome;
      const auto k = static_cast<std::size_t>(std::min<std::int64_t>(
          inserted_, std::max<std::int64_t>(options_.index.shortlist, options_.top_n)));
      graph_->setEf(std::max<std::size_t>(k, static_cast<std::size_t>(options_.index.ef_search)));
      std::int64_t query = kQuery;
      auto found = graph_->searchKnn(&query, k);
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
  void insert(std::int64_t frame) {
    if (!graph_ || graph_->cur_element_count >= graph_->max_elements_) {
      const std::size_t capacity = graph_ ? 2 * graph_->max_elements_ : 1024;
      if (!graph_) {
        graph_ = std::make_unique<hnswlib::HierarchicalNSW<float>>(
            &space_, capacity, static_cast<std::size_t>(options_.index.m),
            static_cast<std::size_t>(options_.index.ef_construction), /*random_seed=*/100);
      } else {
        graph_->resizeIndex(capacity);
      }
    }
    graph_->addPoint(&frame, static_cast<hnswlib::labeltype>(frame));
  }

  SearchOptions options_;
  Frames frames_;
  FrameSpace space_;
  std::unique_ptr<hnswlib::HierarchicalNSW<float>> graph_;
  std::int64_t inserted_ = 0;  // frames 0 .. inserted_-1 are in the graph
  std::int64_t previous_frame_ = -1;    // the last frame ended
  std::vector<std::int64_t> previous_;  // ... and its candidates' frames, best first
  std::vector<std::int64_t> ids_;
  std::vector<Candidate> scratch_;
};

}  // namespace

std::unique_ptr<CandidateSearch> make_index_search(const SearchOptions& options) {
  return std::make_unique<IndexSearch>(options);
}

}  // namespace lsgd
