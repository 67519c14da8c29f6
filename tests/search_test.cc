// Tests of candidate search (include/lsgd/search.h): candidate ordering, the
// exhaustive search against a brute force, and dynamic nodes (Algorithm 1 with
// the reference implementation's relative thresholds) against hand-computed
// node assignments and an independent re-implementation.
#include "lsgd/search.h"
#include "lsgd/search/dynamic_nodes.h"
#include "lsgd/search/exhaustive.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/error.h"
#include "lsgd/frame_store.h"
#include "lsgd/similarity.h"
#include "search/index_key.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::message_of;
using test::splitmix64;

// A 1-cell descriptor on a line: `mass - t` pixels in bin 0 and `t` in bin 1.
// With the L1 metric, sim(t_a, t_b) = 1 - 2 |t_a - t_b| / (2 mass) = 1 - |t_a - t_b| / mass.
Descriptor line_descriptor(int t, int mass = 100) {
  Descriptor d;
  d.grid = {1, 1};
  d.hist.assign(kBins, 0);
  d.hist[0] = static_cast<Bin>(mass - t);
  d.hist[1] = static_cast<Bin>(t);
  d.pixels = {static_cast<Count>(mass)};
  return d;
}

Descriptor random_descriptor(int cells, std::uint64_t seed) {
  std::uint64_t s = seed;
  Descriptor d;
  d.grid = {2, cells / 2};
  d.hist.assign(static_cast<std::size_t>(d.grid.cells()) * kBins, 0);
  d.pixels.assign(d.grid.cells(), 0);
  for (int k = 0; k < d.grid.cells(); ++k) {
    const int n = 100;
    const int centre = static_cast<int>(splitmix64(s) % 200);
    for (int i = 0; i < n; ++i) {
      ++d.hist[static_cast<std::size_t>(k) * kBins + centre + splitmix64(s) % 50];
    }
    d.pixels[k] = n;
  }
  return d;
}

FrameStore store_of(const std::vector<Descriptor>& frames) {
  FrameStore store;
  for (const Descriptor& d : frames) store.add(d);
  return store;
}

// ---- better()

TEST(Better, ScoreDescendingThenLowerFrame) {
  EXPECT_TRUE(better({5, 0.9}, {1, 0.8}));
  EXPECT_FALSE(better({1, 0.8}, {5, 0.9}));
  EXPECT_TRUE(better({1, 0.5}, {2, 0.5}));
  EXPECT_FALSE(better({2, 0.5}, {1, 0.5}));
  EXPECT_FALSE(better({3, 0.5}, {3, 0.5}));  // strict weak ordering: irreflexive
  std::vector<Candidate> v = {{4, 0.2}, {1, 0.9}, {3, 0.9}, {0, 0.2}, {2, 1.0}};
  std::sort(v.begin(), v.end(), better);
  const std::vector<std::int64_t> frames = {2, 1, 3, 0, 4};
  for (std::size_t i = 0; i < v.size(); ++i) EXPECT_EQ(v[i].frame, frames[i]) << i;
}

// ---- exhaustive search

std::vector<Candidate> brute_force(const FrameStore& store, const DescriptorView& query,
                                   std::int64_t query_id, std::int64_t min_gap, int top_n,
                                   SimilarityMetric metric) {
  std::vector<Candidate> all;
  for (std::int64_t j = 0; j < store.size(); ++j) {
    if (j < query_id - min_gap) all.push_back({j, similarity(query, store.view(j), metric)});
  }
  std::sort(all.begin(), all.end(), [](const Candidate& a, const Candidate& b) {
    return a.score > b.score || (a.score == b.score && a.frame < b.frame);
  });
  if (all.size() > static_cast<std::size_t>(top_n)) all.resize(top_n);
  return all;
}

void expect_same(const std::vector<Candidate>& got, const std::vector<Candidate>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].frame, want[i].frame) << "rank " << i;
    EXPECT_EQ(got[i].score, want[i].score) << "rank " << i;
  }
}

