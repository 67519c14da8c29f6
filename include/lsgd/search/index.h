// Search mode "index": a navigable small-world graph (HNSW, hnswlib) over the
// stored frames outside the temporal window, so that a query reads a few
// thousand frames however large the map is; its shortlist is re-scored
// exactly, so only which frames are looked at is approximate, never a score.
//
// The graph's distance between two frames is 1/s - 1 for their similarity s
// (for the reference metric: the mean over cells of sqrt(L1)/256, a metric).
// The graph keeps only frame ids; distances read the descriptors from the
// detector's FrameStore, so a frame costs its descriptor plus the graph's
// links (about 4 * (2 M + 1) bytes on the bottom layer).
//
// A frame enters the graph when it leaves the temporal window (at query
// frame + min_gap + 1), so the window never crowds the shortlist. The graph
// is not saved: a detector restored from a database rebuilds it at its first
// query, from the stored descriptors (docs/performance.md states the cost).
#pragma once

#include <memory>

#include "lsgd/search.h"

namespace lsgd {

// The registered mode (SearchMode::make).
std::unique_ptr<CandidateSearch> make_index_search(const SearchOptions& options);

}  // namespace lsgd
