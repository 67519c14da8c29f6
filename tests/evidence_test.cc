// Tests of the appearance evidence (include/lsgd/evidence.h) against a
// brute-force reference of its definition: standardised similarities,
// sequence sums padded to their full length (no edge effect), the second
// standardisation, the sampled diagonals of dynamic nodes, and a rebuild from
// the store that matches an uninterrupted run bit for bit.
#include "lsgd/evidence.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <limits>
#include <map>
#include <opencv2/core.hpp>
#include <set>
#include <utility>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/io/sequence.h"
#include "test_util.h"

namespace lsgd {
namespace {

// 2-cell frames whose histograms drift along a route and repeat it: frame i
// shows place i % period with a little per-frame noise.
Descriptor frame(int i, int period) {
  std::uint64_t state = 77 + static_cast<std::uint64_t>(i);
  const int p = i % period;
  std::vector<std::vector<std::pair<int, Count>>> cells(2);
  for (int c = 0; c < 2; ++c) {
    for (int k = 0; k < 12; ++k) {
      cells[c].push_back({(p * 5 + k * 17 + c * 101) % kBins,
                          20 + (p * 7 + k * 3) % 30 + static_cast<Count>(test::splitmix64(state) % 4)});
    }
  }
  return test::make_descriptor(cells);
}

// Like frame(), but neighbouring places look alike (each cell a bump that
// moves 3 bins a place), so sequence scores rise smoothly to a revisit.
Descriptor smooth_frame(int i, int period) {
  std::uint64_t state = 91 + static_cast<std::uint64_t>(i);
  const int p = i % period;
  std::vector<std::vector<std::pair<int, Count>>> cells(2);
  for (int c = 0; c < 2; ++c) {
    const int centre = (p * 3 + c * 97) % kBins;
    for (int k = -12; k <= 12; ++k) {
      cells[c].push_back({(centre + k + kBins) % kBins,
                          static_cast<Count>(40 - std::abs(k) * 3) +
                              static_cast<Count>(test::splitmix64(state) % 6)});
    }
  }
  return test::make_descriptor(cells);
}

constexpr double kScale = 1024.0;

// The definition, computed directly: every similarity, every statistic.
struct Reference {
  std::vector<Descriptor> frames;
  std::int64_t min_gap;
  SequenceOptions options;
  bool sample;
  AppearanceEvidence stride_of{{}, 0, false};  // only for stride() / statistics_stride()

  Reference(std::vector<Descriptor> f, std::int64_t w, SequenceOptions o, bool s,
            std::int64_t exact = kExactStatisticsCandidates)
      : frames(std::move(f)), min_gap(w), options(o), sample(s), stride_of(o, w, s, exact) {}