TEST(SearchExhaustive, EqualsBruteForce) {
  std::vector<Descriptor> frames;
  for (int i = 0; i < 40; ++i) frames.push_back(random_descriptor(6, 500 + i));
  const FrameStore store = store_of(frames);
  std::vector<Candidate> scratch, out;
  for (SimilarityMetric metric :
       {SimilarityMetric::kReference, SimilarityMetric::kL1, SimilarityMetric::kNormalizedL1}) {
    for (std::int64_t gap : {0, 1, 5, 39, 40, 1000}) {
      for (int top_n : {1, 3, 10, 1000}) {
        SearchOptions o;
        o.min_gap = gap;
        o.top_n = top_n;
        for (std::int64_t q = 0; q <= 40; q += 3) {
          SCOPED_TRACE(testing::Message() << to_string(metric) << " gap " << gap << " top " << top_n
                                          << " q " << q);
          const Descriptor query = random_descriptor(6, 9000 + q);
          search_exhaustive(store, query.view(), q, o, metric, scratch, out);
          EXPECT_LE(out.size(), static_cast<std::size_t>(top_n));
          for (const Candidate& c : out) EXPECT_LT(c.frame, q - gap);
          for (std::size_t i = 1; i < out.size(); ++i) EXPECT_TRUE(better(out[i - 1], out[i]));
          expect_same(out, brute_force(store, query.view(), q, gap, top_n, metric));
        }
      }
    }
  }
}

TEST(SearchExhaustive, GapAtLeastQueryReturnsNothing) {
  std::vector<Descriptor> frames;
  for (int i = 0; i < 10; ++i) frames.push_back(random_descriptor(4, i));
  const FrameStore store = store_of(frames);
  std::vector<Candidate> scratch, out = {{99, 0.5}};  // stale content must be cleared
  SearchOptions o;
  for (std::int64_t q : {0, 1, 5, 10}) {
    for (std::int64_t gap : {q, q + 1, q + 100}) {
      o.min_gap = gap;
      search_exhaustive(store, frames[0].view(), q, o, SimilarityMetric::kReference, scratch, out);
      EXPECT_TRUE(out.empty()) << "q " << q << " gap " << gap;
    }
  }
  // gap = q - 1 leaves exactly frame 0.
  o.min_gap = 9;
  search_exhaustive(store, frames[3].view(), 10, o, SimilarityMetric::kReference, scratch, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].frame, 0);
}

TEST(SearchExhaustive, EmptyStoreReturnsNothing) {
  const FrameStore store;
  std::vector<Candidate> scratch, out = {{1, 1.0}};
  SearchOptions o;
  o.min_gap = 0;
  const Descriptor q = random_descriptor(4, 1);
  search_exhaustive(store, q.view(), 0, o, SimilarityMetric::kReference, scratch, out);
  EXPECT_TRUE(out.empty());
}

TEST(SearchExhaustive, FindsTheIdenticalFrameFirstAndTiesByOlderFrame) {
  std::vector<Descriptor> frames;
  for (int i = 0; i < 20; ++i) frames.push_back(line_descriptor(i * 4));
  frames[12] = frames[5];  // duplicate of frame 5
  const FrameStore store = store_of(frames);
  std::vector<Candidate> scratch, out;
  SearchOptions o;
  o.min_gap = 0;
  o.top_n = 3;
  search_exhaustive(store, frames[5].view(), 20, o, SimilarityMetric::kL1, scratch, out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].frame, 5);
  EXPECT_EQ(out[0].score, 1.0);
  EXPECT_EQ(out[1].frame, 12);
  EXPECT_EQ(out[1].score, 1.0);
  // Frames 4 and 6 are equally similar (0.96): the older one first.
  EXPECT_EQ(out[2].frame, 4);
  EXPECT_DOUBLE_EQ(out[2].score, 0.96);
}

// ---- options

TEST(SearchOptions, DefaultsAreValid) {
  SearchOptions o;
  EXPECT_NO_THROW(o.check());
  EXPECT_NO_THROW(o.nodes.check());
}

