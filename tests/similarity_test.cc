// Tests of the descriptor similarities (include/lsgd/similarity.h): the
// reference formula, the paper's L1 and the normalised L1, compared against
// hand computations, plus the general properties every metric must have.
#include "lsgd/similarity.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/error.h"
#include "lsgd/limits.h"
#include "lsgd/image.h"
#include "lsgd/segmentation.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::message_of;
using test::random_image;
using test::splitmix64;

const SimilarityMetric kMetrics[] = {SimilarityMetric::kReference, SimilarityMetric::kL1,
                                     SimilarityMetric::kNormalizedL1};

// Exact descriptor of one row of cells, each given as (bin, count) pairs.
constexpr auto make = test::make_descriptor;

// Random descriptor: `cells` cells, each with a random pixel count in
// [min_pixels, max_pixels] spread over random bins.
Descriptor random_descriptor(int cells, std::uint64_t seed, int min_pixels = 50,
                             int max_pixels = 400) {
  std::uint64_t s = seed;
  Descriptor d;
  d.grid = {1, cells};
  d.hist.assign(static_cast<std::size_t>(cells) * kBins, 0);
  d.pixels.assign(cells, 0);
  for (int k = 0; k < cells; ++k) {
    const int n = min_pixels + static_cast<int>(splitmix64(s) % (max_pixels - min_pixels + 1));
    const int centre = static_cast<int>(splitmix64(s) % 256);
    for (int i = 0; i < n; ++i) {
      const int bin = (centre + static_cast<int>(splitmix64(s) % 40)) % 256;
      ++d.hist[static_cast<std::size_t>(k) * kBins + bin];
    }
    d.pixels[k] = static_cast<Count>(n);
  }
  return d;
}

std::uint64_t cell_l1(const Descriptor& a, const Descriptor& b, int k) {
  std::uint64_t sum = 0;
  for (int i = 0; i < kBins; ++i) {
    const std::int64_t d = static_cast<std::int64_t>(a.hist[k * kBins + i]) - b.hist[k * kBins + i];
    sum += static_cast<std::uint64_t>(d < 0 ? -d : d);
  }
  return sum;
}

// Independent implementations of the three documented formulas.
double expected(const Descriptor& a, const Descriptor& b, SimilarityMetric metric) {
  const int cells = a.grid.cells();
  switch (metric) {
    case SimilarityMetric::kReference: {
      double sum = 0;
      for (int k = 0; k < cells; ++k)
        sum += std::sqrt(static_cast<double>(cell_l1(a, b, k))) / 256.0;
      return 1.0 / (1.0 + sum / cells);
    }
    case SimilarityMetric::kL1: {
      double l1 = 0, mass = 0;
      for (int k = 0; k < cells; ++k) {
        l1 += static_cast<double>(cell_l1(a, b, k));
        mass += static_cast<double>(a.pixels[k]) + b.pixels[k];
      }
      return mass == 0 ? 1.0 : 1.0 - l1 / mass;
    }
    case SimilarityMetric::kNormalizedL1: {
      double sum = 0;
      for (int k = 0; k < cells; ++k) {
        const double na = a.pixels[k], nb = b.pixels[k];
        if (na == 0 || nb == 0) {
          sum += (na == nb) ? 0.0 : 2.0;
          continue;
        }
        for (int i = 0; i < kBins; ++i) {
          sum += std::fabs(a.hist[k * kBins + i] / na - b.hist[k * kBins + i] / nb);
        }
      }
      return 1.0 - sum / (2.0 * cells);
    }
  }
  return -1;
}

TEST(Similarity, IdenticalDescriptorsScoreExactlyOne) {
  for (int trial = 0; trial < 5; ++trial) {
    const Descriptor d = random_descriptor(12, 100 + trial);
    for (SimilarityMetric m : kMetrics) {
      SCOPED_TRACE(to_string(m));
      EXPECT_EQ(similarity(d.view(), d.view(), m), 1.0);
      const Descriptor copy = d;
      EXPECT_EQ(similarity(d.view(), copy.view(), m), 1.0);
    }
  }
}

TEST(Similarity, IdenticalRealImageDescriptorsScoreOne) {
  const GrayImage img = random_image(96, 64, 5);
  SegmentationOptions o;
  o.superpixel_size = 10;
  Segmenter seg(o);
  const Descriptor d = describe(img, seg.segment(img));
  for (SimilarityMetric m : kMetrics) EXPECT_EQ(similarity(d.view(), d.view(), m), 1.0);
}

