// Tests of the appearance evidence (include/lsgd/evidence.h) against a
// brute-force reference of its definition: standardised similarities,
// sequence sums padded to their full length (no edge effect), the second
// standardisation, the sampled diagonals of dynamic nodes, and a rebuild from
// the store that matches an uninterrupted run bit for bit. This file: the
// statistics and their summaries, young queries, the definition in every
// mode, best places, query order; the exact-statistics limit, realignment
// and rebuilds: evidence_modes_test.cc; a map split into parts, on real
// sequences: evidence_parts_test.cc.
#include "lsgd/evidence.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <utility>

#include "lsgd/error.h"
#include "evidence_test_support.h"
#include "test_util.h"

namespace lsgd {
namespace {

using evidence_test_support::EvidenceRun;
using evidence_test_support::frame;
using evidence_test_support::Reference;

TEST(Statistics, MeanAndPopulationSd) {
  const double v[] = {1, 2, 3, 4};
  const ScoreStatistics s = statistics(v, 4);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.sd, std::sqrt(1.25));
  EXPECT_EQ(s.count, 4);
  EXPECT_FALSE(s.valid());  // fewer than kMinCalibration values
  EXPECT_EQ(statistics(v, 0).count, 0);
}

// Statistics that merge: the summaries of any split of a set of values,
// merged in any order, give the statistics of the whole bit for bit, and
// the order of the values does not matter either.
TEST(StatisticsSummary, AnySplitMergesToTheWholeBitForBit) {
  std::mt19937_64 rng(7);
  for (const double spread : {0.02, 3.0}) {  // similarities; sequence scores (sigma)
    std::normal_distribution<double> value(spread < 1 ? 0.8 : 0.0, spread);
    std::vector<double> v(5000);
    for (double& x : v) x = value(rng);
    const ScoreStatistics whole = statistics(v.data(), v.size());
    for (const int k : {1, 2, 3}) {
      SCOPED_TRACE(testing::Message() << "spread " << spread << ", " << k << " parts");
      // Contiguous parts, merged last to first; interleaved parts.
      std::vector<StatisticsSummary> parts(static_cast<std::size_t>(k)), woven(parts);
      for (std::size_t i = 0; i < v.size(); ++i) {
        parts[i * static_cast<std::size_t>(k) / v.size()].add(v[i]);
        woven[i % static_cast<std::size_t>(k)].add(v[i]);
      }
      StatisticsSummary a, b;
      for (auto it = parts.rbegin(); it != parts.rend(); ++it) a.merge(*it);
      for (const StatisticsSummary& p : woven) b.merge(p);
      for (const StatisticsSummary* m : {&a, &b}) {
        const ScoreStatistics s = m->statistics();
        EXPECT_EQ(s.count, whole.count);
        EXPECT_EQ(s.mean, whole.mean);
        EXPECT_EQ(s.sd, whole.sd);
      }
    }
    std::shuffle(v.begin(), v.end(), rng);
    const ScoreStatistics shuffled = statistics(v.data(), v.size());
    EXPECT_EQ(shuffled.mean, whole.mean);
    EXPECT_EQ(shuffled.sd, whole.sd);
    // The fixed point (1/2^40) is far below what the evidence resolves (1/1024 sigma).
    double sum = 0, squares = 0;
    for (const double x : v) sum += x;
    for (const double x : v) squares += (x - sum / v.size()) * (x - sum / v.size());
    EXPECT_NEAR(whole.mean, sum / v.size(), 1e-9 * spread);
    EXPECT_NEAR(whole.sd, std::sqrt(squares / v.size()), 1e-9 * spread);
  }
  // Equal values: no spread (never a valid standardisation).
  const std::vector<double> same(40, 0.75);
  EXPECT_EQ(statistics(same.data(), same.size()).sd, 0.0);
  EXPECT_FALSE(statistics(same.data(), same.size()).valid());
  // Beyond kMaxCount values the sums could overflow: refused.
  StatisticsSummary big;
  for (std::int64_t i = 0; i < StatisticsSummary::kMaxCount; ++i) big.add(1e6);  // clamped to 2^13
  EXPECT_THROW(big.add(1.0), InvalidArgument);
  EXPECT_THROW(big.merge(big), InvalidArgument);
}

// On real sequences, the evidence of a map split into 1, 2 or 3 parts:
// tests/evidence_parts_test.cc.

// A young query (fewer than kMinCalibration candidates) has no statistics of
// its own and no sequence evidence; its similarities are standardised with
// the prior, every similarity of the young queries so far, once those are
// kMinCalibration or more. Its row adds no sequence term (z 0), so the
// queries after it score as without the prior. A rebuild (a detector
// restored from storage) recomputes the prior.
TEST(AppearanceEvidence, YoungQueriesAreScoredOnThePrior) {
  const std::int64_t w = 5;
  EvidenceRun run({}, w, false);
  std::vector<double> prior;
  for (int i = 0; i < w + kMinCalibration; ++i) {
    SCOPED_TRACE(i);
    const Descriptor d = frame(i, 1000);
    for (int j = 0; j < i - w; ++j) {
      prior.push_back(similarity(d.view(), run.store.view(j), SimilarityMetric::kReference));
    }
    run.add(d, w, true);
    EXPECT_TRUE(run.evidence.young());
    const ScoreStatistics want = statistics(prior.data(), prior.size());
    const ScoreStatistics& got = run.evidence.similarity_statistics();
    EXPECT_EQ(got.count, static_cast<std::int64_t>(prior.size()));
    EXPECT_EQ(got.valid(), prior.size() >= static_cast<std::size_t>(kMinCalibration));
    if (got.valid()) {
      EXPECT_NEAR(got.mean, want.mean, 1e-12);
      EXPECT_NEAR(got.sd, want.sd, 1e-12);
      EXPECT_NEAR(run.evidence.single_frame(0.5), (0.5 - want.mean) / want.sd, 1e-9);
      // Rebuilt from the stored frames, the next query has the same prior.
      EvidenceRun rebuilt({}, w, false);
      for (int j = 0; j < i; ++j) rebuilt.store.add(frame(j, 1000));
      rebuilt.evidence.rebuild(rebuilt.store, SimilarityMetric::kReference);
      rebuilt.add(d, w, true);
      EXPECT_EQ(rebuilt.evidence.similarity_statistics().mean, got.mean);
      EXPECT_EQ(rebuilt.evidence.similarity_statistics().sd, got.sd);
    } else {
      EXPECT_TRUE(std::isnan(run.evidence.single_frame(0.5)));
    }
    EXPECT_FALSE(run.evidence.sequence_statistics().valid());
    std::vector<Candidate> out;
    run.evidence.best_places(10, out);
    EXPECT_TRUE(out.empty());
    run.store.add(d);
  }
  // The first query with kMinCalibration candidates has statistics of its own.
  const Descriptor d = frame(w + kMinCalibration, 1000);
  run.add(d, w, true);
  EXPECT_FALSE(run.evidence.young());
  EXPECT_EQ(run.evidence.similarity_statistics().count, kMinCalibration);
  EXPECT_TRUE(run.evidence.sequence_statistics().valid());
}

// Every candidate's evidence equals the definition, in particular the
// candidates near the start of the map, whose sequences lack frames: their
// missing terms count as the mean (0), so they are not noisier than others.
TEST(AppearanceEvidence, ExhaustiveMatchesTheDefinitionIncludingTheMapStart) {
  SequenceOptions o;
  o.frames = 4;
  o.long_frames = 12;
  const std::int64_t w = 3;
  std::vector<Descriptor> frames;
  for (int i = 0; i < 120; ++i) frames.push_back(frame(i, 50));
  const Reference ref(frames, w, o, false);
  EvidenceRun run(o, w, false);
  for (std::int64_t q = 0; q < 120; ++q) {
    run.add(frames[q], w, true);
    if (q >= 60 && q % 7 == 0) {
      SCOPED_TRACE(q);
      for (std::int64_t j : {std::int64_t{0}, std::int64_t{1}, std::int64_t{2}, q / 2, q - w - 1}) {
        const double want = ref.evidence(q, j);
        const double got = run.evidence.sequence(run.store, frames[q].view(), j,
                                                 SimilarityMetric::kReference);
        EXPECT_NEAR(got, want, 1e-9) << "frame " << j;
      }
      // The single-frame score is the standardised similarity.
      const ScoreStatistics s = ref.level1(q);
      EXPECT_NEAR(run.evidence.single_frame(0.7), (0.7 - s.mean) / s.sd, 1e-12);
    }
    run.store.add(frames[q]);
  }
}

TEST(AppearanceEvidence, SampledDiagonalsMatchTheDefinition) {
  SequenceOptions o;
  o.frames = 3;
  o.long_frames = 8;
  const std::int64_t w = 2;
  const int n = static_cast<int>(2 * kMaxSampledDiagonals + 90);  // the stride doubles twice
  std::vector<Descriptor> frames;
  for (int i = 0; i < n; ++i) frames.push_back(frame(i, 300));
  const Reference ref(frames, w, o, true);
  EvidenceRun run(o, w, true);
  for (std::int64_t q = 0; q < n; ++q) {
    run.add(frames[q], w, false);
    EXPECT_LE(run.evidence.diagonals(q), kMaxSampledDiagonals);
    if (q > 2 * kMaxSampledDiagonals) {
      EXPECT_GE(run.evidence.diagonals(q), kMaxSampledDiagonals / 2);
    }
    if (q == 200 || q == kMaxSampledDiagonals + 10 || q == n - 1) {
      SCOPED_TRACE(q);
      // On a kept diagonal and off them (computed from the stored frames).
      const std::int64_t s = run.evidence.stride(q);
      for (std::int64_t j : {q - w - 1, q - w - 1 - s, q - w - 2, std::int64_t{1}, q / 3}) {
        const double want = ref.evidence(q, j);
        const double got = run.evidence.sequence(run.store, frames[q].view(), j,
                                                 SimilarityMetric::kReference);
        EXPECT_NEAR(got, want, 1e-9) << "frame " << j << " stride " << s;
      }
    }
    run.store.add(frames[q]);
  }
  EXPECT_EQ(run.evidence.stride(n - 1), 4);
}

// A sequence scored again one query later on the same diagonal continues the
// previous query's sums (its terms t >= 1, less the oldest); it must equal
// the definition, near the map's start too (terms before frame 0), and after
// a query that skipped the diagonal (sums computed afresh).
TEST(AppearanceEvidence, SequencesFollowedAlongADiagonalMatchTheDefinition) {
  SequenceOptions o;
  o.frames = 3;
  o.long_frames = 8;
  const std::int64_t w = 3;
  const int n = static_cast<int>(kMaxSampledDiagonals + 100);
  std::vector<Descriptor> frames;
  for (int i = 0; i < n; ++i) frames.push_back(frame(i, 37));
  const Reference ref(frames, w, o, true);
  EvidenceRun run(o, w, true);
  for (std::int64_t q = 0; q < n; ++q) {
    run.add(frames[q], w, false);
    if (q >= n - 40) {
      SCOPED_TRACE(q);
      ASSERT_EQ(run.evidence.stride(q), 2);  // kept: even offsets (w + 1 + 2 k)
      // Offsets off the kept diagonals, followed every query (571: frames 1
      // to 40, so at first terms before the map's start); every other query.
      std::vector<std::int64_t> offsets = {37, 101, 571};
      if (q % 2 == 0) offsets.push_back(43);
      for (const std::int64_t d : offsets) {
        const std::int64_t j = q - d;
        if (j < 0 || j >= q - w) continue;
        const double want = ref.evidence(q, j);
        const double got = run.evidence.sequence(run.store, frames[q].view(), j,
                                                 SimilarityMetric::kReference);
        EXPECT_NEAR(got, want, 1e-9) << "frame " << j << " offset " << d;
      }
    }
    run.store.add(frames[q]);
  }
}

// The terms a sequence reads are kept by diagonal, a ring of the last
// queries each, and once there are more than 4,096 diagonals the records no
// query of the ring holds any more are dropped: diagonals scored again after
// gaps shorter and longer than the ring (128 slots for long_frames 70), new
// ones every query (more than 4,096 in all, so records were dropped), and one
// scored every query (its carry) all match the definition.
TEST(AppearanceEvidence, SequencesOnDiagonalsScoredAfterGapsMatchTheDefinition) {
  SequenceOptions o;
  o.frames = 5;
  o.long_frames = 70;
  const std::int64_t w = 3;
  const int n = 6000;
  std::vector<Descriptor> frames;
  for (int i = 0; i < n; ++i) frames.push_back(frame(i, 41));
  const Reference ref(frames, w, o, true);
  EvidenceRun run(o, w, true);
  std::set<std::int64_t> scored;  // offsets
  for (std::int64_t q = 0; q < n; ++q) {
    run.add(frames[q], w, false);
    if (q >= 200) {
      SCOPED_TRACE(q);
      std::vector<std::int64_t> offsets = {150};  // every query
      std::uint64_t state = static_cast<std::uint64_t>(q);
      for (int k = 0; k < 40; ++k) {
        offsets.push_back(60 + static_cast<std::int64_t>(test::splitmix64(state) % static_cast<std::uint64_t>(q - 60)));
      }
      if (q % 150 < 3) offsets.push_back(133);  // gaps of 148 queries, longer than the ring
      for (const std::int64_t d : offsets) {
        const std::int64_t j = q - d;
        if (j < 0 || j >= q - w) continue;
        scored.insert(d);
        const double got = run.evidence.sequence(run.store, frames[q].view(), j,
                                                 SimilarityMetric::kReference);
        if (q % 16 == 0 || d == 133) {
          ASSERT_NEAR(got, ref.evidence(q, j), 1e-9) << "frame " << j << " offset " << d;
        }
      }
    }
    run.store.add(frames[q]);
  }
  ASSERT_GT(scored.size(), 4096u);
}

TEST(AppearanceEvidence, BestPlacesAreDistinctLocalMaximaBestFirst) {
  SequenceOptions o;
  o.frames = 4;
  o.long_frames = 0;
  o.tolerance = 2;
  const std::int64_t w = 3;
  std::vector<Descriptor> frames;
  for (int i = 0; i < 160; ++i) frames.push_back(frame(i, 40));  // every place 3 times
  EvidenceRun run(o, w, false);
  const Reference ref(frames, w, o, false);
  for (std::int64_t q = 0; q < 160; ++q) {
    run.add(frames[q], w, true);
    if (q == 150) {
      std::vector<Candidate> out;
      run.evidence.best_places(6, out);
      ASSERT_EQ(out.size(), 6u);
      // The revisits of place 150 % 40 = 30 come first.
      EXPECT_TRUE(out[0].frame == 110 || out[0].frame == 70 || out[0].frame == 30) << out[0].frame;
      for (std::size_t a = 0; a < out.size(); ++a) {
        EXPECT_NEAR(out[a].score, ref.evidence(q, out[a].frame), 1e-9);
        if (a > 0) {
          EXPECT_FALSE(better(out[a], out[a - 1]));
        }
        for (std::size_t b = 0; b < a; ++b) {
          EXPECT_GT(std::llabs(out[a].frame - out[b].frame), 2 * o.tolerance + 1);
        }
        // A local maximum within 2 * tolerance + 1 frames.
        for (std::int64_t j = out[a].frame - 5; j <= out[a].frame + 5; ++j) {
          if (j < 0 || j >= q - w || j == out[a].frame) continue;
          EXPECT_LE(ref.evidence(q, j), out[a].score + 1e-9) << j;
        }
      }
    }
    run.store.add(frames[q]);
  }
}

TEST(AppearanceEvidence, QueriesMustComeInOrder) {
  EvidenceRun run({}, 2, false);
  const Descriptor d = frame(0, 10);
  EXPECT_THROW(run.evidence.add_query(run.store, d.view(), 3, SimilarityMetric::kReference, nullptr),
               InvalidArgument);
  std::vector<double> wrong(5, 0.5);  // query 0 has no candidates
  EXPECT_THROW(run.evidence.add_query(run.store, d.view(), 0, SimilarityMetric::kReference, &wrong),
               InvalidArgument);
  EXPECT_THROW(AppearanceEvidence({}, -1, false), InvalidArgument);
}

}  // namespace
}  // namespace lsgd
