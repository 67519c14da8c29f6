// Helpers of the tests of candidate search (search_test, search_index_test,
// search_nodes_test): descriptors on a line and random ones, a store of
// frames, a brute-force search, candidate lists compared, and the index run
// frame by frame. Header-only.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/frame_store.h"
#include "lsgd/search.h"
#include "lsgd/similarity.h"
#include "test_util.h"

namespace lsgd::search_test_support {

using test::splitmix64;

// A 1-cell descriptor on a line: `mass - t` pixels in bin 0 and `t` in bin 1.
// With the L1 metric, sim(t_a, t_b) = 1 - 2 |t_a - t_b| / (2 mass) = 1 - |t_a - t_b| / mass.
inline Descriptor line_descriptor(int t, int mass = 100) {
  Descriptor d;
  d.grid = {1, 1};
  d.hist.assign(kBins, 0);
  d.hist[0] = static_cast<Bin>(mass - t);
  d.hist[1] = static_cast<Bin>(t);
  d.pixels = {static_cast<Count>(mass)};
  return d;
}

inline Descriptor random_descriptor(int cells, std::uint64_t seed) {
  std::uint64_t s = seed;
  Descriptor d;
  d.grid = {2, cells / 2};
  d.hist.assign(static_cast<std::size_t>(d.grid.cells()) * kBins, 0);
  d.pixels.assign(d.grid.cells(), 0);
  for (int k = 0; k < d.grid.cells(); ++k) {
    const int n = 100;
    const int centre = static_cast<int>(splitmix64(s) % 200);
    for (int i = 0; i < n; ++i) {
      ++d.hist[static_cast<std::size_t>(k) * kBins + centre + splitmix64(s) % 50];
    }
    d.pixels[k] = n;
  }
  return d;
}

inline FrameStore store_of(const std::vector<Descriptor>& frames) {
  FrameStore store;
  for (const Descriptor& d : frames) store.add(d);
  return store;
}

inline std::vector<Candidate> brute_force(const FrameStore& store, const DescriptorView& query,
                                          std::int64_t query_id, std::int64_t min_gap, int top_n,
                                          SimilarityMetric metric) {
  std::vector<Candidate> all;
  for (std::int64_t j = 0; j < store.size(); ++j) {
    if (j < query_id - min_gap) all.push_back({j, similarity(query, store.view(j), metric)});
  }
  std::sort(all.begin(), all.end(), [](const Candidate& a, const Candidate& b) {
    return a.score > b.score || (a.score == b.score && a.frame < b.frame);
  });
  if (all.size() > static_cast<std::size_t>(top_n)) all.resize(top_n);
  return all;
}

inline void expect_same(const std::vector<Candidate>& got, const std::vector<Candidate>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].frame, want[i].frame) << "rank " << i;
    EXPECT_EQ(got[i].score, want[i].score) << "rank " << i;
  }
}

// Runs the index over frames stored one by one, as the detector does, and
// returns each query's candidates.
inline std::vector<std::vector<Candidate>> run_index(const std::vector<Descriptor>& frames,
                                                     const SearchOptions& o,
                                                     SimilarityMetric metric) {
  const std::unique_ptr<CandidateSearch> index = make_search(o);
  FrameStore store;
  std::vector<std::vector<Candidate>> all;
  std::vector<Candidate> out;
  std::vector<double> row;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    index->search({store, frames[i].view(), static_cast<std::int64_t>(i), metric}, out, row);
    all.push_back(out);
    index->end(static_cast<std::int64_t>(i), {});
    store.add(frames[i]);
  }
  return all;
}

}  // namespace lsgd::search_test_support
