// Search mode "exhaustive": every stored frame outside the temporal window is
// scored against the query; the best top_n are the candidates.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "lsgd/search.h"

namespace lsgd {

// Keeps the top_n best candidates of all frames j < query - min_gap.
// `scratch` is reused between calls; the result is written best first. When
// `row` is given it receives every candidate's similarity, in frame order
// (row[j] for j < query - min_gap).
void search_exhaustive(const FrameStore& store, const DescriptorView& query, std::int64_t query_id,
                       const SearchOptions& options, SimilarityMetric metric,
                       std::vector<Candidate>& scratch, std::vector<Candidate>& out,
                       std::vector<double>* row = nullptr);

// The registered mode (SearchMode::make).
std::unique_ptr<CandidateSearch> make_exhaustive_search(const SearchOptions& options);
// Its memory per stored frame beyond the descriptor (SearchMode::bytes_per_frame):
// the sequence evidence's score rows, up to 8 bytes a frame for each of the
// last max(frames, long_frames) queries (1 without the temporal stage).
std::int64_t exhaustive_bytes_per_frame(const DetectorOptions& options, int cells);

}  // namespace lsgd