TEST(SearchOptions, EachFieldOutOfRangeNamesTheField) {
  struct Case {
    const char* field;
    void (*mutate)(SearchOptions&);
  };
  const Case cases[] = {
      {"min_gap", [](SearchOptions& o) { o.min_gap = -1; }},
      {"min_gap", [](SearchOptions& o) { o.min_gap = 1000000001; }},
      {"top_n", [](SearchOptions& o) { o.top_n = 0; }},
      {"top_n", [](SearchOptions& o) { o.top_n = -3; }},
      {"top_n", [](SearchOptions& o) { o.top_n = 1001; }},
      {"mode", [](SearchOptions& o) { o.mode = "foo"; }},
      {"mode", [](SearchOptions& o) { o.mode = ""; }},
      {"threshold_0", [](SearchOptions& o) { o.nodes.threshold_0 = 0.0; }},
      {"threshold_0", [](SearchOptions& o) { o.nodes.threshold_0 = -0.5; }},
      {"threshold_0", [](SearchOptions& o) { o.nodes.threshold_0 = 10.5; }},
      {"threshold_0",
       [](SearchOptions& o) { o.nodes.threshold_0 = std::numeric_limits<double>::quiet_NaN(); }},
      {"alpha", [](SearchOptions& o) { o.nodes.alpha = -0.1; }},
      {"alpha", [](SearchOptions& o) { o.nodes.alpha = 10.1; }},
      {"alpha", [](SearchOptions& o) { o.nodes.alpha = std::numeric_limits<double>::quiet_NaN(); }},
      {"beta", [](SearchOptions& o) { o.nodes.beta = -1.0; }},
      {"beta", [](SearchOptions& o) { o.nodes.beta = 11.0; }},
      {"beta", [](SearchOptions& o) { o.nodes.beta = std::numeric_limits<double>::infinity(); }},
  };
  for (const Case& c : cases) {
    SearchOptions o;
    c.mutate(o);
    SCOPED_TRACE(c.field);
    EXPECT_THROW(o.check(), InvalidArgument);
    const std::string msg = message_of<InvalidArgument>([&] { o.check(); });
    EXPECT_NE(msg.find(c.field), std::string::npos) << msg;
  }
}

TEST(SearchOptions, NodeOptionsCheckedOnTheirOwn) {
  DynamicNodeOptions n;
  EXPECT_NO_THROW(n.check());
  n.alpha = 0;
  n.beta = 0;
  n.threshold_0 = 10;
  EXPECT_NO_THROW(n.check());
  n.alpha = 10;
  n.beta = 10;
  n.threshold_0 = 1e-9;
  EXPECT_NO_THROW(n.check());
  n.beta = 10.0001;
  EXPECT_THROW(n.check(), InvalidArgument);
}

TEST(SearchOptions, BoundaryValuesAccepted) {
  SearchOptions o;
  o.min_gap = 0;
  o.top_n = 1;
  EXPECT_NO_THROW(o.check());
  o.min_gap = 1000000000;
  o.top_n = 1000;
  o.mode = kNodesSearch;
  EXPECT_NO_THROW(o.check());
}

TEST(SearchModes, TheBuiltInModesAreRegisteredAndMadeByName) {
  EXPECT_EQ(search_mode_names(), "exhaustive, nodes, index");
  for (const SearchMode& m : search_modes()) {
    SearchOptions o;
    o.mode = m.name;
    const std::unique_ptr<CandidateSearch> search = make_search(o);
    EXPECT_STREQ(search->name(), m.name);
    EXPECT_EQ(search->groups(), 0);
  }
  SearchOptions o;
  EXPECT_TRUE(make_search(o)->scores_every_frame());
  EXPECT_FALSE(make_search(o)->has_groups());
  EXPECT_THROW(make_search(o)->members(0), InvalidArgument);
  EXPECT_FALSE(make_search(o)->has_state());
  EXPECT_EQ(make_search(o)->group_of(0), -1);
  o.mode = kNodesSearch;
  EXPECT_FALSE(make_search(o)->scores_every_frame());
  EXPECT_TRUE(make_search(o)->has_groups());
  EXPECT_TRUE(make_search(o)->has_state());
  o.mode = kIndexSearch;
  EXPECT_FALSE(make_search(o)->scores_every_frame());
  EXPECT_FALSE(make_search(o)->has_groups());
  EXPECT_TRUE(make_search(o)->has_state());
  for (const char* bad : {"foo", "", "Nodes", "dynamic", "exhaustive "}) {
    const std::string message = message_of<InvalidArgument>([&] { check_search_mode(bad); });
    EXPECT_NE(message.find(std::string("'") + bad + "'"), std::string::npos) << message;
    EXPECT_NE(message.find("exhaustive, nodes, index"), std::string::npos) << message;
    o.mode = bad;
    EXPECT_THROW(make_search(o), InvalidArgument);
  }
}

