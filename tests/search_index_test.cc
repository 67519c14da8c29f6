// The index search mode (include/lsgd/search.h, src/search/index_key.h): its
// shortlist against exhaustive search, its key distance, and the places it
// follows from the previous frame.
#include "lsgd/search.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/error.h"
#include "lsgd/frame_store.h"
#include "lsgd/similarity.h"
#include "search/index_key.h"
#include "search_test_support.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::splitmix64;
using search_test_support::brute_force;
using search_test_support::expect_same;
using search_test_support::random_descriptor;
using search_test_support::run_index;
using search_test_support::store_of;

// With a shortlist as large as the map the index returns exactly what
// exhaustive search does (its shortlist is re-scored exactly); every
// candidate is outside the temporal window, scored by the metric itself.
TEST(SearchIndex, AShortlistAsLargeAsTheMapIsExhaustive) {
  std::vector<Descriptor> frames;
  for (int i = 0; i < 120; ++i) frames.push_back(random_descriptor(6, 700 + i % 37));  // revisits
  for (SimilarityMetric metric : {SimilarityMetric::kReference, SimilarityMetric::kNormalizedL1}) {
    SearchOptions o;
    o.mode = kIndexSearch;
    o.index.exhaustive_up_to = 0;  // the graph from the first query
    o.min_gap = 5;
    o.top_n = 4;
    o.index.shortlist = 200;
    o.index.ef_search = 400;
    const auto all = run_index(frames, o, metric);
    const FrameStore store = store_of(frames);
    for (std::size_t q = 0; q < frames.size(); ++q) {
      SCOPED_TRACE(testing::Message() << to_string(metric) << " query " << q);
      const std::int64_t limit = std::max<std::int64_t>(0, static_cast<std::int64_t>(q) - 5);
      ASSERT_EQ(all[q].size(), static_cast<std::size_t>(limit));  // the whole shortlist
      for (const Candidate& c : all[q]) {
        EXPECT_LT(c.frame, limit);
        EXPECT_EQ(c.score, similarity(frames[q].view(), store.view(c.frame), metric));
      }
      std::vector<Candidate> best(all[q].begin(), all[q].begin() + std::min<std::ptrdiff_t>(4, limit));
      expect_same(best, brute_force(store, frames[q].view(), static_cast<std::int64_t>(q), 5, 4, metric));
    }
  }
}

// The graph ranks by a coarse key; the shortlist is the most similar of its
// `rescore` nearest keys by the metric itself. With rescore covering the map
// it is exactly exhaustive search's best frames, and the newest frame past
// the temporal window (a query that revisits nothing is often most like its
// own recent past).
TEST(SearchIndex, TheShortlistIsTheMostSimilarOfTheRescoredFramesAndTheNewest) {
  std::vector<Descriptor> frames;
  for (int i = 0; i < 150; ++i) frames.push_back(random_descriptor(6, 900 + i % 41));  // revisits
  SearchOptions o;
  o.mode = kIndexSearch;
  o.index.exhaustive_up_to = 0;  // the graph from the first query
  o.min_gap = 5;
  o.top_n = 3;
  o.index.shortlist = 3;
  o.index.rescore = 400;
  const auto all = run_index(frames, o, SimilarityMetric::kReference);
  const FrameStore store = store_of(frames);
  for (std::size_t q = 0; q < frames.size(); ++q) {
    SCOPED_TRACE(testing::Message() << "query " << q);
    const std::int64_t limit = std::max<std::int64_t>(0, static_cast<std::int64_t>(q) - 5);
    std::vector<Candidate> expected =
        brute_force(store, frames[q].view(), static_cast<std::int64_t>(q), 5, 3, SimilarityMetric::kReference);
    const bool newest = std::any_of(expected.begin(), expected.end(),
                                    [&](const Candidate& c) { return c.frame == limit - 1; });
    if (limit > 0 && !newest) {
      expected.push_back({limit - 1, similarity(frames[q].view(), store.view(limit - 1), SimilarityMetric::kReference)});
    }
    std::sort(expected.begin(), expected.end(), better);
    expect_same(all[q], expected);
  }
}