  double sim(std::int64_t a, std::int64_t b) const {
    return similarity(frames[a].view(), frames[b].view(), SimilarityMetric::kReference);
  }
  // Frames of the diagonals the statistics of query q are computed over.
  std::vector<std::int64_t> sampled(std::int64_t q) const {
    std::vector<std::int64_t> out;
    const std::int64_t s = stride_of.statistics_stride(q);
    for (std::int64_t d = min_gap + 1; d <= q; d += s) out.push_back(q - d);
    return out;
  }
  ScoreStatistics level1(std::int64_t q) const {
    if (const auto it = level1_of.find(q); it != level1_of.end()) return it->second;
    std::vector<double> v;
    for (std::int64_t j : sampled(q)) v.push_back(sim(q, j));
    return level1_of[q] = statistics(v.data(), v.size());
  }
  mutable std::map<std::int64_t, ScoreStatistics> level1_of;  // level1(), computed once
  std::int64_t z(std::int64_t a, std::int64_t b) const {
    if (a < 0 || b < 0) return 0;
    const ScoreStatistics s = level1(a);
    if (!s.valid()) return 0;
    const double v = std::clamp(s.standardise(sim(a, b)), -64.0, 64.0);
    return std::lround(v * kScale);
  }
  // A(q, j): terms that do not exist count as 0, the divisor is the full length.
  double sequence_mean(std::int64_t q, std::int64_t j) const {
    std::int64_t a = 0, b = 0;
    const int steps = std::max(options.frames, options.long_frames);
    for (int t = 0; t < steps; ++t) {
      const std::int64_t v = z(q - t, j - t);
      if (t < options.frames) a += v;
      b += v;
    }
    const double short_mean = a / (kScale * options.frames);
    if (options.long_frames == 0) return short_mean;
    return 0.5 * (short_mean + b / (kScale * options.long_frames));
  }
  // Sequence evidence R(q, j), NaN when not calibrated.
  double evidence(std::int64_t q, std::int64_t j) const {
    if (!level1(q).valid()) return std::numeric_limits<double>::quiet_NaN();
    auto it = level2_of.find(q);
    if (it == level2_of.end()) {
      std::vector<double> all;
      for (std::int64_t f : sampled(q)) all.push_back(sequence_mean(q, f));
      it = level2_of.emplace(q, statistics(all.data(), all.size())).first;
    }
    const ScoreStatistics& s = it->second;
    if (!s.valid()) return std::numeric_limits<double>::quiet_NaN();
    return s.standardise(sequence_mean(q, j));
  }
  mutable std::map<std::int64_t, ScoreStatistics> level2_of;  // evidence(), computed once
};

struct EvidenceRun {
  FrameStore store;
  AppearanceEvidence evidence;
  EvidenceRun(const SequenceOptions& o, std::int64_t w, bool s,
              std::int64_t exact = kExactStatisticsCandidates)
      : evidence(o, w, s, exact) {}
  // Adds query q = store.size() (exhaustive: with its similarity row).
  void add(const Descriptor& d, std::int64_t w, bool with_row) {
    const std::int64_t q = store.size();
    std::vector<double> row;
    for (std::int64_t j = 0; j < q - w; ++j) {
      row.push_back(similarity(d.view(), store.view(j), SimilarityMetric::kReference));
    }
    evidence.add_query(store, d.view(), q, SimilarityMetric::kReference, with_row ? &row : nullptr);
  }
};

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

// On real sequences: every query's similarity statistics over the map, from
// the summaries of the map split into k = 1, 2, 3 parts (frame ranges, as
// a fleet's shards would hold them), equal the whole map's bit for bit.
TEST(StatisticsSummary, RealMapsSplitIntoPartsGiveTheSameStatistics) {
  namespace fs = std::filesystem;
  const fs::path root = fs::path(LSGD_SHARED_DIR) / "datasets";
  int sequences = 0;
  for (const char* name : {"corridor", "lip6-outdoor"}) {
    if (!fs::is_regular_file(root / name / "sequence.txt")) continue;
    SCOPED_TRACE(name);
    ++sequences;
    const std::int64_t w = 50;
    DetectorOptions options;
    options.search.min_gap = w;
    options.verification.stages = {};  // the statistics only
    Detector detector(options);
    const io::Sequence seq = io::open_sequence((root / name / "sequence.txt").string());
    const std::size_t n = std::min<std::size_t>(seq.images.size(), 300);
    for (std::size_t i = 0; i < n; ++i) detector.process(io::read_image(seq.images[i]));
    int queries = 0;
    for (std::int64_t q = w + 1 + kMinCalibration; q < detector.size(); q += 7) {
      const std::int64_t candidates = q - w;
      std::vector<double> row;
      for (std::int64_t j = 0; j < candidates; ++j) row.push_back(detector.similarity(q, j));
      const ScoreStatistics whole = statistics(row.data(), row.size());
      for (const std::int64_t k : {1, 2, 3}) {
        // Part p holds frames [p * size / k, (p + 1) * size / k) of the map.
        StatisticsSummary merged;
        for (std::int64_t p = k - 1; p >= 0; --p) {
          StatisticsSummary part;
          const std::int64_t first = p * detector.size() / k, end = (p + 1) * detector.size() / k;
          for (std::int64_t j = first; j < std::min(end, candidates); ++j) {
            part.add(row[static_cast<std::size_t>(j)]);
          }
          merged.merge(part);
        }
        const ScoreStatistics s = merged.statistics();
        ASSERT_EQ(s.count, whole.count) << q;
        ASSERT_EQ(s.mean, whole.mean) << q << " k " << k;
        ASSERT_EQ(s.sd, whole.sd) << q << " k " << k;
      }
      ++queries;
    }
    EXPECT_GT(queries, 10);
  }
  if (sequences == 0) GTEST_SKIP() << "no real sequence under " << root << " (../shared is absent)";
}

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

// Beyond exact_statistics candidates, exhaustive search standardises with the
// sampled diagonals' statistics, so it scores every candidate bit for bit as
// the sampled modes do; up to it, over every candidate.
TEST(AppearanceEvidence, BeyondTheExactLimitExhaustiveScoresAsTheSampledModes) {
  SequenceOptions o;
  o.frames = 3;
  o.long_frames = 8;
  const std::int64_t w = 2, exact = 300;
  const int n = 1100;  // the sampled stride reaches 4
  std::vector<Descriptor> frames;
  for (int i = 0; i < n; ++i) frames.push_back(frame(i, 200));
  const Reference ref(frames, w, o, false, exact);
  EvidenceRun all(o, w, false, exact), sampled(o, w, true);
  for (std::int64_t q = 0; q < n; ++q) {
    all.add(frames[q], w, true);
    sampled.add(frames[q], w, false);
    const ScoreStatistics& a = all.evidence.similarity_statistics();
    const ScoreStatistics& b = sampled.evidence.similarity_statistics();
    if (q - w <= exact) {
      // (A young query's statistics are the prior's, over more values.)
      if (q - w >= kMinCalibration) {
        EXPECT_EQ(a.count, q - w) << q;
      }
      EXPECT_EQ(all.evidence.statistics_stride(q), 1);
    } else {
      SCOPED_TRACE(q);
      EXPECT_EQ(all.evidence.statistics_stride(q), sampled.evidence.stride(q));
      EXPECT_EQ(a.count, b.count);
      EXPECT_EQ(a.mean, b.mean);  // bit for bit
      EXPECT_EQ(a.sd, b.sd);
      EXPECT_EQ(all.evidence.sequence_statistics().mean, sampled.evidence.sequence_statistics().mean);
      EXPECT_EQ(all.evidence.sequence_statistics().sd, sampled.evidence.sequence_statistics().sd);
      if (q % 97 == 0 || q == n - 1) {
        for (const std::int64_t j : {q - w - 1, q - w - 2, q - w - 3, std::int64_t{5}, q / 3}) {
          const double x =
              all.evidence.sequence(all.store, frames[q].view(), j, SimilarityMetric::kReference);
          const double y = sampled.evidence.sequence(sampled.store, frames[q].view(), j,
                                                     SimilarityMetric::kReference);
          EXPECT_EQ(x, y) << "frame " << j;
          EXPECT_NEAR(x, ref.evidence(q, j), 1e-9) << "frame " << j;
        }
      }
    }
    all.store.add(frames[q]);
    sampled.store.add(frames[q]);
  }
  EXPECT_EQ(sampled.evidence.stride(n - 1), 4);
  EXPECT_THROW(AppearanceEvidence(o, w, false, -1), InvalidArgument);
}

// A sampled mode that scores every frame up to a number of candidates
// (index mode's search.index.exhaustive_up_to) standardises as exhaustive
// search does, bit for bit, on both sides of it: before, with every
// diagonal, and ranks every place; after, with the diagonals of the stride
// that exhaustive search's statistics sample there (here it jumps from 1 to
// 4 at once). A rebuild right after the switch (a ring of two strides)
// continues bit for bit. The limit may also lie beyond exhaustive search's
// exact statistics (the statistics are then sampled before the rows are).
TEST(AppearanceEvidence, EveryFrameUpToALimitThenSampledScoresAsExhaustive) {
  for (const std::int64_t exact : {std::int64_t{1100}, std::int64_t{600}}) {
    SCOPED_TRACE(testing::Message() << "exact statistics up to " << exact);
    SequenceOptions o;
    o.frames = 3;
    o.long_frames = 8;
    const std::int64_t w = 2, limit = 1100;
    const int n = 1200;
    std::vector<Descriptor> frames;
    for (int i = 0; i < n; ++i) frames.push_back(frame(i, 200));
    const Reference ref(frames, w, o, false, exact);
    EvidenceRun all(o, w, false, exact), hybrid(o, w, true, exact), resumed(o, w, true, exact);
    hybrid.evidence = AppearanceEvidence(o, w, true, exact, limit);
    resumed.evidence = AppearanceEvidence(o, w, true, exact, limit);
    const std::int64_t stop = limit + w + 3;  // three queries after the switch
    for (std::int64_t q = 0; q < n; ++q) {
      SCOPED_TRACE(q);
      const bool every = q - w <= limit;
      EXPECT_EQ(hybrid.evidence.sampled(q), !every);
      EXPECT_EQ(hybrid.evidence.stride(q), every ? 1 : 4);
      all.add(frames[q], w, true);
      hybrid.add(frames[q], w, every);  // the search's row while it scores every frame
      if (q == stop) resumed.evidence.rebuild(resumed.store, SimilarityMetric::kReference);
      if (q >= stop) resumed.add(frames[q], w, false);
      for (EvidenceRun* run : {&hybrid, &resumed}) {
        if (run == &resumed && q < stop) continue;
        const AppearanceEvidence& e = run->evidence;
        EXPECT_EQ(e.similarity_statistics().count, all.evidence.similarity_statistics().count);
        EXPECT_EQ(e.similarity_statistics().mean, all.evidence.similarity_statistics().mean);
        EXPECT_EQ(e.similarity_statistics().sd, all.evidence.similarity_statistics().sd);
        EXPECT_EQ(e.sequence_statistics().mean, all.evidence.sequence_statistics().mean);
        EXPECT_EQ(e.sequence_statistics().sd, all.evidence.sequence_statistics().sd);
      }
      std::vector<Candidate> a, b;
      all.evidence.best_places(10, a);
      hybrid.evidence.best_places(10, b);
      if (every) {
        ASSERT_EQ(a.size(), b.size());
        for (std::size_t k = 0; k < a.size(); ++k) {
          EXPECT_EQ(a[k].frame, b[k].frame);
          EXPECT_EQ(a[k].score, b[k].score);
        }
      } else {
        EXPECT_TRUE(b.empty());  // sampled: the search's shortlist is realigned instead
      }
      if (q % 50 == 0 || (q >= limit + w - 2 && q <= stop + 2) || q == n - 1) {
        for (const std::int64_t j : {q - w - 1, q - w - 2, q - w - 7, std::int64_t{5}, q / 3}) {
          if (j < 0) continue;
          const double x =
              all.evidence.sequence(all.store, frames[q].view(), j, SimilarityMetric::kReference);
          const double y = hybrid.evidence.sequence(hybrid.store, frames[q].view(), j,
                                                    SimilarityMetric::kReference);
          if (std::isnan(x)) {
            EXPECT_TRUE(std::isnan(y)) << "frame " << j;
            continue;
          }
          EXPECT_EQ(x, y) << "frame " << j;
          EXPECT_NEAR(x, ref.evidence(q, j), 1e-9) << "frame " << j;
          if (q >= stop) {
            EXPECT_EQ(resumed.evidence.sequence(resumed.store, frames[q].view(), j,
                                                SimilarityMetric::kReference), x)
                << "frame " << j;
          }
        }
      }
      all.store.add(frames[q]);
      hybrid.store.add(frames[q]);
      resumed.store.add(frames[q]);
    }
    // A row for a query whose diagonals are sampled is an error, as is a
    // negative limit.
    std::vector<double> row(static_cast<std::size_t>(n - w), 0.5);
    EXPECT_THROW(hybrid.evidence.add_query(hybrid.store, frames[0].view(), n,
                                           SimilarityMetric::kReference, &row),
                 InvalidArgument);
    EXPECT_THROW(AppearanceEvidence(o, w, true, limit, -1), InvalidArgument);
  }
}

// A shortlist realigned with a reach reports the places exhaustive search
// ranks (best_places: local maxima within 2 * tolerance + 1 frames), with
// the same scores, from candidates a few frames off them, and every such
// place near a candidate; a shortlist without reach only looks within
// +-tolerance.
TEST(AppearanceEvidence, RealignedShortlistReportsExhaustiveSearchsPlaces) {
  SequenceOptions o;
  o.frames = 4;
  o.long_frames = 12;
  o.tolerance = 2;
  const std::int64_t w = 3, exact = 64;
  const int n = 700;
  std::vector<Descriptor> frames;
  for (int i = 0; i < n; ++i) frames.push_back(smooth_frame(i, 120));  // every place 5 times
  EvidenceRun all(o, w, false, exact), sampled(o, w, true);
  for (std::int64_t q = 0; q < n; ++q) {
    all.add(frames[q], w, true);
    sampled.add(frames[q], w, false);
    if (q == 650 || q == 699) {
      SCOPED_TRACE(q);
      std::vector<Candidate> peaks, top, raw, out;
      all.evidence.best_places(100000, peaks);
      all.evidence.best_places(4, top);
      ASSERT_EQ(top.size(), 4u);
      // Each of the best places from a frame 4 past it (outside the window),
      // and frames between places.
      for (const Candidate& c : top) raw.push_back({c.frame + 4, 0});
      for (const std::int64_t j : {std::int64_t{17}, std::int64_t{333}, std::int64_t{401}}) raw.push_back({j, 0});
      sampled.evidence.realign(sampled.store, frames[q].view(), raw, SimilarityMetric::kReference,
                               4, 16, out);
      ASSERT_EQ(out.size(), top.size());
      for (std::size_t k = 0; k < out.size(); ++k) {
        EXPECT_EQ(out[k].frame, top[k].frame);
        EXPECT_EQ(out[k].score, top[k].score);  // bit for bit
      }
      // Exactly exhaustive search's places within tolerance + reach of a
      // candidate, every one of them: also two places with a candidate
      // between them (an uphill climb from it finds only one).
      const std::int64_t reach = 16, span = o.tolerance + reach;
      std::int64_t between = -1;
      for (const Candidate& a : peaks) {
        for (const Candidate& b : peaks) {
          if (b.frame > a.frame && b.frame - a.frame <= 2 * span && b.frame - a.frame > 2 * o.tolerance + 2) {
            between = (a.frame + b.frame) / 2;
          }
        }
      }
      ASSERT_GE(between, 0) << "no two places close enough for the test";
      raw.push_back({between, 0});
      sampled.evidence.realign(sampled.store, frames[q].view(), raw, SimilarityMetric::kReference,
                               100000, reach, out);
      std::vector<Candidate> expected;
      for (const Candidate& p : peaks) {
        const bool near = std::any_of(raw.begin(), raw.end(), [&](const Candidate& r) {
          return std::llabs(r.frame - p.frame) <= span;
        });
        if (near) expected.push_back(p);
      }
      ASSERT_EQ(out.size(), expected.size());
      for (std::size_t k = 0; k < out.size(); ++k) {
        EXPECT_EQ(out[k].frame, expected[k].frame);
        EXPECT_EQ(out[k].score, expected[k].score);  // bit for bit
      }
      EXPECT_GE(std::count_if(out.begin(), out.end(), [&](const Candidate& c) {
                  return std::llabs(c.frame - between) <= span;
                }),
                2);
      // Without reach: the best of +-tolerance around each candidate.
      sampled.evidence.realign(sampled.store, frames[q].view(), raw, SimilarityMetric::kReference,
                               100, 0, out);
      for (const Candidate& c : out) {
        const bool near = std::any_of(raw.begin(), raw.end(), [&](const Candidate& r) {
          return std::llabs(r.frame - c.frame) <= o.tolerance;
        });
        EXPECT_TRUE(near) << "frame " << c.frame;
      }
    }
    all.store.add(frames[q]);
    sampled.store.add(frames[q]);
  }
}

// A detector restored from storage rebuilds its evidence from the stored
// frames; from then on it must score exactly as one that never stopped.
// Followed frames (a mode follows places beyond top_n to the next query):
// one whose sequence would rank among the top_n is realigned as a candidate,
// so the top_n are still exhaustive search's places near the candidates;
// the others come after them, best first, without a second frame of the
// same stretch of diagonals, up to `keep` in all.
TEST(AppearanceEvidence, FollowedFramesAreRealignedWhenTheyWouldRankAndRankedOtherwise) {
  SequenceOptions o;
  o.frames = 4;
  o.long_frames = 12;
  o.tolerance = 2;
  const std::int64_t w = 3, exact = 64, reach = 16, span = o.tolerance + reach;
  const std::int64_t radius = 2 * o.tolerance + 1;
  const int n = 700, top_n = 4, keep = 12;
  std::vector<Descriptor> frames;
  for (int i = 0; i < n; ++i) frames.push_back(smooth_frame(i, 120));
  // The last query, with exhaustive search's places for it.
  const std::int64_t q = n - 1;
  std::vector<Candidate> peaks;
  {
    EvidenceRun a(o, w, false, exact), b(o, w, true);
    for (std::int64_t k = 0; k <= q; ++k) {
      a.add(frames[k], w, true);
      b.add(frames[k], w, false);
      if (k < q) a.store.add(frames[k]), b.store.add(frames[k]);
    }
    a.evidence.best_places(100000, peaks);
    ASSERT_GE(peaks.size(), 9u);
    // Candidates: the places ranked 5 to 8; followed: the best place (it
    // ranks first, so it is realigned), and two neighbouring frames away
    // from every place and candidate (ranked, the better one kept).
    std::vector<Candidate> raw(peaks.begin() + 4, peaks.begin() + 8);
    const auto far = [&](std::int64_t j) {
      return std::none_of(peaks.begin(), peaks.begin() + 8, [&](const Candidate& p) {
        return std::llabs(p.frame - j) <= 2 * span + radius;
      });
    };
    std::int64_t x = -1;
    for (std::int64_t j = 10; j + 1 < q - w && x < 0; ++j) {
      if (far(j) && far(j + 1)) x = j;
    }
    ASSERT_GE(x, 0);
    const std::vector<std::int64_t> followed = {peaks[0].frame, x, x + 1};
    std::vector<Candidate> out;
    b.evidence.realign(b.store, frames[q].view(), raw, followed, SimilarityMetric::kReference, top_n,
                       reach, keep, out);
    // Expected: exhaustive search's places near the candidates and the
    // promoted best place's frame, best first; then x or x + 1, the better.
    std::vector<Candidate> near;
    for (const Candidate& p : peaks) {
      const bool close = std::llabs(p.frame - peaks[0].frame) <= span ||
                         std::any_of(raw.begin(), raw.end(), [&](const Candidate& r) {
                           return std::llabs(r.frame - p.frame) <= span;
                         });
      if (close) near.push_back(p);
    }
    ASSERT_GE(near.size(), static_cast<std::size_t>(top_n));
    EXPECT_EQ(near[0].frame, peaks[0].frame);
    const double ax = b.evidence.sequence(b.store, frames[q].view(), x, SimilarityMetric::kReference);
    const double ax1 = b.evidence.sequence(b.store, frames[q].view(), x + 1, SimilarityMetric::kReference);
    ASSERT_LT(std::max(ax, ax1), near[top_n - 1].score) << "x would rank among the top_n";
    std::vector<Candidate> expected = near;
    expected.push_back(ax1 > ax ? Candidate{x + 1, ax1} : Candidate{x, ax});
    std::sort(expected.begin() + top_n, expected.end(), better);
    if (expected.size() > static_cast<std::size_t>(keep)) expected.resize(keep);
    ASSERT_EQ(out.size(), expected.size());
    for (std::size_t k = 0; k < out.size(); ++k) {
      SCOPED_TRACE(k);
      EXPECT_EQ(out[k].frame, expected[k].frame);
      EXPECT_EQ(out[k].score, expected[k].score);  // bit for bit
    }
    // top_n 0: no followed frame ranks among the top_n, so none is realigned;
    // they and the places are ranked, up to keep.
    b.evidence.realign(b.store, frames[q].view(), raw, followed, SimilarityMetric::kReference, 0, reach,
                       3, out);
    ASSERT_EQ(out.size(), 3u);
    EXPECT_EQ(out[0].frame, peaks[0].frame);
    EXPECT_EQ(out[0].score, peaks[0].score);
    // Without followed frames: the top_n of the candidates' places only.
    b.evidence.realign(b.store, frames[q].view(), raw, {}, SimilarityMetric::kReference, top_n, reach,
                       keep, out);
    EXPECT_NE(out[0].frame, peaks[0].frame);
  }
}

TEST(AppearanceEvidence, RebuildContinuesBitForBit) {
  // Exhaustive, sampled, and exhaustive past its exact statistics.
  for (const auto& [sample, exact] : {std::pair{false, kExactStatisticsCandidates},
                                      std::pair{true, kExactStatisticsCandidates},
                                      std::pair{false, std::int64_t{40}}}) {
    SequenceOptions o;
    o.frames = 5;
    o.long_frames = 9;
    const std::int64_t w = 4;
    const int n = sample || exact < 100 ? static_cast<int>(kMaxSampledDiagonals + 60) : 150;
    std::vector<Descriptor> frames;
    for (int i = 0; i < n; ++i) frames.push_back(frame(i, 70));
    // Stops early (a partial ring), mid-run and, sampled, right after the
    // stride doubled (the rebuilt ring mixes two strides).
    for (const int stop : {3, 60, static_cast<int>(kMaxSampledDiagonals + w + 3)}) {
      if (stop >= n - 5) continue;
      SCOPED_TRACE(testing::Message() << (sample ? "sampled" : "exhaustive") << " exact " << exact
                                      << " stop " << stop);
      EvidenceRun live(o, w, sample, exact), fresh(o, w, sample, exact);
      for (int q = 0; q < n; ++q) {
        live.add(frames[q], w, !sample);
        if (q >= stop) {
          if (q == stop) fresh.evidence.rebuild(fresh.store, SimilarityMetric::kReference);
          fresh.add(frames[q], w, !sample);
          ASSERT_EQ(fresh.evidence.last_query(), q);
          EXPECT_EQ(fresh.evidence.sequence_statistics().mean,
                    live.evidence.sequence_statistics().mean);
          if (!sample) {
            std::vector<Candidate> a, b;
            fresh.evidence.best_places(10, a);
            live.evidence.best_places(10, b);
            ASSERT_EQ(a.size(), b.size());
            for (std::size_t k = 0; k < a.size(); ++k) {
              EXPECT_EQ(a[k].frame, b[k].frame);
              EXPECT_EQ(a[k].score, b[k].score);  // bit for bit
            }
          }
          for (const std::int64_t j : {std::int64_t{0}, std::int64_t{q / 2}, std::int64_t{q - w - 1}}) {
            if (j < 0 || j >= q - w) continue;
            const double a = fresh.evidence.sequence(fresh.store, frames[q].view(), j,
                                                     SimilarityMetric::kReference);
            const double b = live.evidence.sequence(live.store, frames[q].view(), j,
                                                    SimilarityMetric::kReference);
            if (std::isnan(b)) {
              EXPECT_TRUE(std::isnan(a));
            } else {
              EXPECT_EQ(a, b) << q << " " << j;
            }
          }
        }
        live.store.add(frames[q]);
        fresh.store.add(frames[q]);
      }
    }
  }
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