// ---- index

// Runs the index over frames stored one by one, as the detector does, and
// returns each query's candidates.
std::vector<std::vector<Candidate>> run_index(const std::vector<Descriptor>& frames,
                                              const SearchOptions& o, SimilarityMetric metric) {
  const std::unique_ptr<CandidateSearch> index = make_search(o);
  FrameStore store;
  std::vector<std::vector<Candidate>> all;
  std::vector<Candidate> out;
  std::vector<double> row;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    index->search({store, frames[i].view(), static_cast<std::int64_t>(i), metric}, out, row);
    all.push_back(out);
    index->end(static_cast<std::int64_t>(i), {});
    store.add(frames[i]);
  }
  return all;
}

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

// ---- dynamic nodes

struct Step {
  DynamicNodes::Outcome outcome;
  std::vector<Candidate> candidates;
};

// Feeds `frames` one by one: assign, then store.
std::vector<Step> run_nodes(DynamicNodes& nodes, const std::vector<Descriptor>& frames,
                            const SearchOptions& o, SimilarityMetric metric) {
  FrameStore store;
  std::vector<Candidate> scratch;
  std::vector<Step> steps;
  for (std::size_t q = 0; q < frames.size(); ++q) {
    Step step;
    step.outcome = nodes.assign(store, frames[q].view(), static_cast<std::int64_t>(q), o, metric,
                                scratch, step.candidates);
    store.add(frames[q]);
    steps.push_back(step);
  }
  return steps;
}

// Feeds `frames` to dynamic nodes with zero thresholds (alpha = beta = 0) and
// the reference metric, whose scores are positive: each frame joins the first
// node whose first frame lies outside the window `min_gap`.
std::vector<Step> run_zero_thresholds(DynamicNodes& nodes, const std::vector<Descriptor>& frames,
                                      std::int64_t min_gap, int top_n) {
  SearchOptions o;
  o.mode = kNodesSearch;
  o.min_gap = min_gap;
  o.top_n = top_n;
  o.nodes.alpha = 0;
  o.nodes.beta = 0;
  return run_nodes(nodes, frames, o, SimilarityMetric::kReference);
}

TEST(DynamicNodes, FirstFrameCreatesNodeZero) {
  DynamicNodes nodes;
  EXPECT_EQ(nodes.size(), 0);
  FrameStore store;
  std::vector<Candidate> scratch, out = {{3, 0.3}};
  SearchOptions o;
  const Descriptor d = random_descriptor(4, 1);
  const auto outcome = nodes.assign(store, d.view(), 0, o, SimilarityMetric::kReference, scratch, out);
  EXPECT_EQ(outcome.node, 0);
  EXPECT_TRUE(outcome.created);
  EXPECT_EQ(outcome.similarities, 0);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(nodes.size(), 1);
  EXPECT_EQ(nodes.members(0), (std::vector<std::int64_t>{0}));
  EXPECT_THROW(nodes.members(1), InvalidArgument);  // not std::out_of_range
}

