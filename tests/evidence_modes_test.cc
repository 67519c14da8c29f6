// The appearance evidence (include/lsgd/evidence.h) across its modes:
// exhaustive search beyond the exact-statistics limit scores as the sampled
// modes, every frame up to a limit then sampled, realigned shortlists and
// followed frames, and a rebuild that continues bit for bit.
#include "lsgd/evidence.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <opencv2/core.hpp>
#include <set>
#include <utility>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "evidence_test_support.h"
#include "test_util.h"

namespace lsgd {
namespace {

using evidence_test_support::EvidenceRun;
using evidence_test_support::frame;
using evidence_test_support::Reference;

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

}  // namespace
}  // namespace lsgd
