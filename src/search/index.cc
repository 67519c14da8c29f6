#include "lsgd/search/index.h"

// hnswlib 0.6.2's SSE path prefetches one link past the end of a node's link
// list (an out-of-bounds read AddressSanitizer reports in searchBaseLayer);
// its vector kernels are for its own L2/IP spaces, which we do not use.
#define NO_MANUAL_VECTORIZATION
#include <hnswlib/hnswlib.h>

#ifdef __linux__
#include <sys/mman.h>
#endif

#include <algorithm>
#include <cstring>
#include <exception>
#include <limits>
#include <sstream>
#include <string>

#include "internal/check.h"
#include "internal/clock.h"
#include "lsgd/detector.h"
#include "lsgd/evidence.h"
#include "lsgd/search/exhaustive.h"
#include "lsgd/state.h"
#include "search/index_key.h"
#include "search/scoring.h"

namespace lsgd {
namespace {

static_assert(IndexOptions{}.exhaustive_up_to == kExactStatisticsCandidates,
              "the index's statistics are exhaustive search's up to its exact ones");

using internal::KeySpaceParam;
using internal::key_distance;
using internal::kKeyBins;
using internal::make_key;

// hnswlib's space: the frame's key as the data, key_distance as the distance.
class KeySpace final : public hnswlib::SpaceInterface<float> {
 public:
  KeySpace(int cells, SimilarityMetric metric) : metric_(metric) {
    param_.cells = cells;
    param_.sqrt = metric == SimilarityMetric::kReference;
  }
  size_t get_data_size() override { return static_cast<std::size_t>(param_.cells) * kKeyBins; }
  hnswlib::DISTFUNC<float> get_dist_func() override { return key_distance; }
  void* get_dist_func_param() override { return &param_; }
  int cells() const { return param_.cells; }
  SimilarityMetric metric() const { return metric_; }

 private:
  KeySpaceParam param_;
  SimilarityMetric metric_;
};

// The graph's bottom layer (links, key and label of every frame, one block)
// on huge pages where the kernel has them: a query or an insertion reads a
// few thousand frames scattered over the block (1.4 GB at 10^6 frames), and
// with 4 KiB pages each read also walks page tables that no longer fit the
// caches. A hint on the whole 2 MiB pages inside the block; hnswlib
// reallocates the block when the graph grows, so it is given again then.
void advise_huge_pages(const hnswlib::HierarchicalNSW<float>& g) {
#ifdef __linux__
  constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
  const auto begin = reinterpret_cast<std::uintptr_t>(g.data_level0_memory_);
  const std::uintptr_t end = begin + g.max_elements_ * g.size_data_per_element_;
  const std::uintptr_t from = (begin + kHuge - 1) & ~(kHuge - 1), to = end & ~(kHuge - 1);
  if (to > from) madvise(reinterpret_cast<void*>(from), to - from, MADV_HUGEPAGE);
#else
  (void)g;
#endif
}

class IndexSearch final : public CandidateSearch {
 public:
  explicit IndexSearch(const SearchOptions& options) : options_(options) {}
  const char* name() const override { return kIndexSearch; }
  bool scores_every_frame() const override { return false; }
  // search.index.exhaustive_up_to (corridor + 4,000 distractors: 96 loops
  // declared with the graph from the start against exhaustive search's 102;
  // docs/performance.md).
  std::int64_t scores_every_frame_up_to() const override { return options_.index.exhaustive_up_to; }
  // A shortlist by single frames: the best aligned sequence of a revisit may
  // sit a few frames off its best single frame (lip6-outdoor: 979 of 981
  // reported candidates as exhaustive search's with 16, 972 without;
  // docs/results.md).
  std::int64_t realign_reach() const override { return 16; }
  int follow() const override { return options_.index.follow; }
  const std::vector<std::int64_t>& followed() const override { return followed_; }