// With a small shortlist the graph still finds the nearest frame for almost
// every query of a map with revisits, and reads far fewer than all frames.
TEST(SearchIndex, ASmallShortlistFindsTheNearestFrame) {
  std::vector<Descriptor> frames;
  for (int i = 0; i < 1500; ++i) frames.push_back(random_descriptor(6, 5000 + i % 500));
  SearchOptions o;
  o.mode = kIndexSearch;
  o.index.exhaustive_up_to = 0;  // the graph from the first query
  o.min_gap = 10;
  o.index.shortlist = 8;
  const auto all = run_index(frames, o, SimilarityMetric::kReference);
  const FrameStore store = store_of(frames);
  int queries = 0, same = 0;
  for (std::size_t q = 600; q < frames.size(); q += 7) {
    const auto exact = brute_force(store, frames[q].view(), static_cast<std::int64_t>(q), 10, 1,
                                   SimilarityMetric::kReference);
    ++queries;
    same += !all[q].empty() && all[q][0].frame == exact[0].frame ? 1 : 0;
  }
  EXPECT_GE(same, queries * 97 / 100) << same << " of " << queries;
}

// The graph's key distance (four cells at a time, the rest one by one) is the
// sum over cells of the cell's SAD, or of its square root for the reference
// metric, for every cell count; zero between a key and itself, symmetric.
TEST(IndexKey, DistanceIsTheSumOfTheCellsCosts) {
  std::uint64_t seed = 11;
  for (int cells = 1; cells <= 13; ++cells) {
    std::vector<std::uint8_t> a(static_cast<std::size_t>(cells) * internal::kKeyBins), b(a.size());
    for (auto& v : a) v = static_cast<std::uint8_t>(splitmix64(seed));
    for (auto& v : b) v = static_cast<std::uint8_t>(splitmix64(seed));
    for (const bool root : {false, true}) {
      SCOPED_TRACE(testing::Message() << cells << " cells, sqrt " << root);
      const internal::KeySpaceParam p{cells, root};
      double expected = 0;
      for (int c = 0; c < cells; ++c) {
        int sad = 0;
        for (int i = 0; i < internal::kKeyBins; ++i) {
          const std::size_t at = static_cast<std::size_t>(c) * internal::kKeyBins + static_cast<std::size_t>(i);
          sad += std::abs(int{a[at]} - int{b[at]});
        }
        expected += root ? std::sqrt(static_cast<double>(sad)) : sad;
      }
      const float got = internal::key_distance(a.data(), b.data(), &p);
      if (root) {
        EXPECT_NEAR(got, expected, 1e-6 * expected);
      } else {
        EXPECT_EQ(got, static_cast<float>(expected));  // integers: exact in float
      }
      EXPECT_EQ(internal::key_distance(b.data(), a.data(), &p), got);
      EXPECT_EQ(internal::key_distance(a.data(), a.data(), &p), 0.0f);
    }
  }
}

