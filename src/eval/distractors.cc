#include "lsgd/eval/distractors.h"

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

#include "internal/check.h"

namespace lsgd::eval {
namespace {

std::uint64_t next(std::uint64_t& s) {  // splitmix64
  std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace

void make_distractor(const Descriptor& base, std::int64_t k, std::int64_t run, HistogramStorage storage,
                     Descriptor& exact, Descriptor& out) {
  if (run < 1) internal::throw_invalid("distractor run ", run, ": must be at least 1 frame");
  if (k < 0) internal::throw_invalid("distractor ", k, ": must be 0 or more");
  const auto cell_count = static_cast<std::size_t>(std::max(base.grid.cells(), 0));
  if (base.storage != HistogramStorage::kExact || cell_count == 0 ||
      base.hist.size() != cell_count * kBins || base.pixels.size() != cell_count) {
    internal::throw_invalid("distractor ", k, ": its base must be an exact descriptor (", base.grid.cells(),
                            " cells, ", base.hist.size(), " bins, ", base.pixels.size(), " cell sizes)");
  }
  std::uint64_t s = 0x5eed0000ull + static_cast<std::uint64_t>(k / run);
  const int cells = base.grid.cells();
  std::vector<int> order(static_cast<std::size_t>(cells));
  for (int c = 0; c < cells; ++c) order[static_cast<std::size_t>(c)] = c;
  for (int c = cells - 1; c > 0; --c) std::swap(order[static_cast<std::size_t>(c)], order[next(s) % (c + 1)]);
  exact.grid = base.grid;
  exact.storage = HistogramStorage::kExact;
  // What its bins count is its base's: a distractor of a gradient
  // descriptor had none ("") and was scored against intensity descriptors.
  exact.type = base.type;
  exact.hist.assign(base.hist.size(), 0);
  exact.pixels = base.pixels;
  for (int c = 0; c < cells; ++c) {
    const int from = order[static_cast<std::size_t>(c)];
    const int shift = static_cast<int>(next(s) % 49) - 24;
    exact.pixels[static_cast<std::size_t>(c)] = base.pixels[static_cast<std::size_t>(from)];
    Bin* to = &exact.hist[static_cast<std::size_t>(c) * kBins];
    const Bin* src = &base.hist[static_cast<std::size_t>(from) * kBins];
    for (int b = 0; b < kBins; ++b) {
      const int t = std::clamp(b + shift, 0, kBins - 1);
      to[t] = static_cast<Bin>(std::min<int>(65535, to[t] + src[b]));
    }
  }
  if (storage == HistogramStorage::kCompact) {
    compact(exact, out);  // keeps the type
  } else {
    out = exact;
  }
}

}  // namespace lsgd::eval
