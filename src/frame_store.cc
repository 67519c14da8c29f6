#include "lsgd/frame_store.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>

#ifdef __linux__
#include <sys/mman.h>
#endif

#include "internal/check.h"

namespace lsgd {
namespace {

// Makes room for `more` elements with geometric growth (reserve(size + more)
// alone would reallocate on every call).
template <typename T>
void grow(std::vector<T>& v, std::size_t more) {
  if (v.capacity() - v.size() >= more) return;
  v.reserve(std::max(v.size() + more, 2 * v.capacity()));
}

constexpr std::size_t kHugePage = std::size_t{2} << 20;

}  // namespace

void FrameStore::FreeArena::operator()(std::byte* p) const { std::free(p); }

FrameStore::Arena FrameStore::allocate_arena(std::size_t bytes) {
  bytes = (bytes + kHugePage - 1) / kHugePage * kHugePage;  // aligned_alloc needs a multiple
  void* p = std::aligned_alloc(kHugePage, bytes);
  if (p == nullptr) throw std::bad_alloc();
#ifdef __linux__
  madvise(p, bytes, MADV_HUGEPAGE);  // a hint: without huge pages it is just slower
#endif
  Arena arena;
  arena.data.reset(static_cast<std::byte*>(p));
  arena.size = bytes;
  return arena;
}

std::size_t FrameStore::frame_bytes() const {
  const auto cells = static_cast<std::size_t>(grid_.cells());
  return storage_ == HistogramStorage::kCompact ? cells * kCompactBins * sizeof(CompactBin)
                                                : cells * kBins * sizeof(Bin);
}

FrameStore::FrameStore(const FrameStore& other)
    : grid_(other.grid_),
      storage_(other.storage_),
      cell_pixels_(other.cell_pixels_),
      max_chunk_frames_(other.max_chunk_frames_),
      chunks_(other.chunks_),
      slots_(other.slots_),
      groups_(other.groups_),
      pixels_(other.pixels_) {
  arenas_.reserve(other.arenas_.size());
  for (const Arena& arena : other.arenas_) {
    arenas_.push_back(allocate_arena(arena.size));
    arenas_.back().used = arena.used;
    std::memcpy(arenas_.back().data.get(), arena.data.get(), arena.used);
  }
  for (Chunk& chunk : chunks_) chunk.data = arenas_[chunk.arena].data.get() + chunk.offset;
}

FrameStore& FrameStore::operator=(const FrameStore& other) {
  if (this != &other) *this = FrameStore(other);
  return *this;
}

void FrameStore::check_joins(const Descriptor& descriptor, std::int64_t group) const {
  descriptor.check_consistent("FrameStore::add");
  const bool first = slots_.empty();
  if (!first && descriptor.grid != grid_) {
    internal::throw_invalid("frame grid ", descriptor.grid.rows, "x", descriptor.grid.cols,
                            " differs from the stored frames' ", grid_.rows, "x", grid_.cols,
                            ": every frame must have the same image size");
  }
  if (!first && descriptor.storage != storage_) {
    internal::throw_invalid("FrameStore::add: a ", to_string(descriptor.storage),
                            " descriptor cannot join a store of ", to_string(storage_),
                            " descriptors");
  }
  if (!first && descriptor.storage == HistogramStorage::kCompact &&
      descriptor.cell_pixels != cell_pixels_) {
    internal::throw_invalid("FrameStore::add: compact descriptor with ", descriptor.cell_pixels,
                            " pixels per cell differs from the stored frames' ", cell_pixels_,
                            ": every frame must have the same image size");
  }
  if (group < 0 || group > groups()) {
    internal::throw_invalid("FrameStore::add: group ", group, " is neither one of the ", groups(),
                            " groups nor the next new one");
  }
}

std::int64_t FrameStore::add(const Descriptor& descriptor, std::int64_t group) {
  check_joins(descriptor, group);
  const bool first = slots_.empty();
  const bool compact = descriptor.storage == HistogramStorage::kCompact;
  const std::size_t bytes = compact ? descriptor.compact.size() * sizeof(CompactBin)
                                    : descriptor.hist.size() * sizeof(Bin);
  const std::int64_t max_chunk_frames =
      first ? std::max<std::int64_t>(1, static_cast<std::int64_t>(kChunkBytes / bytes))
            : max_chunk_frames_;
  const bool new_group = group == groups();
  Group g = new_group ? Group{} : groups_[static_cast<std::size_t>(group)];

  // Allocate everything that can fail before changing any member. A new
  // chunk is cut from the last arena, or from a new one when it does not fit.
  const bool new_chunk = g.used == g.capacity;
  const std::int64_t chunk_frames = std::clamp<std::int64_t>(g.frames / 2, 1, max_chunk_frames);
  const std::size_t chunk_size = static_cast<std::size_t>(chunk_frames) * bytes;
  const bool new_arena =
      new_chunk && (arenas_.empty() || arenas_.back().size - arenas_.back().used < chunk_size);
  Arena arena;
  if (new_chunk) {
    if (chunks_.size() >= std::numeric_limits<std::uint32_t>::max() ||
        arenas_.size() >= std::numeric_limits<std::uint32_t>::max()) {
      internal::throw_invalid("FrameStore::add: more than 2^32 - 1 chunks");
    }
    if (new_arena) {
      arena = allocate_arena(std::max(kArenaBytes, chunk_size));
      grow(arenas_, 1);
    }
    grow(chunks_, 1);
  }
  grow(slots_, 1);
  if (new_group) grow(groups_, 1);
  grow(pixels_, descriptor.pixels.size());

  // No allocation from here on.
  if (new_arena) arenas_.push_back(std::move(arena));
  if (new_chunk) {
    Arena& last = arenas_.back();
    chunks_.push_back(
        {last.data.get() + last.used, static_cast<std::uint32_t>(arenas_.size() - 1), last.used});
    last.used += chunk_size;
    g.chunk = static_cast<std::uint32_t>(chunks_.size() - 1);
    g.capacity = chunk_frames;
    g.used = 0;
  }
  std::byte* slot = chunks_[g.chunk].data + static_cast<std::size_t>(g.used) * bytes;
  if (compact) {
    std::memcpy(slot, descriptor.compact.data(), bytes);
  } else {
    std::memcpy(slot, descriptor.hist.data(), bytes);
  }
  slots_.push_back({g.chunk, static_cast<std::uint32_t>(g.used)});
  ++g.used;
  ++g.frames;
  if (new_group) {
    groups_.push_back(g);
  } else {
    groups_[static_cast<std::size_t>(group)] = g;
  }
  pixels_.insert(pixels_.end(), descriptor.pixels.begin(), descriptor.pixels.end());
  grid_ = descriptor.grid;
  storage_ = descriptor.storage;
  cell_pixels_ = descriptor.cell_pixels;
  max_chunk_frames_ = max_chunk_frames;
  return size() - 1;
}

DescriptorView FrameStore::view(std::int64_t frame) const {
  if (frame < 0 || frame >= size()) {
    internal::throw_invalid("frame ", frame, " is not stored (", size(), " frames)");
  }
  const Slot s = slots_[static_cast<std::size_t>(frame)];
  const std::byte* data = chunks_[s.chunk].data + static_cast<std::size_t>(s.slot) * frame_bytes();
  DescriptorView v;
  v.cells = grid_.cells();
  if (storage_ == HistogramStorage::kCompact) {
    v.compact = reinterpret_cast<const CompactBin*>(data);
    v.cell_pixels = cell_pixels_;
  } else {
    v.hist = reinterpret_cast<const Bin*>(data);
    v.pixels = pixels_.data() + static_cast<std::size_t>(frame) * static_cast<std::size_t>(v.cells);
  }
  return v;
}

std::size_t FrameStore::bytes_per_frame() const {
  return Descriptor::bytes_per_frame(storage_, grid_.cells());
}

std::size_t FrameStore::allocated_bytes() const {
  std::size_t bytes = 0;
  for (const Arena& arena : arenas_) bytes += arena.size;
  return bytes + pixels_.capacity() * sizeof(Count) + slots_.capacity() * sizeof(Slot) +
         groups_.capacity() * sizeof(Group) + chunks_.capacity() * sizeof(Chunk) +
         arenas_.capacity() * sizeof(Arena);
}

void FrameStore::reserve(std::int64_t frames) {
  if (frames <= 0) return;
  slots_.reserve(static_cast<std::size_t>(frames));
  if (storage_ == HistogramStorage::kExact && grid_.cells() > 0) {
    pixels_.reserve(static_cast<std::size_t>(frames) * static_cast<std::size_t>(grid_.cells()));
  }
}

}  // namespace lsgd
