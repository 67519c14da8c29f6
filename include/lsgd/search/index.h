// Search mode "index": a navigable small-world graph (HNSW, hnswlib) over the
// stored frames outside the temporal window, so that a query reads a few
// thousand small keys however large the map is; its shortlist is re-scored
// exactly, so only which frames are looked at is approximate, never a score.
//
// The graph holds a key per frame: each cell's histogram pooled into 16 bins
// of 16 intensities, normalised to 255 (16 bytes a cell: 1,280 bytes for a
// 1241x376 frame at 80 cells, an eighth of its compact descriptor), with the
// distance sum_k sqrt(SAD_k) (a metric; the reference metric's form; sum_k
// SAD_k for the L1 metrics). A frame costs its descriptor in the FrameStore
// plus its key and links in the graph (about 16 cells + 4 (2 M + 1) + 8
// bytes on the bottom layer, and hnswlib's per-frame lock and label entry).
//
// A frame enters the graph when it leaves the temporal window (at query
// frame + min_gap + 1), so the window never crowds the shortlist. The
// graph's `rescore` (64) nearest keys are re-scored exactly; the best
// `shortlist` (10) of them, and the previous frame's top_n places one frame
// on, are realigned by the temporal stage to the places exhaustive search
// would rank; its next `follow` (22) places are followed one frame on along
// their diagonals, their sequence only, and realigned when one would rank
// among the top_n (AppearanceEvidence::realign). The graph is saved whole in
// the place database (Database::save_index) and restored without a rebuild;
// without a saved graph, a restored detector rebuilds it from the stored
// descriptors at its first query.
#pragma once

#include <memory>

#include "lsgd/search.h"

namespace lsgd {

// The registered mode (SearchMode::make).
std::unique_ptr<CandidateSearch> make_index_search(const SearchOptions& options);
// Its memory per stored frame beyond the descriptor (SearchMode::bytes_per_frame):
// the graph's key (16 bytes a cell), its bottom-layer links (2 M of 4
// bytes) and hnswlib's bookkeeping (64 bytes), as measured (docs/performance.md).
std::int64_t index_bytes_per_frame(const DetectorOptions& options, int cells);

}  // namespace lsgd