TEST(DynamicNodes, QueryMustBeTheNextFrame) {
  DynamicNodes nodes;
  FrameStore store;
  std::vector<Candidate> scratch, out;
  SearchOptions o;
  const Descriptor d = random_descriptor(4, 1);
  EXPECT_THROW(nodes.assign(store, d.view(), 1, o, SimilarityMetric::kReference, scratch, out),
               InvalidArgument);
  store.add(d);
  EXPECT_THROW(nodes.assign(store, d.view(), 0, o, SimilarityMetric::kReference, scratch, out),
               InvalidArgument);
  EXPECT_THROW(nodes.assign(store, d.view(), 2, o, SimilarityMetric::kReference, scratch, out),
               InvalidArgument);
  EXPECT_EQ(nodes.size(), 0);  // rejected calls change nothing
}

TEST(DynamicNodes, ZeroThresholdsPutEveryFrameInNodeZero) {
  std::vector<Descriptor> frames;
  for (int i = 0; i < 25; ++i) frames.push_back(random_descriptor(6, 700 + i));
  DynamicNodes nodes;
  const auto steps = run_zero_thresholds(nodes, frames, 0, 1000);
  EXPECT_EQ(nodes.size(), 1);
  EXPECT_TRUE(steps[0].outcome.created);
  const FrameStore store = store_of(frames);
  for (std::size_t q = 1; q < frames.size(); ++q) {
    SCOPED_TRACE(q);
    EXPECT_EQ(steps[q].outcome.node, 0);
    EXPECT_FALSE(steps[q].outcome.created);
    // Candidates: every earlier frame, best first (= exhaustive search).
    EXPECT_EQ(steps[q].candidates.size(), q);
    FrameStore prefix;
    for (std::size_t j = 0; j < q; ++j) prefix.add(frames[j]);
    expect_same(steps[q].candidates,
                brute_force(prefix, frames[q].view(), static_cast<std::int64_t>(q), 0, 1000,
                            SimilarityMetric::kReference));
    // prev + first + the other members.
    EXPECT_EQ(steps[q].outcome.similarities, static_cast<std::int64_t>(1 + q));
  }
  std::vector<std::int64_t> all(frames.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::int64_t>(i);
  EXPECT_EQ(nodes.members(0), all);
}

TEST(DynamicNodes, NodeInsideWindowIsNeverExamined) {
  std::vector<Descriptor> frames;
  for (int i = 0; i < 12; ++i) frames.push_back(random_descriptor(6, 800 + i));
  DynamicNodes nodes;
  const auto steps = run_zero_thresholds(nodes, frames, 3, 1000);
  // Frames 0..3: node 0 (first frame 0) lies inside the window (q - 0 <= 3),
  // so each frame creates its own node.
  for (int q = 0; q <= 3; ++q) {
    EXPECT_TRUE(steps[q].outcome.created) << q;
    EXPECT_EQ(steps[q].outcome.node, q) << q;
    EXPECT_TRUE(steps[q].candidates.empty()) << q;
    EXPECT_EQ(steps[q].outcome.similarities, q > 0 ? 1 : 0) << q;  // only sim(q, q-1)
  }
  // From frame 4 on every frame joins node 0; candidates are only its
  // members outside the window (j < q - 3).
  for (int q = 4; q < 12; ++q) {
    SCOPED_TRACE(q);
    EXPECT_FALSE(steps[q].outcome.created);
    EXPECT_EQ(steps[q].outcome.node, 0);
    std::vector<std::int64_t> want = {0};
    for (int j = 4; j < q - 3; ++j) want.push_back(j);
    std::vector<std::int64_t> got;
    for (const Candidate& c : steps[q].candidates) {
      EXPECT_LT(c.frame, q - 3);
      got.push_back(c.frame);
    }
    for (std::size_t i = 1; i < steps[q].candidates.size(); ++i) {
      EXPECT_TRUE(better(steps[q].candidates[i - 1], steps[q].candidates[i]));
    }
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, want);
    // prev + all members of node 0 ({0, 4, ..., q-1}).
    EXPECT_EQ(steps[q].outcome.similarities, 1 + 1 + (q - 4));
  }
  EXPECT_EQ(nodes.size(), 4);
  EXPECT_EQ(nodes.members(0), (std::vector<std::int64_t>{0, 4, 5, 6, 7, 8, 9, 10, 11}));
  for (int i = 1; i <= 3; ++i) EXPECT_EQ(nodes.members(i), (std::vector<std::int64_t>{i}));
}

