// Distractor frames: descriptors of places a map never saw, made from the
// descriptors of real frames, to measure a map at a size no dataset here
// reaches (`lsgd bench --distractors N`; docs/performance.md).
#pragma once

#include <cstdint>

#include "lsgd/descriptor.h"

namespace lsgd::eval {

// Distractor k made from `base`, the exact descriptor of sequence frame k % M
// (M frames): its cells are shuffled (a random permutation: another spatial
// layout of the same kind of content) and each cell's histogram is moved by a
// random offset of -24 to +24 intensity levels (a lighting change; mass
// pushed past 0 or 255 stays at the end bin), with a generator seeded by
// k / run. So the `run` consecutive distractors of one run share their layout
// and lighting: a stretch of another place, as a camera would have stored it;
// with run 1 each distractor is its own place. Writes `exact` and `out` (as
// `storage` keeps it). InvalidArgument for k < 0, run < 1 or a base that is
// not exact storage.
void make_distractor(const Descriptor& base, std::int64_t k, std::int64_t run,
                     HistogramStorage storage, Descriptor& exact, Descriptor& out);

}  // namespace lsgd::eval
