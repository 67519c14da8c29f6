// Helpers of the tests that run a detector over a sequence with revisits
// (database_test, query_test): the synthetic street and comparisons of
// results and of whole detector states. Header-only.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <opencv2/core.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/stage.h"
#include "synthetic/synthetic.h"

namespace lsgd::test {

// The synthetic street at 160x120, route_scale 0.3: 327 frames, the first
// revisit (A') from frame ~90.
inline const eval::SyntheticWorld& world() {
  static const eval::SyntheticWorld w([] {
    eval::SyntheticOptions o;
    o.width = 160;
    o.height = 120;
    o.route_scale = 0.3;
    return o;
  }());
  return w;
}

inline const cv::Mat& frame(std::int64_t i) {
  static std::vector<cv::Mat> frames(static_cast<std::size_t>(world().frames()));
  cv::Mat& f = frames[static_cast<std::size_t>(i)];
  if (f.empty()) f = world().render(i);
  return f;
}

// Everything a Result reports except timings.
inline void expect_same(const Result& a, const Result& b) {
  SCOPED_TRACE("frame " + std::to_string(a.frame));
  EXPECT_EQ(a.frame, b.frame);
  EXPECT_EQ(a.loop, b.loop);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.id, b.id);
  EXPECT_EQ(a.loop_id, b.loop_id);
  EXPECT_EQ(a.best.frame, b.best.frame);
  EXPECT_EQ(a.best.score, b.best.score);
  // NaN (no appearance) equals NaN.
  EXPECT_TRUE(a.evidence.appearance == b.evidence.appearance ||
              (a.evidence.appearance != a.evidence.appearance &&
               b.evidence.appearance != b.evidence.appearance))
      << a.evidence.appearance << " vs " << b.evidence.appearance;
  EXPECT_EQ(a.evidence.inliers, b.evidence.inliers);
  EXPECT_EQ(a.evidence.confirmed, b.evidence.confirmed);
  EXPECT_EQ(a.evidence.continues, b.evidence.continues);
  EXPECT_EQ(a.ranking.best.frame, b.ranking.best.frame);
  EXPECT_EQ(a.ranking.best.score, b.ranking.best.score);
  EXPECT_EQ(a.ranking.confirmed, b.ranking.confirmed);
  ASSERT_EQ(a.candidates.size(), b.candidates.size());
  for (std::size_t i = 0; i < a.candidates.size(); ++i) {
    EXPECT_EQ(a.candidates[i].frame, b.candidates[i].frame);
    EXPECT_EQ(a.candidates[i].score, b.candidates[i].score);
  }
  ASSERT_EQ(a.verification.size(), b.verification.size());
  for (std::size_t i = 0; i < a.verification.size(); ++i) {
    EXPECT_EQ(a.verification[i].candidate, b.verification[i].candidate);
    EXPECT_EQ(a.verification[i].stage, b.verification[i].stage);
    EXPECT_EQ(a.verification[i].accepted, b.verification[i].accepted);
    EXPECT_EQ(a.verification[i].reason, b.verification[i].reason);
  }
  EXPECT_EQ(a.node, b.node);
  EXPECT_EQ(a.node_created, b.node_created);
}

// The full state two detectors hold: descriptors, nodes, temporal places, features.
inline void expect_same_state(const Detector& a, const Detector& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.width(), b.width());
  EXPECT_EQ(a.height(), b.height());
  for (std::int64_t f = 0; f < a.size(); ++f) {
    const DescriptorView x = a.store().view(f), y = b.store().view(f);
    ASSERT_EQ(x.cells, y.cells);
    ASSERT_EQ(x.storage(), y.storage());
    if (x.storage() == HistogramStorage::kCompact) {
      ASSERT_TRUE(std::equal(x.compact, x.compact + x.cells * kCompactBins, y.compact))
          << "frame " << f;
      ASSERT_EQ(x.cell_pixels, y.cell_pixels);
      continue;
    }
    ASSERT_TRUE(std::equal(x.hist, x.hist + x.cells * kBins, y.hist)) << "frame " << f;
    ASSERT_TRUE(std::equal(x.pixels, x.pixels + x.cells, y.pixels)) << "frame " << f;
  }
  ASSERT_EQ(a.nodes(), b.nodes());
  EXPECT_EQ(a.store().groups(), b.store().groups());
  for (std::int64_t k = 0; k < a.nodes(); ++k) {
    EXPECT_EQ(a.search().members(k), b.search().members(k));
  }
  EXPECT_EQ(a.continuity().query, b.continuity().query);
  EXPECT_EQ(a.continuity().loop, b.continuity().loop);
  EXPECT_EQ(a.continuity().inliers, b.continuity().inliers);
  // Every component's state: nodes, temporal places, ORB features, loops.
  for (std::int64_t f = 0; f < a.size(); ++f) {
    ASSERT_EQ(a.frame_state(f), b.frame_state(f)) << "frame " << f;
  }
}

// A search mode and verification stages, min_gap 20 (the tests of every mode).
struct ModeCase {
  std::string mode;
  const char* stages;
  std::int64_t exhaustive_up_to = 8192;  // index mode: 0, the graph from the start
};

inline void PrintTo(const ModeCase& c, std::ostream* out) {
  *out << c.mode << " " << c.stages
       << (c.mode == kIndexSearch ? " exhaustive up to " + std::to_string(c.exhaustive_up_to) : "");
}

inline DetectorOptions options(const ModeCase& c) {
  DetectorOptions o;
  o.search.mode = c.mode;
  o.search.min_gap = 20;
  o.search.index.exhaustive_up_to = c.exhaustive_up_to;
  parse_verification_stages(c.stages, o.verification);
  return o;
}

// The search mode's saved index (index mode's graph), to compare two detectors'.
inline std::vector<std::uint8_t> index_of(const Detector& d) {
  std::vector<std::uint8_t> out;
  d.save_index(out);
  return out;
}

// A verification stage of one's own with per-frame state that says nothing
// of queries or of forgetting (answers_queries() and forgets() false):
// Detector::query() and forget() must refuse it by name. Registered as
// "test-remembering" by the tests that use it.
class Remembering final : public VerificationStage {
 public:
  const char* name() const override { return "test-remembering"; }
  Role role() const override { return Role::kGate; }
  bool has_state() const override { return true; }
  StageCheck check(std::int64_t, const Candidate&) override { return {true, -1, "ok", 0, nullptr}; }
  void end(std::int64_t query, const std::vector<Candidate>&) override { seen_.push_back(query); }
  void save_frame(std::int64_t frame, StateWriter& out) const override {
    out.put_i64(seen_.at(static_cast<std::size_t>(frame)));
  }

 private:
  std::vector<std::int64_t> seen_;
};

}  // namespace lsgd::test
