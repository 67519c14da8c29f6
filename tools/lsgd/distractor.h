// The map planning of lsgd bench --distractors (bench_distractors.cc says
// how the distractors are used; eval/distractors.h makes them).
#pragma once

#include <cstdint>
#include <istream>
#include <string>

#include "lsgd/descriptor.h"
#include "lsgd/detector.h"
#include "lsgd/eval/distractors.h"

namespace lsgd::cli::bench {

// Distractor frames: lsgd/eval/distractors.h.
using eval::make_distractor;

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
