// Dynamic nodes (include/lsgd/search/dynamic_nodes.h): Algorithm 1 with the
// reference implementation's relative thresholds, against hand-computed node
// assignments and an independent re-implementation.
#include "lsgd/search/dynamic_nodes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/error.h"
#include "lsgd/frame_store.h"
#include "lsgd/search.h"
#include "lsgd/similarity.h"
#include "search_test_support.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::splitmix64;
using search_test_support::brute_force;
using search_test_support::expect_same;
using search_test_support::line_descriptor;
using search_test_support::random_descriptor;
using search_test_support::store_of;

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