TEST(DynamicNodes, TopNLimitsCandidates) {
  std::vector<Descriptor> frames;
  for (int i = 0; i < 15; ++i) frames.push_back(random_descriptor(6, 900 + i));
  DynamicNodes nodes;
  const auto steps = run_zero_thresholds(nodes, frames, 0, 4);
  for (std::size_t q = 1; q < frames.size(); ++q) {
    FrameStore prefix;
    for (std::size_t j = 0; j < q; ++j) prefix.add(frames[j]);
    expect_same(steps[q].candidates,
                brute_force(prefix, frames[q].view(), static_cast<std::int64_t>(q), 0, 4,
                            SimilarityMetric::kReference));
  }
}

// The run the two hand-computed tests below follow: frames are the points
// t = 50, 60, 70, 72, 55, 42, 90, 44, 46, 88 on a line (line_descriptor, L1
// metric), threshold_0 = 1, alpha = 0.9, beta = 0.95, top_n = 10 and the given
// temporal window `min_gap`.
std::vector<Step> run_hand_computed(DynamicNodes& nodes, std::int64_t min_gap) {
  const int ts[] = {50, 60, 70, 72, 55, 42, 90, 44, 46, 88};
  std::vector<Descriptor> frames;
  for (int t : ts) frames.push_back(line_descriptor(t));
  SearchOptions o;
  o.mode = kNodesSearch;
  o.min_gap = min_gap;
  o.top_n = 10;
  o.nodes.threshold_0 = 1.0;
  o.nodes.alpha = 0.9;
  o.nodes.beta = 0.95;
  return run_nodes(nodes, frames, o, SimilarityMetric::kL1);
}

// Checks every step of a hand-computed run against the expected node, node
// creation, similarity count and candidates (frame and score, rank by rank);
// stops at the first step whose candidate count is wrong.
template <std::size_t N>
void expect_steps(const std::vector<Step>& steps, const std::int64_t (&want_node)[N],
                  const bool (&want_created)[N], const std::int64_t (&want_sims)[N],
                  const std::vector<std::vector<Candidate>>& want_candidates) {
  for (std::size_t q = 0; q < steps.size(); ++q) {
    SCOPED_TRACE(testing::Message() << "frame " << q);
    EXPECT_EQ(steps[q].outcome.node, want_node[q]);
    EXPECT_EQ(steps[q].outcome.created, want_created[q]);
    EXPECT_EQ(steps[q].outcome.similarities, want_sims[q]);
    ASSERT_EQ(steps[q].candidates.size(), want_candidates[q].size());
    for (std::size_t i = 0; i < want_candidates[q].size(); ++i) {
      EXPECT_EQ(steps[q].candidates[i].frame, want_candidates[q][i].frame) << "rank " << i;
      EXPECT_NEAR(steps[q].candidates[i].score, want_candidates[q][i].score, 1e-12) << "rank " << i;
    }
  }
}