// Its state: the places the last frame's candidates pointed to, followed one
// frame on at the next query; refused when damaged.
TEST(SearchIndex, FollowsThePreviousFramesPlacesAndKeepsThemAsState) {
  std::vector<Descriptor> frames;
  for (int i = 0; i < 40; ++i) frames.push_back(random_descriptor(6, 100 + i));
  SearchOptions o;
  o.mode = kIndexSearch;
  o.index.exhaustive_up_to = 0;  // the graph from the first query
  o.min_gap = 2;
  o.index.shortlist = 1;
  o.top_n = 2;
  const std::unique_ptr<CandidateSearch> index = make_search(o);
  EXPECT_EQ(index->follow(), o.index.follow);
  FrameStore store;
  std::vector<Candidate> out;
  std::vector<double> row;
  for (int i = 0; i < 30; ++i) {
    index->search({store, frames[i].view(), i, SimilarityMetric::kReference}, out, row);
    index->end(i, {});
    store.add(frames[i]);
  }
  // The detector's places for frame 29: top_n = 2 candidates, then two it
  // follows and one that has not left the temporal window one frame on.
  index->end(29, {{11, 0.0}, {20, 0.0}, {5, 0.0}, {8, 0.0}, {27, 0.0}});
  index->search({store, frames[30].view(), 30, SimilarityMetric::kReference}, out, row);
  std::vector<std::int64_t> ids;
  for (const Candidate& c : out) ids.push_back(c.frame);
  EXPECT_NE(std::find(ids.begin(), ids.end(), 12), ids.end());  // 11 + 1
  EXPECT_NE(std::find(ids.begin(), ids.end(), 21), ids.end());  // 20 + 1
  EXPECT_NE(std::find(ids.begin(), ids.end(), 27), ids.end());  // the newest past the window
  EXPECT_EQ(index->followed(), (std::vector<std::int64_t>{6, 9}));  // 28 is inside the window
  // The followed frames are not candidates: the same as without them.
  std::vector<Candidate> top_only;
  index->end(29, {{11, 0.0}, {20, 0.0}});
  index->search({store, frames[30].view(), 30, SimilarityMetric::kReference}, top_only, row);
  EXPECT_TRUE(index->followed().empty());
  ASSERT_EQ(top_only.size(), out.size());
  for (std::size_t k = 0; k < out.size(); ++k) EXPECT_EQ(top_only[k].frame, out[k].frame);
  index->end(29, {{11, 0.0}, {20, 0.0}, {5, 0.0}, {8, 0.0}, {27, 0.0}});
  StateWriter w;
  index->save_frame(29, w);
  // Every frame keeps its own (a forget may make any of them the last):
  // frame 28 ranked none.
  StateWriter earlier;
  index->save_frame(28, earlier);
  EXPECT_EQ(earlier.bytes(), std::vector<std::uint8_t>(8, 0));
  // A frame restored without them (a row of an older lsgd) has none known.
  const std::unique_ptr<CandidateSearch> older = make_search(o);
  older->restore_frame(0, 1, 1, 1, StateReader(nullptr, 0, "x"));
  StateWriter unknown;
  older->save_frame(0, unknown);
  EXPECT_TRUE(unknown.empty());
  const std::unique_ptr<CandidateSearch> restored = make_search(o);
  EXPECT_NO_THROW(restored->check_frame(29, 1, 1, 1, StateReader(w.bytes().data(), w.bytes().size(), "x")));
  // Restored, it follows the same places.
  restored->restore_frame(29, 1, 1, 1, StateReader(w.bytes().data(), w.bytes().size(), "x"));
  restored->search({store, frames[30].view(), 30, SimilarityMetric::kReference}, out, row);
  EXPECT_EQ(restored->followed(), (std::vector<std::int64_t>{6, 9}));
  // With follow 1, the first of them only; without follow, none.
  for (const int follow : {1, 0}) {
    SearchOptions f = o;
    f.index.follow = follow;
    const std::unique_ptr<CandidateSearch> s = make_search(f);
    EXPECT_EQ(s->follow(), follow);
    s->restore_frame(29, 1, 1, 1, StateReader(w.bytes().data(), w.bytes().size(), "x"));
    s->search({store, frames[30].view(), 30, SimilarityMetric::kReference}, out, row);
    EXPECT_EQ(s->followed(), follow == 1 ? std::vector<std::int64_t>{6} : std::vector<std::int64_t>{});
  }
  StateWriter bad;
  bad.put_i64(1);
  bad.put_i64(29);  // not an earlier frame
  EXPECT_THROW(restored->check_frame(29, 1, 1, 1, StateReader(bad.bytes().data(), bad.bytes().size(), "x")),
               InvalidArgument);
  StateWriter overflow;
  overflow.put_i64(1000000);
  EXPECT_THROW(restored->check_frame(29, 1, 1, 1,
                                     StateReader(overflow.bytes().data(), overflow.bytes().size(), "x")),
               InvalidArgument);
}

}  // namespace
}  // namespace lsgd
