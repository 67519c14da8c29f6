// A search mode registered from outside the library runs in the online
// detector (include/lsgd/detector.h) through CandidateSearch alone, and its
// own memory model adds to the estimated map bytes.
#include "lsgd/detector.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "lsgd/error.h"
#include "lsgd/search/exhaustive.h"
#include "detector_test_support.h"
#include "test_util.h"

namespace lsgd {
namespace {

using detector_test_support::expect_same_result;
using detector_test_support::random_frame;
using detector_test_support::small_options;

// The extension point: a mode registered from outside the library runs in
// the detector through CandidateSearch alone.
// "test-copy": exhaustive search under another name (it forwards to the
// built-in one); results must be identical.
class CopyOfExhaustive final : public CandidateSearch {
 public:
  explicit CopyOfExhaustive(const SearchOptions& o) : inner_(make_exhaustive_search(o)) {}
  const char* name() const override { return "test-copy"; }
  bool scores_every_frame() const override { return inner_->scores_every_frame(); }
  Outcome search(const Query& q, std::vector<Candidate>& out, std::vector<double>& row) override {
    return inner_->search(q, out, row);
  }

 private:
  std::unique_ptr<CandidateSearch> inner_;
};

// "test-blocks": a shortlist with groups: frame i is in group i / 4, and the
// candidates are the frames of the newest group outside the window.
class Blocks final : public CandidateSearch {
 public:
  explicit Blocks(const SearchOptions& o) : options_(o) {}
  const char* name() const override { return "test-blocks"; }
  bool scores_every_frame() const override { return false; }
  Outcome search(const Query& q, std::vector<Candidate>& out, std::vector<double>&) override {
    out.clear();
    const std::int64_t limit = q.id - options_.min_gap;
    for (std::int64_t j = std::max<std::int64_t>(0, (limit - 1) / 4 * 4); j < limit; ++j) {
      out.push_back({j, similarity(q.descriptor, q.store.view(j), q.metric)});
    }
    std::sort(out.begin(), out.end(), better);
    if (out.size() > static_cast<std::size_t>(options_.top_n)) out.resize(options_.top_n);
    const std::int64_t group = q.id / 4;
    if (group == static_cast<std::int64_t>(groups_.size())) groups_.emplace_back();
    groups_.back().push_back(q.id);
    return {group, q.id % 4 == 0};
  }
  bool has_groups() const override { return true; }
  std::int64_t groups() const override { return static_cast<std::int64_t>(groups_.size()); }
  const std::vector<std::int64_t>& members(std::int64_t g) const override {
    return groups_.at(static_cast<std::size_t>(g));
  }

 private:
  SearchOptions options_;
  std::vector<std::vector<std::int64_t>> groups_;
};

void register_test_modes() {
  static const bool once = [] {
    register_search_mode({"test-copy", "exhaustive, renamed",
                          [](const SearchOptions& o) -> std::unique_ptr<CandidateSearch> {
                            return std::make_unique<CopyOfExhaustive>(o);
                          }});
    register_search_mode({"test-blocks", "groups of 4 frames",
                          [](const SearchOptions& o) -> std::unique_ptr<CandidateSearch> {
                            return std::make_unique<Blocks>(o);
                          },
                          // Its memory model: a group id per frame, and 2 bytes a cell.
                          [](const DetectorOptions&, int cells) -> std::int64_t {
                            return 8 + 2 * std::int64_t{cells};
                          }});
    return true;
  }();
  (void)once;
}

TEST(SearchModes, ARegisteredModeRunsInTheDetectorThroughTheInterfaceAlone) {
  register_test_modes();
  EXPECT_NE(search_mode_names().find("test-copy"), std::string::npos);
  const auto make = [](const SearchOptions& o) -> std::unique_ptr<CandidateSearch> {
    return std::make_unique<CopyOfExhaustive>(o);
  };
  EXPECT_THROW(register_search_mode({"test-copy", "again", make}), InvalidArgument);
  EXPECT_THROW(register_search_mode({"", "no name", make}), InvalidArgument);
  EXPECT_THROW(register_search_mode({"test-none", "no make", nullptr}), InvalidArgument);

  DetectorOptions copy = small_options(kExhaustiveSearch, 2, 4);
  copy.verification.stages = {kTemporalStage};  // sequence evidence over the search's row
  DetectorOptions original = copy;
  copy.search.mode = "test-copy";
  Detector a(copy), b(original);
  for (int i = 0; i < 60; ++i) {
    const cv::Mat f = random_frame(700 + i % 23);  // revisits
    const Result ra = a.process(f);
    const Result rb = b.process(f);
    expect_same_result(ra, rb);
  }

  DetectorOptions blocks = small_options("test-blocks", 2, 4);
  blocks.verification.stages = {kTemporalStage};  // realigned candidates, sampled statistics
  Detector c(blocks);
  for (int i = 0; i < 60; ++i) {
    const Result r = c.process(random_frame(700 + i % 23));
    EXPECT_EQ(r.node, i / 4);
    EXPECT_EQ(r.node_created, i % 4 == 0);
    for (const Candidate& k : r.candidates) EXPECT_LT(k.frame, i - 2);
  }
  EXPECT_EQ(c.nodes(), 15);
  EXPECT_EQ(c.search().members(3), (std::vector<std::int64_t>{12, 13, 14, 15}));
}

// The memory a map takes: each frame's descriptor and its mode's own model,
// a registered mode's included.
TEST(SearchModes, EstimatedMapBytesAddTheModesOwnMemoryModel) {
  register_test_modes();
  DetectorOptions o;
  // Each frame's place signature too (verification.temporal.place_cut).
  const std::int64_t exact =
      static_cast<std::int64_t>(Descriptor::bytes_per_frame(HistogramStorage::kExact, 80)) + kPlaceBytesPerFrame;
  o.search.mode = kExhaustiveSearch;
  EXPECT_EQ(estimated_map_bytes(o, 1000, 80), 1000 * (exact + 8 * 48));
  o.search.mode = kNodesSearch;
  EXPECT_EQ(estimated_map_bytes(o, 1000, 80), 1000 * exact);
  o.search.mode = kIndexSearch;
  EXPECT_EQ(estimated_map_bytes(o, 1000, 80), 1000 * (exact + 16 * 80 + 8 * o.search.index.m + 64));
  o.search.mode = "test-blocks";
  EXPECT_EQ(estimated_map_bytes(o, 1000, 80), 1000 * (exact + 8 + 160));
  o.search.mode = "test-copy";  // no model: the descriptors alone
  EXPECT_EQ(estimated_map_bytes(o, 10, 80), 10 * exact);
  o.verification.temporal_options.place_cut = 0;  // no places: no signatures
  EXPECT_EQ(estimated_map_bytes(o, 10, 80), 10 * (exact - kPlaceBytesPerFrame));
  o.search.mode = "no-such-mode";
  EXPECT_THROW(estimated_map_bytes(o, 10, 80), InvalidArgument);
}

}  // namespace
}  // namespace lsgd