TEST(Similarity, ScoresInUnitIntervalAndSymmetric) {
  for (int trial = 0; trial < 20; ++trial) {
    const Descriptor a = random_descriptor(8, 1000 + trial);
    const Descriptor b = random_descriptor(8, 2000 + trial);
    for (SimilarityMetric m : kMetrics) {
      SCOPED_TRACE(to_string(m));
      const double ab = similarity(a.view(), b.view(), m);
      const double ba = similarity(b.view(), a.view(), m);
      EXPECT_GE(ab, 0.0);
      EXPECT_LE(ab, 1.0);
      EXPECT_EQ(ab, ba);
      EXPECT_NEAR(ab, expected(a, b, m), 1e-12);
      EXPECT_LT(ab, 1.0);  // different descriptors
    }
  }
}

TEST(Similarity, ExtremesStayInRange) {
  // Disjoint histograms: L1 and normalised L1 reach 0, the reference stays positive.
  const Descriptor a = make({{{0, 1000}}, {{10, 500}}});
  const Descriptor b = make({{{255, 1000}}, {{200, 500}}});
  EXPECT_EQ(similarity(a.view(), b.view(), SimilarityMetric::kL1), 0.0);
  EXPECT_EQ(similarity(a.view(), b.view(), SimilarityMetric::kNormalizedL1), 0.0);
  const double ref = similarity(a.view(), b.view(), SimilarityMetric::kReference);
  EXPECT_GT(ref, 0.0);
  EXPECT_LT(ref, 1.0);
  // Full (saturated) bins do not overflow.
  const Descriptor big_a = make({{{0, 65535u}}});
  const Descriptor big_b = make({{{1, 65535u}}});
  for (SimilarityMetric m : kMetrics) {
    const double s = similarity(big_a.view(), big_b.view(), m);
    EXPECT_GE(s, 0.0) << to_string(m);
    EXPECT_LE(s, 1.0) << to_string(m);
  }
  EXPECT_EQ(similarity(big_a.view(), big_b.view(), SimilarityMetric::kL1), 0.0);
}

TEST(Similarity, ReferenceHandComputedTwoCells) {
  // Cell 0: a = {bin 10: 4, bin 20: 6}, b = {bin 10: 1, bin 30: 9}
  //   L1_0 = |4-1| + |6-0| + |0-9| = 18.
  // Cell 1: a = {bin 0: 50}, b = {bin 0: 50, bin 1: 50}: L1_1 = 50.
  const Descriptor a = make({{{10, 4}, {20, 6}}, {{0, 50}}});
  const Descriptor b = make({{{10, 1}, {30, 9}}, {{0, 50}, {1, 50}}});
  const double d0 = std::sqrt(18.0) / 256.0;
  const double d1 = std::sqrt(50.0) / 256.0;
  const double want = 1.0 / (1.0 + (d0 + d1) / 2.0);
  EXPECT_NEAR(similarity(a.view(), b.view(), SimilarityMetric::kReference), want, 1e-15);
  // Numerically: (4.2426 + 7.0711) / 512 = 0.022097, 1 / 1.022097 = 0.978381.
  EXPECT_NEAR(similarity(a.view(), b.view(), SimilarityMetric::kReference), 0.978381, 1e-6);
}

TEST(Similarity, L1HandComputed) {
  // Same example: L1 = 18 + 50 = 68, masses 10 + 10 + 50 + 100 = 170.
  const Descriptor a = make({{{10, 4}, {20, 6}}, {{0, 50}}});
  const Descriptor b = make({{{10, 1}, {30, 9}}, {{0, 50}, {1, 50}}});
  EXPECT_NEAR(similarity(a.view(), b.view(), SimilarityMetric::kL1), 1.0 - 68.0 / 170.0, 1e-15);
  // For frames of one size: 1 - L1 / (2 * pixels).
  const Descriptor c = make({{{0, 30}, {1, 70}}});
  const Descriptor e = make({{{0, 70}, {1, 30}}});
  EXPECT_NEAR(similarity(c.view(), e.view(), SimilarityMetric::kL1), 1.0 - 80.0 / 200.0, 1e-15);
}

