// Helpers of the tests of the appearance evidence (evidence_test,
// evidence_modes_test): 2-cell frames along a repeating route, a brute-force
// reference of the evidence's definition, and an evidence fed query by query
// from a frame store. Header-only.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include "lsgd/evidence.h"
#include "lsgd/frame_store.h"
#include "lsgd/similarity.h"
#include "test_util.h"

namespace lsgd::evidence_test_support {

// 2-cell frames whose histograms drift along a route and repeat it: frame i
// shows place i % period with a little per-frame noise.
inline Descriptor frame(int i, int period) {
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

inline constexpr double kScale = 1024.0;

// The definition, computed directly: every similarity, every statistic.
struct Reference {
  std::vector<Descriptor> frames;
  std::int64_t min_gap;
  SequenceOptions options;
  bool sample;
  AppearanceEvidence stride_of{{}, 0, false};  // only for stride() / statistics_stride()
  // The places' first frames after the first (AppearanceEvidence::set_places).
  std::vector<std::int64_t> cuts;
  std::int64_t start_of(std::int64_t f) const {
    std::int64_t s = 0;
    for (const std::int64_t c : cuts) s = f >= c ? c : s;
    return s;
  }

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
  // Query q's level 1 over the candidates in the place that begins at `start`.
  ScoreStatistics level1_place(std::int64_t q, std::int64_t start) const {
    std::vector<double> v;
    for (std::int64_t j : sampled(q)) {
      if (start_of(j) == start) v.push_back(sim(q, j));
    }
    return statistics(v.data(), v.size());
  }
  std::int64_t z(std::int64_t a, std::int64_t b) const {
    if (a < 0 || b < 0) return 0;
    const ScoreStatistics s = level1(a);
    if (!s.valid()) return 0;
    double v = s.standardise(sim(a, b));
    if (!cuts.empty()) {  // the lower of the map's and the place's (0: a young place)
      const ScoreStatistics p = level1_place(a, start_of(b));
      v = std::min(v, p.valid() ? p.standardise(sim(a, b)) : 0.0);
    }
    return std::lround(std::clamp(v, -64.0, 64.0) * kScale);
  }
  // A(q, j): terms that do not exist count as 0, the divisor is the full length.
  double sequence_mean(std::int64_t q, std::int64_t j) const {
    std::int64_t a = 0, b = 0;
    const int steps = std::max(options.frames, options.long_frames);
    for (int t = 0; t < steps; ++t) {
      // With places, a pair before the place of either end counts 0.
      const bool across = q - t < start_of(q) || j - t < start_of(j);
      const std::int64_t v = across ? 0 : z(q - t, j - t);
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
    const double a = sequence_mean(q, j);
    if (cuts.empty()) return s.standardise(a);
    std::vector<double> mine;
    for (std::int64_t f : sampled(q)) {
      if (start_of(f) == start_of(j)) mine.push_back(sequence_mean(q, f));
    }
    const ScoreStatistics p = statistics(mine.data(), mine.size());
    if (!p.valid()) return std::min(0.0, s.standardise(a));
    return (a - std::max(p.mean, s.mean)) / std::max(p.sd, 0.5 * s.sd);
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

}  // namespace lsgd::evidence_test_support
