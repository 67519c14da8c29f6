// Distractor frames (include/lsgd/eval/distractors.h): what lsgd bench
// --distractors stores to measure a map at a size no dataset here reaches.
#include "lsgd/eval/distractors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/similarity.h"

namespace {

lsgd::Descriptor spiked_base() {
  lsgd::Descriptor d;
  d.grid = {3, 4};
  d.hist.assign(static_cast<std::size_t>(d.grid.cells()) * lsgd::kBins, 0);
  for (int c = 0; c < d.grid.cells(); ++c) {
    d.pixels.push_back(static_cast<lsgd::Count>(100 + c));
    d.hist[static_cast<std::size_t>(c) * lsgd::kBins + 40 + 15 * c] = static_cast<lsgd::Bin>(100 + c);
  }
  return d;
}

TEST(Distractor, ARunSharesOneLayoutAndLighting) {
  using lsgd::eval::make_distractor;
  const lsgd::Descriptor base = spiked_base();
  const auto make = [&](std::int64_t k, std::int64_t run) {
    lsgd::Descriptor exact, out;
    make_distractor(base, k, run, lsgd::HistogramStorage::kExact, exact, out);
    EXPECT_EQ(exact.hist, out.hist);
    return exact;
  };
  // Each cell is a whole cell of the base moved (mass kept), and not the
  // base itself.
  const lsgd::Descriptor d0 = make(0, 1);
  std::vector<lsgd::Count> sorted = d0.pixels;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(sorted, base.pixels);
  EXPECT_NE(d0.hist, base.hist);
  for (int c = 0; c < d0.grid.cells(); ++c) {
    std::uint32_t mass = 0;
    for (int b = 0; b < lsgd::kBins; ++b) mass += d0.hist[static_cast<std::size_t>(c) * lsgd::kBins + b];
    EXPECT_EQ(mass, d0.pixels[static_cast<std::size_t>(c)]) << c;
  }
  // Run 1: every distractor its own; distractor k of run R is what
  // distractor k / R is with run 1.
  EXPECT_NE(make(1, 1).hist, d0.hist);
  EXPECT_NE(make(1, 1).pixels, d0.pixels);
  for (std::int64_t k = 10; k < 15; ++k) {
    const lsgd::Descriptor d = make(k, 5);
    EXPECT_EQ(d.hist, make(2, 1).hist) << k;
    EXPECT_EQ(d.pixels, make(2, 1).pixels) << k;
  }
  EXPECT_NE(make(15, 5).hist, make(14, 5).hist);
  // Compact storage keeps the compacted exact distractor.
  lsgd::Descriptor exact, out, expected;
  make_distractor(base, 3, 1, lsgd::HistogramStorage::kCompact, exact, out);
  lsgd::compact(exact, expected);
  EXPECT_EQ(out.compact, expected.compact);
  EXPECT_TRUE(out.hist.empty());
  EXPECT_THROW(make_distractor(base, 3, 0, lsgd::HistogramStorage::kExact, exact, out),
               lsgd::InvalidArgument);
}

TEST(Distractor, ABaseThatIsNotAnExactDescriptorIsRefused) {
  lsgd::Descriptor exact, out, compacted;
  lsgd::Descriptor base = spiked_base();
  lsgd::compact(base, compacted);
  EXPECT_THROW(lsgd::eval::make_distractor(compacted, 0, 1, lsgd::HistogramStorage::kExact, exact, out),
               lsgd::InvalidArgument);
  EXPECT_THROW(lsgd::eval::make_distractor(base, -1, 1, lsgd::HistogramStorage::kExact, exact, out),
               lsgd::InvalidArgument);
  base.pixels.pop_back();
  EXPECT_THROW(lsgd::eval::make_distractor(base, 0, 1, lsgd::HistogramStorage::kExact, exact, out),
               lsgd::InvalidArgument);
  EXPECT_THROW(lsgd::eval::make_distractor(lsgd::Descriptor(), 0, 1, lsgd::HistogramStorage::kExact, exact, out),
               lsgd::InvalidArgument);
}

}  // namespace

// A distractor counts what its base counts: one of a gradient descriptor
// had no type ("") and was scored against intensity descriptors.
TEST(Distractor, KeepsWhatItsBaseCounts) {
  lsgd::Descriptor base = spiked_base(), intensity = spiked_base();
  base.type = "gradient (threshold 1.5, orientations 32)";
  intensity.type = "intensity";
  for (const auto storage : {lsgd::HistogramStorage::kExact, lsgd::HistogramStorage::kCompact}) {
    lsgd::Descriptor exact, out;
    lsgd::eval::make_distractor(base, 3, 1, storage, exact, out);
    EXPECT_EQ(exact.type, base.type);
    EXPECT_EQ(out.type, base.type);
    EXPECT_THROW(lsgd::similarity(out.view(), intensity.view(), lsgd::SimilarityMetric::kReference),
                 lsgd::InvalidArgument);
  }
}
