// Statistics that merge (issue 32; the fleet's shards, issue 34): the
// appearance evidence of a map split into k = 1, 2, 3 parts
// (AppearanceEvidence::set_parts), each part summarising its own frames'
// values, scores every query of a real sequence as the map in one part does,
// bit for bit: both levels of statistics over the map and by place, the
// prior of the young queries, single-frame and sequence scores, the best
// places (every frame scored) and the realigned shortlist (sampled
// diagonals). These are everything the decision reads from appearance, so
// the decision of a split map is the decision of one map.
#include "lsgd/evidence.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/io/sequence.h"
#include "evidence_test_support.h"

namespace lsgd {
namespace {

namespace fs = std::filesystem;

// The descriptors of the first `n` frames of a real sequence (exact storage).
std::vector<Descriptor> describe_sequence(const fs::path& list, std::size_t n) {
  DetectorOptions options;
  options.verification.stages = {};
  Detector detector(options);
  const io::Sequence seq = io::open_sequence(list.string());
  n = std::min(n, seq.images.size());
  for (std::size_t i = 0; i < n; ++i) detector.process(io::read_image(seq.images[i]));
  std::vector<Descriptor> out;
  const FrameStore& store = detector.store();
  for (std::int64_t f = 0; f < store.size(); ++f) {
    const DescriptorView v = store.view(f);
    Descriptor d;
    d.grid = store.grid();
    d.hist.assign(v.hist, v.hist + static_cast<std::size_t>(v.cells) * kBins);
    d.pixels.assign(v.pixels, v.pixels + v.cells);
    out.push_back(std::move(d));
  }
  return out;
}

void expect_same(const ScoreStatistics& a, const ScoreStatistics& b, const char* what, std::int64_t q) {
  ASSERT_EQ(a.count, b.count) << what << ", query " << q;
  ASSERT_EQ(a.mean, b.mean) << what << ", query " << q;
  ASSERT_EQ(a.sd, b.sd) << what << ", query " << q;
}

void expect_same(const std::vector<Candidate>& a, const std::vector<Candidate>& b, const char* what,
                 std::int64_t q) {
  ASSERT_EQ(a.size(), b.size()) << what << ", query " << q;
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].frame, b[k].frame) << what << ", query " << q << ", rank " << k;
    ASSERT_EQ(a[k].score, b[k].score) << what << ", query " << q << ", rank " << k;
  }
}

struct Split {
  const char* label;
  std::vector<std::int64_t> parts;  // AppearanceEvidence::set_parts
};

