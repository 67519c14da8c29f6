#include "distractor.h"

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/search.h"
#include "lsgd/verification.h"

namespace lsgd::cli::bench {

std::int64_t map_bytes(const std::string& mode, std::int64_t frames, int cells,
                       const DetectorOptions& options) {
  DetectorOptions in_mode = options;
  in_mode.search.mode = mode;
  return estimated_map_bytes(in_mode, frames, cells);
}

std::int64_t mem_available_bytes(std::istream& meminfo) {
  std::string line;
  while (std::getline(meminfo, line)) {
    if (line.rfind("MemAvailable:", 0) != 0) continue;
    std::istringstream in(line.substr(13));
    std::int64_t kb = -1;
    std::string unit;
    if (in >> kb >> unit && kb >= 0 && unit == "kB") return kb * 1024;
    return -1;
  }
  return -1;
}

std::int64_t cgroup_room_bytes(std::istream& max, std::istream& current) {
  std::string limit;
  std::int64_t used = -1;
  if (!(max >> limit) || limit == "max" || !(current >> used) || used < 0) return -1;
  std::int64_t cap = -1;
  try {
    cap = std::stoll(limit);
  } catch (const std::exception&) {
    return -1;
  }
  return std::max<std::int64_t>(0, cap - used);
}

std::int64_t available_memory_bytes() {
  std::ifstream meminfo("/proc/meminfo");
  std::int64_t room = meminfo ? mem_available_bytes(meminfo) : -1;
  std::ifstream max("/sys/fs/cgroup/memory.max"), current("/sys/fs/cgroup/memory.current");
  if (max && current) {
    const std::int64_t cgroup = cgroup_room_bytes(max, current);
    if (cgroup >= 0) room = room < 0 ? cgroup : std::min(room, cgroup);
  }
  return room;
}

void require_memory(const std::string& what, std::int64_t frames, int cells,
                    const DetectorOptions& options, std::int64_t need, std::int64_t available,
                    const std::string& fewer) {
  if (available < 0 || need <= available) return;
  const auto gb = [](std::int64_t bytes) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(1) << static_cast<double>(bytes) / 1e9 << " GB";
    return out.str();
  };
  std::string advice = fewer;
  if (options.descriptor.storage == HistogramStorage::kExact) {
    advice = "--option descriptor.storage=compact (" +
             std::to_string(Descriptor::bytes_per_frame(HistogramStorage::kCompact, cells)) +
             " descriptor bytes a frame instead of " +
             std::to_string(Descriptor::bytes_per_frame(HistogramStorage::kExact, cells)) + ") or " + advice;
  }
  throw InvalidArgument(what + ": a map of " + std::to_string(frames) + " frames of " +
                        std::to_string(cells) + " cells in " + to_string(options.descriptor.storage) +
                        " storage needs about " + gb(need) + " of memory and " + gb(available) +
                        " is available (MemAvailable, and the cgroup's limit); use " + advice);
}

}  // namespace lsgd::cli::bench
