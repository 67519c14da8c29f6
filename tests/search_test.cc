// Tests of candidate search (include/lsgd/search.h): candidate ordering, the
// exhaustive search against a brute force, and dynamic nodes (Algorithm 1 with
// the reference implementation's relative thresholds) against hand-computed
// node assignments and an independent re-implementation. This file: ordering,
// exhaustive search, options and the registry of modes; the index:
// search_index_test.cc; dynamic nodes: search_nodes_test.cc.
#include "lsgd/search.h"
#include "lsgd/search/exhaustive.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/error.h"
#include "lsgd/frame_store.h"
#include "lsgd/similarity.h"
#include "search_test_support.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::message_of;
using search_test_support::brute_force;
using search_test_support::expect_same;
using search_test_support::line_descriptor;
using search_test_support::random_descriptor;
using search_test_support::store_of;

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

}  // namespace
}  // namespace lsgd