TEST(Similarity, NormalizedL1HandComputed) {
  // Cell 0: a = {0: 1, 1: 3} -> (0.25, 0.75); b = {0: 2, 1: 2} -> (0.5, 0.5): L1 = 0.5.
  // Cell 1: a = {5: 10}, b = {5: 1000}: same shape, L1 = 0.
  // score = 1 - (0.5 + 0) / (2 * 2) = 0.875.
  const Descriptor a = make({{{0, 1}, {1, 3}}, {{5, 10}}});
  const Descriptor b = make({{{0, 2}, {1, 2}}, {{5, 1000}}});
  EXPECT_NEAR(similarity(a.view(), b.view(), SimilarityMetric::kNormalizedL1), 0.875, 1e-15);
  // Scale invariance: a histogram and a multiple of it are identical.
  const Descriptor c = make({{{3, 2}, {9, 5}}});
  const Descriptor d = make({{{3, 20}, {9, 50}}});
  EXPECT_NEAR(similarity(c.view(), d.view(), SimilarityMetric::kNormalizedL1), 1.0, 1e-15);
  EXPECT_LT(similarity(c.view(), d.view(), SimilarityMetric::kL1), 1.0);
}

TEST(Similarity, NormalizedL1EmptyCells) {
  // Empty vs empty counts as identical.
  const Descriptor a = make({{}, {{7, 10}}});
  const Descriptor b = make({{}, {{7, 3}}});
  EXPECT_EQ(similarity(a.view(), b.view(), SimilarityMetric::kNormalizedL1), 1.0);
  // Empty vs non-empty counts as maximally different (L1 = 2).
  const Descriptor c = make({{{0, 5}}, {{7, 10}}});
  EXPECT_NEAR(similarity(a.view(), c.view(), SimilarityMetric::kNormalizedL1), 1.0 - 2.0 / 4.0,
              1e-15);
  EXPECT_NEAR(similarity(c.view(), a.view(), SimilarityMetric::kNormalizedL1), 0.5, 1e-15);
  // All cells empty on both sides.
  const Descriptor e = make({{}, {}});
  EXPECT_EQ(similarity(e.view(), e.view(), SimilarityMetric::kNormalizedL1), 1.0);
  // The other metrics are also defined on empty descriptors.
  EXPECT_EQ(similarity(e.view(), e.view(), SimilarityMetric::kL1), 1.0);
  EXPECT_EQ(similarity(e.view(), e.view(), SimilarityMetric::kReference), 1.0);
}

TEST(Similarity, MetricsMatchIndependentImplementationOnVariedMasses) {
  for (int trial = 0; trial < 10; ++trial) {
    Descriptor a = random_descriptor(6, 3000 + trial, 0, 60);
    Descriptor b = random_descriptor(6, 4000 + trial, 0, 60);
    for (SimilarityMetric m : kMetrics) {
      EXPECT_NEAR(similarity(a.view(), b.view(), m), expected(a, b, m), 1e-12) << to_string(m);
    }
  }
}

// The reference metric of compact descriptors, by hand: SADs scaled to
// pixels with the mean cell size, added in cell order.
double expected_compact_reference(const Descriptor& a, const Descriptor& b) {
  const int cells = a.grid.cells();
  const double scale = 0.5 * (a.cell_pixels + b.cell_pixels) / kCompactMass;
  double sum = 0;
  for (int k = 0; k < cells; ++k) {
    std::uint32_t sad = 0;
    for (int i = 0; i < kCompactBins; ++i) {
      const std::size_t at = static_cast<std::size_t>(k) * kCompactBins + i;
      sad += static_cast<std::uint32_t>(std::abs(a.compact[at] - b.compact[at]));
    }
    sum += std::sqrt(sad * scale) / 256.0;
  }
  return 1.0 / (1.0 + sum / cells);
}

// similarities() scores frames several at a time (interleaved sums, SIMD
// per-cell distances); every score must still be the in-order formula, bit
// for bit: 200 cells span two of its 128-cell blocks, and 0..9 frames cover
// full and partial groups.
TEST(Similarities, BatchIsBitIdenticalToTheInOrderFormulaInBothStorages) {
  const int cells = 200;
  const Descriptor query = random_descriptor(cells, 77, 0, 3000);
  std::vector<Descriptor> frames;
  for (int i = 0; i < 9; ++i) frames.push_back(random_descriptor(cells, 500 + i, 0, 3000));
  Descriptor cquery;
  compact(query, cquery);
  std::vector<Descriptor> cframes(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) compact(frames[i], cframes[i]);
  for (const bool is_compact : {false, true}) {
    SCOPED_TRACE(is_compact ? "compact" : "exact");
    const Descriptor& q = is_compact ? cquery : query;
    const std::vector<Descriptor>& fs = is_compact ? cframes : frames;
    std::vector<DescriptorView> views;
    for (const Descriptor& f : fs) views.push_back(f.view());
    for (std::size_t count = 0; count <= views.size(); ++count) {
      for (SimilarityMetric m : kMetrics) {
        std::vector<double> got(count + 1, -1.0);
        similarities(q.view(), views.data(), count, m, got.data());
        EXPECT_EQ(got[count], -1.0) << "wrote past count";
        for (std::size_t i = 0; i < count; ++i) {
          EXPECT_EQ(got[i], similarity(q.view(), views[i], m)) << to_string(m) << " " << i;
          if (m != SimilarityMetric::kReference) continue;
          const double by_hand =
              is_compact ? expected_compact_reference(q, fs[i]) : expected(q, fs[i], m);
          EXPECT_EQ(got[i], by_hand) << "frame " << i << " of " << count;
        }
      }
    }
  }
}