// Hand-computed run of Algorithm 1. Frames are points t on a line with
// sim(a, b) = 1 - |t_a - t_b| / 100 (L1 metric), threshold_0 = 1, alpha = 0.9,
// beta = 0.95, min_gap = 0:
//   q0 t=50: creates N0.
//   q1 t=60: base = sim(60,50) = .90; N0 first .90 > .81, mean .90 > .855: joins N0.
//   q2 t=70: base .90; N0 first sim(70,50) = .80 <= .81: creates N1.
//   q3 t=72: base .98; N0 first .78 <= .882; N1 first .98 > .882, mean .98 > .931: joins N1.
//   q4 t=55: base sim(55,72) = .83; N0 first .95 > .747, mean (.95+.95)/2 > .7885: joins N0;
//            candidates 0 and 1 tie at .95: older first.
//   q5 t=42: base .87; N0 first .92 > .783, mean (.92+.82+.87)/3 = .87 > .8265: joins N0.
//   q6 t=90: base .52; N0 first .60 > .468, mean .6175 > .494: joins N0.
//   q7 t=44: base .54; N0 first .94 > .486, mean .838 > .513: joins N0.
//   q8 t=46: base .98; N0 first .96 > .882 but mean (.96+.86+.91+.96+.56+.98)/6 = .8717
//            <= .931; N1 first .76 <= .882: creates N2.
//   q9 t=88: base .58; N0 first .62 > .522, mean .6817 > .551: joins N0.
TEST(DynamicNodes, HandComputedAlgorithm1) {
  DynamicNodes nodes;
  const auto steps = run_hand_computed(nodes, 0);

  const std::int64_t want_node[] = {0, 0, 1, 1, 0, 0, 0, 0, 2, 0};
  const bool want_created[] = {true, false, true, false, false, false, false, false, true, false};
  const std::int64_t want_sims[] = {0, 2, 2, 3, 3, 4, 5, 6, 8, 7};
  const std::vector<std::vector<Candidate>> want_candidates = {
      {},
      {{0, .90}},
      {},
      {{2, .98}},
      {{0, .95}, {1, .95}},
      {{0, .92}, {4, .87}, {1, .82}},
      {{1, .70}, {4, .65}, {0, .60}, {5, .52}},
      {{5, .98}, {0, .94}, {4, .89}, {1, .84}, {6, .54}},
      {},
      {{6, .98}, {1, .72}, {4, .67}, {0, .62}, {7, .56}, {5, .54}},
  };
  ASSERT_NO_FATAL_FAILURE(expect_steps(steps, want_node, want_created, want_sims, want_candidates));
  ASSERT_EQ(nodes.size(), 3);
  EXPECT_EQ(nodes.members(0), (std::vector<std::int64_t>{0, 1, 4, 5, 6, 7, 9}));
  EXPECT_EQ(nodes.members(1), (std::vector<std::int64_t>{2, 3}));
  EXPECT_EQ(nodes.members(2), (std::vector<std::int64_t>{8}));
}

// The same frames with a temporal window of 2 frames:
//   q1, q2: N0's first frame is inside the window: create N1, N2.
//   q3 t=72: N0 first .78 <= .882 (N1, N2 inside the window): creates N3.
//   q4 t=55: joins N0 = {0} (mean .95 > .7885); candidates: 0.
//   q5 t=42: N0 = {0, 4}, mean .895 > .8265: joins; 4 is inside the window.
//   q6 t=90: joins N0 (mean .59 > .494); candidates j < 4: only 0.
//   q7 t=44: joins N0; candidates j < 5: 0 (.94), 4 (.89).
//   q8 t=46: N0 mean .874 <= .931; N1 .86, N2 .76, N3 .74 all <= .882: creates N4.
//   q9 t=88: joins N0; candidates j < 7: 6 (.98), 4 (.67), 0 (.62), 5 (.54); 7 is too recent.
TEST(DynamicNodes, HandComputedAlgorithm1WithWindow) {
  DynamicNodes nodes;
  const auto steps = run_hand_computed(nodes, 2);

  const std::int64_t want_node[] = {0, 1, 2, 3, 0, 0, 0, 0, 4, 0};
  const bool want_created[] = {true, true, true, true, false, false, false, false, true, false};
  const std::int64_t want_sims[] = {0, 1, 1, 2, 2, 3, 4, 5, 9, 6};
  const std::vector<std::vector<Candidate>> want_candidates = {
      {}, {}, {}, {}, {{0, .95}}, {{0, .92}}, {{0, .60}}, {{0, .94}, {4, .89}}, {},
      {{6, .98}, {4, .67}, {0, .62}, {5, .54}},
  };
  ASSERT_NO_FATAL_FAILURE(expect_steps(steps, want_node, want_created, want_sims, want_candidates));
  ASSERT_EQ(nodes.size(), 5);
  EXPECT_EQ(nodes.members(0), (std::vector<std::int64_t>{0, 4, 5, 6, 7, 9}));
  EXPECT_EQ(nodes.members(4), (std::vector<std::int64_t>{8}));
}

// Independent re-implementation of Algorithm 1 (as documented in search.h and
// algorithm.md section 4), compared on random walks.
struct OracleStep {
  std::int64_t node;
  bool created;
  std::vector<Candidate> candidates;
};