// Feeds every frame to one evidence per split and compares each query's
// scores with the first split's (one part).
void run_splits(const std::vector<Descriptor>& frames, std::int64_t w, bool sample,
                const std::vector<std::int64_t>& cuts, const std::vector<Split>& splits) {
  const SimilarityMetric metric = SimilarityMetric::kReference;
  SequenceOptions sequence;
  std::vector<AppearanceEvidence> evidence;
  for (const Split& split : splits) {
    evidence.emplace_back(sequence, w, sample);
    evidence.back().set_places(cuts);
    evidence.back().set_parts(split.parts);
  }
  FrameStore store;
  std::vector<double> row;
  std::vector<Candidate> raw, first, other;
  int young = 0, calibrated = 0;
  for (std::int64_t q = 0; q < static_cast<std::int64_t>(frames.size()); ++q) {
    const DescriptorView d = frames[static_cast<std::size_t>(q)].view();
    row.clear();
    for (std::int64_t j = 0; j < q - w; ++j) row.push_back(similarity(d, store.view(j), metric));
    for (AppearanceEvidence& e : evidence) {
      e.add_query(store, d, q, metric, e.sampled(q) ? nullptr : &row);
    }
    // The raw shortlist a sampled search would give: the best single frames.
    raw.clear();
    for (std::int64_t j = 0; j < q - w; ++j) raw.push_back({j, row[static_cast<std::size_t>(j)]});
    std::sort(raw.begin(), raw.end(), [](const Candidate& a, const Candidate& b) {
      return a.score > b.score || (a.score == b.score && a.frame < b.frame);
    });
    raw.resize(std::min<std::size_t>(raw.size(), 8));
    const AppearanceEvidence& one = evidence[0];
    young += one.young() ? 1 : 0;
    calibrated += one.similarity_statistics().valid() ? 1 : 0;
    for (std::size_t s = 0; s < evidence.size(); ++s) {
      SCOPED_TRACE(splits[s].label);
      AppearanceEvidence& e = evidence[s];
      ASSERT_EQ(e.young(), evidence[0].young()) << q;
      expect_same(e.similarity_statistics(), evidence[0].similarity_statistics(), "level 1", q);
      expect_same(e.sequence_statistics(), evidence[0].sequence_statistics(), "level 2", q);
      for (const Candidate& c : raw) {
        const double a = e.single_frame(c.score), b = evidence[0].single_frame(c.score);
        ASSERT_TRUE(a == b || (std::isnan(a) && std::isnan(b))) << "single frame, query " << q;
        const double sa = e.sequence(store, d, c.frame, metric);
        const double sb = evidence[0].sequence(store, d, c.frame, metric);
        ASSERT_TRUE(sa == sb || (std::isnan(sa) && std::isnan(sb))) << "sequence, query " << q;
      }
      if (!e.sampled(q)) {
        e.best_places(5, other);
        evidence[0].best_places(5, first);
        expect_same(other, first, "best places", q);
      } else {
        e.realign(store, d, raw, metric, 5, 0, other);
        evidence[0].realign(store, d, raw, metric, 5, 0, first);
        expect_same(other, first, "realigned", q);
      }
    }
    store.add(frames[static_cast<std::size_t>(q)]);
  }
  EXPECT_GT(young, 0);  // the prior was used ...
  EXPECT_GT(calibrated, static_cast<int>(frames.size()) / 2);  // ... and the queries' own statistics
}

TEST(EvidenceParts, RealMapsSplitIntoOneTwoOrThreePartsScoreAlike) {
  const fs::path root = fs::path(LSGD_SHARED_DIR) / "datasets";
  int sequences = 0;
  for (const char* name : {"corridor", "lip6-outdoor"}) {
    const fs::path list = root / name / "sequence.txt";
    if (!fs::is_regular_file(list)) continue;
    ++sequences;
    SCOPED_TRACE(name);
    // lip6-outdoor's 640 frames take the sampled mode past 512 diagonals
    // (stride 2); corridor is whole.
    const std::vector<Descriptor> frames = describe_sequence(list, 640);
    const auto n = static_cast<std::int64_t>(frames.size());
    const std::int64_t w = 20;
    const std::vector<Split> splits = {
        {"1 part", {}},
        {"2 parts", {n / 2}},
        {"3 parts", {n / 3, 2 * n / 3}},
        // Parts inside the young queries' candidates: the prior from 3 parts.
        {"3 small parts first", {4, 11}},
    };
    for (const bool sample : {false, true}) {
      for (const std::vector<std::int64_t>& cuts : {std::vector<std::int64_t>{},
                                                    std::vector<std::int64_t>{2 * n / 5, 7 * n / 10}}) {
        SCOPED_TRACE(testing::Message() << (sample ? "sampled" : "every frame scored") << ", "
                                        << cuts.size() + 1 << " places");
        run_splits(frames, w, sample, cuts, splits);
      }
    }
  }
  if (sequences == 0) {
    GTEST_SKIP() << "no real sequence under " << root << " (../shared is absent)";
  }
}

TEST(EvidenceParts, PartsMustBeginInOrderAfterFrameZero) {
  AppearanceEvidence e(SequenceOptions{}, 5, false);
  EXPECT_THROW(e.set_parts({0}), InvalidArgument);
  EXPECT_THROW(e.set_parts({10, 10}), InvalidArgument);
  EXPECT_THROW(e.set_parts({10, 4}), InvalidArgument);
  e.set_parts({4, 10});
  EXPECT_EQ(e.part_of(0), 0u);
  EXPECT_EQ(e.part_of(3), 0u);
  EXPECT_EQ(e.part_of(4), 1u);
  EXPECT_EQ(e.part_of(10), 2u);
  EXPECT_EQ(e.parts(), (std::vector<std::int64_t>{4, 10}));
}

}  // namespace
}  // namespace lsgd