TEST(Similarities, MismatchedFrameThrowsBeforeWritingAnything) {
  const Descriptor q = random_descriptor(6, 1);
  const Descriptor good = random_descriptor(6, 2);
  const Descriptor other = random_descriptor(7, 3);
  Descriptor packed;
  compact(good, packed);
  for (const Descriptor* bad : {&other, static_cast<const Descriptor*>(&packed)}) {
    const DescriptorView views[] = {good.view(), good.view(), bad->view()};
    double out[3] = {-1, -1, -1};
    const std::string what = message_of<InvalidArgument>(
        [&] { similarities(q.view(), views, 3, SimilarityMetric::kReference, out); });
    EXPECT_NE(what.find("similarities"), std::string::npos) << what;
    EXPECT_EQ(out[0], -1);
    EXPECT_EQ(out[1], -1);
  }
}

TEST(Similarity, DifferentCellCountsThrow) {
  const Descriptor a = random_descriptor(4, 1);
  const Descriptor b = random_descriptor(5, 2);
  for (SimilarityMetric m : kMetrics) {
    EXPECT_THROW(similarity(a.view(), b.view(), m), InvalidArgument) << to_string(m);
    EXPECT_THROW(similarity(b.view(), a.view(), m), InvalidArgument) << to_string(m);
  }
  // Zero cells is rejected too.
  const DescriptorView empty{};
  EXPECT_THROW(similarity(empty, empty, SimilarityMetric::kReference), InvalidArgument);
}

TEST(Similarity, UnknownMetricThrows) {
  const Descriptor a = random_descriptor(2, 1);
  EXPECT_THROW(similarity(a.view(), a.view(), static_cast<SimilarityMetric>(17)), InvalidArgument);
  SimilarityOptions o;
  o.metric = static_cast<SimilarityMetric>(17);
  EXPECT_THROW(o.check(), InvalidArgument);
}

TEST(SimilarityMetricNames, RoundTrip) {
  for (SimilarityMetric m : kMetrics) {
    EXPECT_EQ(parse_similarity_metric(to_string(m)), m);
  }
  EXPECT_STREQ(to_string(SimilarityMetric::kReference), "reference");
  EXPECT_STREQ(to_string(SimilarityMetric::kL1), "l1");
  EXPECT_STREQ(to_string(SimilarityMetric::kNormalizedL1), "normalized_l1");
}

TEST(SimilarityMetricNames, RejectsUnknown) {
  EXPECT_THROW(parse_similarity_metric("foo"), InvalidArgument);
  EXPECT_THROW(parse_similarity_metric(""), InvalidArgument);
  EXPECT_THROW(parse_similarity_metric("L1"), InvalidArgument);
  EXPECT_THROW(parse_similarity_metric("reference "), InvalidArgument);
  const std::string msg = message_of<InvalidArgument>([] { parse_similarity_metric("foo"); });
  EXPECT_NE(msg.find("foo"), std::string::npos) << msg;
}

TEST(SimilarityOptions, DefaultIsReference) {
  SimilarityOptions o;
  EXPECT_EQ(o.metric, SimilarityMetric::kReference);
  EXPECT_NO_THROW(o.check());
  for (SimilarityMetric m : kMetrics) {
    o.metric = m;
    EXPECT_NO_THROW(o.check());
  }
}

