// The distractor frames of lsgd bench --distractors (bench_distractors.cc
// says how they are used).
#pragma once

#include <cstdint>
#include <istream>
#include <string>

#include "lsgd/descriptor.h"
#include "lsgd/detector.h"

namespace lsgd::cli::bench {

// Distractor k made from `base`, the exact descriptor of sequence frame k % M
// (M frames): its cells are shuffled (a random permutation: another spatial
// layout of the same kind of content) and each cell's histogram is moved by a
// random offset of -24 to +24 intensity levels (a lighting change; mass
// pushed past 0 or 255 stays at the end bin), with a generator seeded by
// k / run. So the `run` consecutive distractors of one run share their layout
// and lighting: a stretch of another place, as a camera would have stored it;
// with run 1 each distractor is its own place. Writes `exact` and `out` (as
// `storage` keeps it).
void make_distractor(const Descriptor& base, std::int64_t k, std::int64_t run,
                     HistogramStorage storage, Descriptor& exact, Descriptor& out);

// Memory a detector with `options` in search mode `mode` takes for `frames`
// stored frames of `cells` cells, bytes: lsgd::estimated_map_bytes() (each
// mode's memory model is its own, SearchMode::bytes_per_frame).
std::int64_t map_bytes(const std::string& mode, std::int64_t frames, int cells,
                       const DetectorOptions& options);

// MemAvailable of a /proc/meminfo text, bytes; -1 when it has none.
std::int64_t mem_available_bytes(std::istream& meminfo);
// What a cgroup v2 still lets this process take: memory.max less
// memory.current, bytes; -1 when unlimited or unreadable.
std::int64_t cgroup_room_bytes(std::istream& max, std::istream& current);
// The memory this process can still take on this machine: the smaller of
// MemAvailable and its cgroup's room; -1 when neither is known.
std::int64_t available_memory_bytes();

// Throws InvalidArgument when `need` bytes (a map of `frames` frames of
// `cells` cells in `options`' storage, and what the bench holds besides) are
// more than `available` (available_memory_bytes(); -1: unknown, no check),
// so a run too large for the machine is told at once instead of being killed
// at its end. `what` names the flag and value ("--frames 1000000000"); the
// message gives both sizes and, in exact storage, the compact storage's size.
void require_memory(const std::string& what, std::int64_t frames, int cells,
                    const DetectorOptions& options, std::int64_t need, std::int64_t available,
                    const std::string& fewer);

}  // namespace lsgd::cli::bench