std::vector<OracleStep> oracle(const std::vector<Descriptor>& frames, const SearchOptions& o,
                               SimilarityMetric metric) {
  std::vector<std::vector<std::int64_t>> nodes;
  std::vector<OracleStep> steps;
  auto sim = [&](std::size_t a, std::size_t b) {
    return similarity(frames[a].view(), frames[b].view(), metric);
  };
  for (std::size_t q = 0; q < frames.size(); ++q) {
    const double base = o.nodes.threshold_0 * (q > 0 ? sim(q, q - 1) : 1.0);
    OracleStep step{-1, true, {}};
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const std::int64_t first = nodes[i].front();
      if (!(first < static_cast<std::int64_t>(q) - o.min_gap)) continue;
      if (!(sim(q, first) > o.nodes.alpha * base)) continue;
      double sum = 0;
      for (std::int64_t m : nodes[i]) sum += sim(q, m);
      if (!(sum / nodes[i].size() > o.nodes.beta * base)) continue;
      for (std::int64_t m : nodes[i]) {
        if (m < static_cast<std::int64_t>(q) - o.min_gap) step.candidates.push_back({m, sim(q, m)});
      }
      std::sort(step.candidates.begin(), step.candidates.end(), better);
      if (step.candidates.size() > static_cast<std::size_t>(o.top_n)) step.candidates.resize(o.top_n);
      nodes[i].push_back(static_cast<std::int64_t>(q));
      step.node = static_cast<std::int64_t>(i);
      step.created = false;
      break;
    }
    if (step.created) {
      nodes.push_back({static_cast<std::int64_t>(q)});
      step.node = static_cast<std::int64_t>(nodes.size()) - 1;
    }
    steps.push_back(step);
  }
  return steps;
}

TEST(DynamicNodes, MatchesIndependentImplementationOnRandomWalks) {
  std::uint64_t s = 4242;
  int configs = 0, nontrivial = 0;
  for (int walk = 0; walk < 6; ++walk) {
    // A random walk on the line that revisits places, so nodes are re-joined.
    constexpr int kMass = 200;
    std::vector<Descriptor> frames;
    int t = kMass / 2;
    for (int i = 0; i < 120; ++i) {
      t += static_cast<int>(splitmix64(s) % 21) - 10;
      t = std::max(0, std::min(kMass, t));
      frames.push_back(line_descriptor(t, kMass));
    }
    const DynamicNodeOptions node_options[] = {{0.9, 0.8, 1.0}, {1.0, 0.9, 0.95}, {1.0, 0.95, 1.0}};
    for (const DynamicNodeOptions& nopt : node_options) {
      for (std::int64_t gap : {0, 3, 10}) {
        for (SimilarityMetric metric : {SimilarityMetric::kL1, SimilarityMetric::kReference}) {
          SearchOptions o;
          o.mode = kNodesSearch;
          o.min_gap = gap;
          o.top_n = 5;
          o.nodes = nopt;
          SCOPED_TRACE(testing::Message() << "walk " << walk << " gap " << gap << " "
                                          << to_string(metric) << " alpha " << nopt.alpha
                                          << " beta " << nopt.beta);
          DynamicNodes nodes;
          const auto steps = run_nodes(nodes, frames, o, metric);
          const auto want = oracle(frames, o, metric);
          std::int64_t created = 0;
          for (std::size_t q = 0; q < frames.size(); ++q) {
            ASSERT_EQ(steps[q].outcome.node, want[q].node) << "frame " << q;
            ASSERT_EQ(steps[q].outcome.created, want[q].created) << "frame " << q;
            expect_same(steps[q].candidates, want[q].candidates);
            created += want[q].created;
          }
          EXPECT_EQ(nodes.size(), created);
          ++configs;
          nontrivial += created > 1 && created < 100;
        }
      }
    }
  }
  // Most configurations both create several nodes and re-join them.
  EXPECT_GE(nontrivial, configs * 2 / 3);
}

}  // namespace
}  // namespace lsgd