// match_top_k (lsgd match, Python lsgd.match): each query's best reference
// frames by similarity, ties by lower index, scored in sigma of the query's
// similarities to the whole reference.
TEST(MatchTopK, BestFirstTiesByIndexScoresInSigma) {
  std::vector<Descriptor> refs;
  for (int i = 0; i < 6; ++i) refs.push_back(random_descriptor(8, 500 + i));
  refs.push_back(refs[2]);  // a tie with frame 2
  const std::vector<Descriptor> queries = {refs[2], refs[4]};
  std::vector<DescriptorView> r, q;
  for (const Descriptor& d : refs) r.push_back(d.view());
  for (const Descriptor& d : queries) q.push_back(d.view());
  const std::vector<TopMatch> m = match_top_k(r, q, 3, SimilarityMetric::kReference, 100);
  ASSERT_EQ(m.size(), 6u);
  EXPECT_EQ(m[0].query, 100);
  EXPECT_EQ(m[0].match, 2);
  EXPECT_EQ(m[1].match, 6);  // the same similarity: after the lower index
  EXPECT_EQ(m[0].similarity, 1.0);
  EXPECT_EQ(m[1].similarity, 1.0);
  EXPECT_EQ(m[2].rank, 3);
  EXPECT_GE(m[1].similarity, m[2].similarity);
  EXPECT_EQ(m[3].query, 101);
  EXPECT_EQ(m[3].match, 4);
  std::vector<double> s;
  for (const DescriptorView& v : r) s.push_back(similarity(q[1], v, SimilarityMetric::kReference));
  double mean = 0, var = 0;
  for (const double v : s) mean += v / static_cast<double>(s.size());
  for (const double v : s) var += (v - mean) * (v - mean) / static_cast<double>(s.size());
  EXPECT_NEAR(m[3].score, (1.0 - mean) / std::sqrt(var), 1e-12);
  // k beyond the reference: every frame once.
  EXPECT_EQ(match_top_k(r, q, 50, SimilarityMetric::kReference).size(), 2 * r.size());
  EXPECT_THROW(match_top_k(r, q, 0, SimilarityMetric::kReference), InvalidArgument);
  EXPECT_THROW(match_top_k(r, q, kMaxTopK + 1, SimilarityMetric::kReference), InvalidArgument);
  EXPECT_THROW(match_top_k(r, q, 1, SimilarityMetric::kReference, -1), InvalidArgument);
  EXPECT_THROW(match_top_k(r, q, 1, SimilarityMetric::kReference, kMaxFrameId), InvalidArgument);
  EXPECT_EQ(match_top_k(r, q, 1, SimilarityMetric::kReference,
                        kMaxFrameId - static_cast<std::int64_t>(q.size())).back().query, kMaxFrameId - 1);
  EXPECT_THROW(match_top_k({}, q, 1, SimilarityMetric::kReference), InvalidArgument);
  const Descriptor other = random_descriptor(4, 9);
  EXPECT_THROW(match_top_k(r, {other.view()}, 1, SimilarityMetric::kReference), InvalidArgument);
}

// Descriptors that count different things (Descriptor::type) are refused by
// the C++ functions over views too, as by Python's lsgd.similarity and
// lsgd.match: the view carries the type (issue 35, seventh pass; only
// Python checked it, so C++ callers scored gradient against intensity).
TEST(MatchTopK, DescriptorsThatCountDifferentThingsAreRefused) {
  Descriptor intensity = random_descriptor(8, 1);
  Descriptor gradient = random_descriptor(8, 2);
  Descriptor unknown = random_descriptor(8, 3);  // built by hand: taken as it comes
  intensity.type = "intensity";
  gradient.type = "gradient (threshold 1.5, orientations 32)";
  EXPECT_STREQ(intensity.view().type, "intensity");
  EXPECT_EQ(unknown.view().type, nullptr);
  for (const SimilarityMetric metric : kMetrics) {
    const std::string m = message_of<InvalidArgument>([&] { similarity(intensity.view(), gradient.view(), metric); });
    EXPECT_NE(m.find("count different things (intensity and gradient (threshold 1.5"), std::string::npos) << m;
    EXPECT_NO_THROW(similarity(intensity.view(), unknown.view(), metric));
    double out[2];
    const DescriptorView frames[2] = {unknown.view(), gradient.view()};
    EXPECT_THROW(similarities(intensity.view(), frames, 2, metric, out), InvalidArgument);
  }
  // A reference mixing two kinds is refused even for a query of unknown
  // type, which each reference alone would accept.
  const std::vector<DescriptorView> mixed = {intensity.view(), gradient.view()};
  const std::string m = message_of<InvalidArgument>([&] { match_top_k(mixed, {unknown.view()}, 1, SimilarityMetric::kReference); });
  EXPECT_NE(m.find("match: the descriptors count different things"), std::string::npos) << m;
  EXPECT_THROW(match_top_k({intensity.view()}, {gradient.view()}, 1, SimilarityMetric::kReference),
               InvalidArgument);
  EXPECT_EQ(match_top_k({intensity.view(), unknown.view()}, {intensity.view()}, 2, SimilarityMetric::kReference)
                .size(), 2u);
}

}  // namespace
}  // namespace lsgd