  Outcome search(const Query& q, std::vector<Candidate>& out, std::vector<double>& row) override {
    out.clear();
    followed_.clear();
    // Frames that left the temporal window join the graph.
    const std::int64_t limit = std::max<std::int64_t>(0, std::min(q.store.size(), q.id - options_.min_gap));
    Outcome outcome;
    try {
      if (inserted_ < limit) insert_up_to(q, limit, outcome);
      if (scores_every_frame_for(limit)) {
        search_exhaustive(q.store, q.descriptor, q.id, options_, q.metric, scratch_, out, &row);
        return outcome;
      }
      if (inserted_ == 0) return outcome;
      // The graph's `rescore` nearest keys, re-scored exactly; the best
      // `shortlist` of them by similarity go on (the key is coarse: a frame's
      // rank by key and by similarity differ).
      const auto k = static_cast<std::size_t>(std::min<std::int64_t>(
          inserted_, std::max<std::int64_t>(options_.index.shortlist, options_.top_n)));
      nearest_keys(q, k);
      const std::size_t from_graph = ids_.size();
      follow_previous(q, limit);
      // The newest frame in the graph, just past the temporal window: a query
      // that revisits nothing is often most like its own recent past, a
      // sequence no single frame of which stands out (street + 10^4
      // distractors: 10 of the 13 queries whose place differed from
      // exhaustive search's; docs/performance.md).
      ids_.push_back(limit - 1);
      rescore(q, from_graph, k);
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

  // search()'s steps.
  void insert_up_to(const Query& q, std::int64_t limit, Outcome& outcome) {
    const std::int64_t start = internal::now_ns();
    outcome.inserted = limit - inserted_;
    // Counted only once in the graph: a failed insertion is retried.
    for (; inserted_ < limit; ++inserted_) insert(q.store, q.metric, inserted_);
    outcome.insert_ms = internal::ms_since(start);
  }

  // The graph's nearest keys to the query's (at least k of them) into ids_.
  void nearest_keys(const Query& q, std::size_t k) {
    const auto fetch = std::max(k, static_cast<std::size_t>(std::min<std::int64_t>(
                                       inserted_, options_.index.rescore)));
    graph_->setEf(std::max<std::size_t>(fetch, static_cast<std::size_t>(options_.index.ef_search)));
    key_.resize(space_->get_data_size());
    make_key(q.descriptor, key_.data());
    auto found = graph_->searchKnn(key_.data(), fetch);
    ids_.clear();
    while (!found.empty()) {
      ids_.push_back(static_cast<std::int64_t>(found.top().second));
      found.pop();
    }
  }

  // The previous frame's places, one frame on along their diagonals: a
  // revisit whose sequence stands out stays in the shortlist even where
  // single frames look alike elsewhere. Its top_n are realigned as
  // candidates (into ids_); the places and frames it followed beyond them are
  // followed again, their sequence only (followed_; a query that revisits
  // nothing: its best place is the highest of the map's sequences of noise,
  // which builds up over many queries and no single frame of which stands out).
  void follow_previous(const Query& q, std::int64_t limit) {
    if (previous_frame_ != q.id - 1) return;
    for (std::size_t rank = 0; rank < previous_.size(); ++rank) {
      const std::int64_t j = previous_[rank] + 1;
      if (j < 1 || j >= limit) continue;
      if (rank < static_cast<std::size_t>(options_.top_n)) {
        ids_.push_back(j);
      } else if (followed_.size() < static_cast<std::size_t>(options_.index.follow)) {
        followed_.push_back(j);
      }
    }
  }

  // ids_ re-scored exactly, in one batch (the candidates' scores are the
  // metric's own), into scratch_: the best k of the graph's, then the others
  // not among them.
  void rescore(const Query& q, std::size_t from_graph, std::size_t k) {
    views_.clear();
    for (const std::int64_t j : ids_) views_.push_back(q.store.view(j));
    scores_.resize(views_.size());
    similarities(q.descriptor, views_.data(), views_.size(), q.metric, scores_.data());
    scratch_.clear();
    for (std::size_t i = 0; i < from_graph; ++i) scratch_.push_back({ids_[i], scores_[i]});
    if (scratch_.size() > k) {
      std::partial_sort(scratch_.begin(), scratch_.begin() + static_cast<std::ptrdiff_t>(k),
                        scratch_.end(), better);
      scratch_.resize(k);
    }
    for (std::size_t i = from_graph; i < ids_.size(); ++i) {
      const bool seen = std::any_of(scratch_.begin(), scratch_.end(),
                                    [&](const Candidate& c) { return c.frame == ids_[i]; });
      if (!seen) scratch_.push_back({ids_[i], scores_[i]});
    }
  }

  // search() keeps nothing of the query: the frames it inserts are stored
  // ones search() inserts at the next frame anyway, in the same order (the
  // same graph), and the followed frames are recomputed at every search.
  Outcome query(const Query& q, std::vector<Candidate>& out, std::vector<double>& row) override {
    return search(q, out, row);
  }

  void end(std::int64_t frame, const std::vector<Candidate>& candidates) override {
    previous_frame_ = frame;
    previous_.clear();
    for (const Candidate& c : candidates) previous_.push_back(c.frame);
    keep_ranked(frame, true);
  }

  // State, version 1: the places the frame ranked, its top_n candidates' and
  // those it followed beyond them (count, then int64 ids; a database written
  // before follow holds the top_n only), for the frame after it; an empty
  // record when they are not known (rows of older lsgd kept the last frame's
  // only: only the last one is read, but a forget may make an earlier frame
  // the last). The graph itself is saved whole (save_index), or rebuilt from
  // the stored frames at the first query.
  bool has_state() const override { return true; }
  void save_frame(std::int64_t frame, StateWriter& out) const override {
    if (frame < 0 || frame >= static_cast<std::int64_t>(ranked_at_.size())) return;
    const std::size_t at = ranked_at_[static_cast<std::size_t>(frame)];
    const std::int64_t n = ranked_[at];
    if (n < 0) return;  // not known
    out.put_i64(n);
    for (std::int64_t k = 1; k <= n; ++k) out.put_i64(ranked_[at + static_cast<std::size_t>(k)]);
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
  void restore_frame(std::int64_t frame, int width, int height, std::uint32_t version,
                     StateReader in) override {
    restore_renumbered(frame, width, height, version, in, FrameRenumbering::identity());
  }
  // Forgotten places are followed no more; the graph is built again from the
  // kept frames at the next query.
  bool forgets() const override { return true; }
  void restore_renumbered(std::int64_t frame, int, int, std::uint32_t, StateReader in,
                          const FrameRenumbering& renumbered) override {
    previous_frame_ = frame;
    previous_.clear();
    const bool known = in.present() && !in.empty();
    if (known) {
      const std::int64_t n = in.get_i64();
      for (std::int64_t k = 0; k < n; ++k) {
        const std::int64_t j = renumbered.after(in.get_i64());
        if (j >= 0) previous_.push_back(j);  // (-1, none: never followed)
      }
    }
    keep_ranked(frame, known);
  }

  // The graph, version 1 (StateWriter's little-endian integers, then
  // hnswlib's own layout of this machine, marked by a native 32-bit 1):
  //   "lsgdhnsw", version, native marker, cells, metric, M, ef_construction,
  //   frames, top level, entry point, the level generator's state (text),
  //   frames x (bottom-layer links, key, label), then per frame its level and
  //   links above the bottom layer.
  std::int64_t save_index(std::vector<std::uint8_t>& out) const override {
    out.clear();
    if (!graph_ || graph_->cur_element_count == 0) return 0;
    const auto& g = *graph_;
    std::size_t upper = 0;
    for (std::size_t i = 0; i < g.cur_element_count; ++i) {
      upper += static_cast<std::size_t>(g.element_levels_[i]) * g.size_links_per_element_;
    }
    StateWriter w;
    w.reserve(4096 + g.cur_element_count * (g.size_data_per_element_ + 8) + upper);
    w.put_bytes(reinterpret_cast<const std::uint8_t*>(kMagic), 8);
    w.put_i64(kSnapshotVersion);
    const std::uint32_t marker = 1;
    w.put_bytes(reinterpret_cast<const std::uint8_t*>(&marker), sizeof marker);
    w.put_i64(space_->cells());
    w.put_i64(static_cast<std::int64_t>(space_->metric()));
    w.put_i64(static_cast<std::int64_t>(g.M_));
    w.put_i64(static_cast<std::int64_t>(g.ef_construction_));
    w.put_i64(static_cast<std::int64_t>(g.cur_element_count));
    w.put_i64(g.maxlevel_);
    w.put_i64(static_cast<std::int64_t>(g.enterpoint_node_));
    std::ostringstream generator;
    generator << g.level_generator_;
    const std::string text = generator.str();
    w.put_i64(static_cast<std::int64_t>(text.size()));
    w.put_bytes(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
    w.put_bytes(reinterpret_cast<const std::uint8_t*>(g.data_level0_memory_),
                g.cur_element_count * g.size_data_per_element_);
    for (std::size_t i = 0; i < g.cur_element_count; ++i) {
      const int level = g.element_levels_[i];
      w.put_i64(level);
      if (level > 0) {
        w.put_bytes(reinterpret_cast<const std::uint8_t*>(g.linkLists_[i]),
                    static_cast<std::size_t>(level) * g.size_links_per_element_);
      }
    }
    out = w.take();
    return static_cast<std::int64_t>(g.cur_element_count);
  }

  void restore_index(const FrameStore& store, SimilarityMetric metric, const std::uint8_t* data,
                     std::size_t size) override {
    if (inserted_ > 0) internal::throw_invalid("search mode index: restore_index after the graph was built");
    try {
      load(store, metric, data, size);
    } catch (...) {
      graph_.reset();
      space_.reset();
      inserted_ = 0;
      throw;
    }
  }

 private:
  static constexpr char kMagic[9] = "lsgdhnsw";
  static constexpr std::int64_t kSnapshotVersion = 1;

  // A snapshot's header (load()).
  struct SnapshotHeader {
    std::int64_t cells = 0, metric = 0, m = 0, ef = 0, count = 0, top = 0, entry = 0;
    std::string generator;  // the level generator's state
  };

  template <typename... Parts>
  [[noreturn]] static void bad(const Parts&... parts) {
    internal::throw_invalid("index snapshot: ", parts...);
  }

  // A list of links: at most max_links, each to another frame of the n.
  static bool links_ok(const hnswlib::linklistsizeint* list, std::size_t max_links, std::size_t self,
                       std::size_t n) {
    const std::size_t k = *list;
    if (k > max_links) return false;
    const auto* ids = reinterpret_cast<const hnswlib::tableint*>(list + 1);
    for (std::size_t e = 0; e < k; ++e) {
      if (ids[e] >= n || ids[e] == self) return false;
    }
    return true;
  }

  void load(const FrameStore& store, SimilarityMetric expected_metric, const std::uint8_t* data,
            std::size_t size) {
    StateReader in(data, size, "index snapshot");
    const SnapshotHeader h = read_header(in, store, expected_metric);
    space_ = std::make_unique<KeySpace>(static_cast<int>(h.cells), static_cast<SimilarityMetric>(h.metric));
    const auto n = static_cast<std::size_t>(h.count);
    std::size_t capacity = 1024;
    while (capacity < n) capacity *= 2;
    graph_ = std::make_unique<hnswlib::HierarchicalNSW<float>>(
        space_.get(), capacity, static_cast<std::size_t>(h.m), static_cast<std::size_t>(h.ef), 100);
    advise_huge_pages(*graph_);
    auto& g = *graph_;
    std::istringstream generator(h.generator);
    generator >> g.level_generator_;
    if (!generator) bad("level generator state unreadable");
    const std::size_t block = g.size_data_per_element_;
    std::memcpy(g.data_level0_memory_, in.get_bytes(n * block), n * block);
    check_bottom_layer(store, n);
    g.cur_element_count = n;  // from here the destructor frees the upper layers made below
    for (std::size_t i = 0; i < n; ++i) g.element_levels_[i] = 0;
    read_upper_layers(in, n, h.top, h.entry);
    in.finish();
    check_upper_links(n);
    g.maxlevel_ = static_cast<int>(h.top);
    g.enterpoint_node_ = static_cast<hnswlib::tableint>(h.entry);
    inserted_ = h.count;
  }

  SnapshotHeader read_header(StateReader& in, const FrameStore& store, SimilarityMetric expected_metric) const {
    if (std::memcmp(in.get_bytes(8), kMagic, 8) != 0) bad("not an index snapshot (no lsgdhnsw mark)");
    const std::int64_t version = in.get_i64();
    if (version != kSnapshotVersion) bad("version ", version, " is not ", kSnapshotVersion);
    std::uint32_t marker = 0;
    std::memcpy(&marker, in.get_bytes(sizeof marker), sizeof marker);
    if (marker != 1) bad("written on a machine of the other byte order");
    SnapshotHeader h;
    h.cells = in.get_i64(), h.metric = in.get_i64(), h.m = in.get_i64(), h.ef = in.get_i64(),
    h.count = in.get_i64(), h.top = in.get_i64(), h.entry = in.get_i64();
    if (store.empty() || h.cells != store.view(0).cells) {
      bad(h.cells, " cells per frame, the stored frames have ", store.empty() ? 0 : store.view(0).cells);
    }
    if (h.metric != static_cast<std::int64_t>(expected_metric)) {
      bad("made for similarity metric ", h.metric, ", the detector's is ", to_string(expected_metric));
    }
    if (h.m != options_.index.m || h.ef != options_.index.ef_construction) {
      bad("made with m ", h.m, ", ef_construction ", h.ef, "; the options say ", options_.index.m, ", ",
          options_.index.ef_construction);
    }
    if (h.count < 1 || h.count > store.size()) bad(h.count, " frames, the store holds ", store.size());
    if (h.top < 0 || h.top > 64 || h.entry < 0 || h.entry >= h.count) {
      bad("top level ", h.top, ", entry point ", h.entry);
    }
    const std::int64_t text_size = in.get_i64();
    if (text_size < 0 || text_size > 4096) bad("level generator state of ", text_size, " bytes");
    const auto* text = reinterpret_cast<const char*>(in.get_bytes(static_cast<std::size_t>(text_size)));
    h.generator.assign(text, static_cast<std::size_t>(text_size));
    return h;
  }

  // Every link points to another frame of the graph, no list is longer than
  // the layer allows, labels are the frames in order, keys are the stored
  // frames' keys.
  void check_bottom_layer(const FrameStore& store, std::size_t n) {
    auto& g = *graph_;
    const std::size_t block = g.size_data_per_element_;
    key_.resize(space_->get_data_size());
    for (std::size_t i = 0; i < n; ++i) {
      char* element = g.data_level0_memory_ + i * block;
      hnswlib::labeltype label = 0;
      std::memcpy(&label, element + g.label_offset_, sizeof label);
      if (label != i) bad("frame ", i, " is labelled ", label);
      if (!links_ok(reinterpret_cast<const hnswlib::linklistsizeint*>(element), g.maxM0_, i, n)) {
        bad("frame ", i, ": bottom-layer links out of range");
      }
      make_key(store.view(static_cast<std::int64_t>(i)), key_.data());
      if (std::memcmp(element + g.offsetData_, key_.data(), key_.size()) != 0) {
        bad("frame ", i, ": its key is not the stored frame's (a snapshot of other frames)");
      }
    }
  }

  void read_upper_layers(StateReader& in, std::size_t n, std::int64_t top, std::int64_t entry) {
    auto& g = *graph_;
    for (std::size_t i = 0; i < n; ++i) {
      const std::int64_t level = in.get_i64();
      if (level < 0 || level > top) bad("frame ", i, ": level ", level, " above the top level ", top);
      if (static_cast<std::int64_t>(i) == entry && level != top) bad("the entry point is not on the top level");
      if (level == 0) continue;
      const std::size_t bytes = static_cast<std::size_t>(level) * g.size_links_per_element_;
      g.linkLists_[i] = static_cast<char*>(std::malloc(bytes));
      if (g.linkLists_[i] == nullptr) bad("out of memory at frame ", i);
      g.element_levels_[i] = static_cast<int>(level);
      std::memcpy(g.linkLists_[i], in.get_bytes(bytes), bytes);
      for (std::int64_t l = 0; l < level; ++l) {
        const char* list = g.linkLists_[i] + static_cast<std::size_t>(l) * g.size_links_per_element_;
        if (!links_ok(reinterpret_cast<const hnswlib::linklistsizeint*>(list), g.maxM_, i, n)) {
          bad("frame ", i, ": links on level ", l + 1, " out of range");
        }
      }
    }
  }

  // Upper-layer links only to frames on that layer.
  void check_upper_links(std::size_t n) {
    auto& g = *graph_;
    for (std::size_t i = 0; i < n; ++i) {
      for (int l = 1; l <= g.element_levels_[i]; ++l) {
        const auto* list = reinterpret_cast<const hnswlib::linklistsizeint*>(
            g.linkLists_[i] + static_cast<std::size_t>(l - 1) * g.size_links_per_element_);
        const auto* ids = reinterpret_cast<const hnswlib::tableint*>(list + 1);
        for (std::size_t e = 0; e < *list; ++e) {
          if (g.element_levels_[ids[e]] < l) bad("frame ", i, " links on level ", l, " to a lower frame");
        }
      }
      g.label_lookup_[i] = static_cast<hnswlib::tableint>(i);
    }
  }

  void insert(const FrameStore& store, SimilarityMetric metric, std::int64_t frame) {
    const DescriptorView d = store.view(frame);
    if (!space_) space_ = std::make_unique<KeySpace>(d.cells, metric);
    if (d.cells != space_->cells() || metric != space_->metric()) {
      internal::throw_invalid("search mode index: frame ", frame, " has ", d.cells, " cells and metric ",
                              to_string(metric), ", the graph's frames ", space_->cells(), " and ",
                              to_string(space_->metric()));
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
      advise_huge_pages(*graph_);
    }
    graph_->addPoint(key_.data(), static_cast<hnswlib::labeltype>(frame));
  }

  SearchOptions options_;
  std::unique_ptr<KeySpace> space_;  // made at the first insertion (it needs the cell count)
  std::unique_ptr<hnswlib::HierarchicalNSW<float>> graph_;
  std::int64_t inserted_ = 0;  // frames 0 .. inserted_-1 are in the graph
  std::int64_t previous_frame_ = -1;    // the last frame ended
  std::vector<std::int64_t> previous_;  // ... and its candidates' frames, best first
  // previous_ of every frame ended, for save_frame(): at ranked_at_[frame] in
  // ranked_, the count (-1: not known), then the frames (about 0.25 KB a
  // frame, against 10 to 41 KB of descriptor).
  std::vector<std::int64_t> ranked_;
  std::vector<std::size_t> ranked_at_;
  void keep_ranked(std::int64_t frame, bool known) {
    const auto f = static_cast<std::size_t>(frame);
    if (ranked_at_.size() > f) {  // ended again: its entry and later ones go
      ranked_.resize(ranked_at_[f]);
      ranked_at_.resize(f);
    }
    while (ranked_at_.size() < f) {  // frames not ended here: not known
      ranked_at_.push_back(ranked_.size());
      ranked_.push_back(-1);
    }
    ranked_at_.push_back(ranked_.size());
    ranked_.push_back(known ? static_cast<std::int64_t>(previous_.size()) : -1);
    if (known) ranked_.insert(ranked_.end(), previous_.begin(), previous_.end());
  }
  std::vector<std::int64_t> followed_;  // previous_ beyond top_n, one frame on
  std::vector<std::int64_t> ids_;
  std::vector<std::uint8_t> key_;
  std::vector<DescriptorView> views_;  // the shortlist's descriptors ...
  std::vector<double> scores_;         // ... and their exact scores
  std::vector<Candidate> scratch_;
};

}  // namespace

std::unique_ptr<CandidateSearch> make_index_search(const SearchOptions& options) {
  return std::make_unique<IndexSearch>(options);
}

std::int64_t index_bytes_per_frame(const DetectorOptions& options, int cells) {
  return 16 * std::int64_t{cells} + 8 * std::int64_t{options.search.index.m} + 64;
}

}  // namespace lsgd
