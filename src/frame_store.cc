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

// Chunks of 2 MiB or more are aligned to 2 MiB for huge pages, smaller ones to
// a cache line; aligned_alloc needs the size to be a multiple of the alignment.
std::size_t chunk_alignment(std::size_t bytes) { return bytes >= kHugePage ? kHugePage : 64; }
std::size_t chunk_size(std::int64_t frames, std::size_t frame_bytes) {
  const std::size_t wanted = static_cast<std::size_t>(frames) * frame_bytes;
  const std::size_t align = chunk_alignment(wanted);
  return (wanted + align - 1) / align * align;
}

}  // namespace

void FrameStore::FreeChunk::operator()(std::byte* p) const { std::free(p); }

FrameStore::Chunk FrameStore::allocate_chunk(std::int64_t frames, std::size_t frame_bytes) {
  const std::size_t bytes = chunk_size(frames, frame_bytes);
  const std::size_t align = chunk_alignment(bytes);
  void* p = std::aligned_alloc(align, bytes);
  if (p == nullptr) throw std::bad_alloc();
#ifdef __linux__
  if (align == kHugePage) madvise(p, bytes, MADV_HUGEPAGE);  // a hint: without them it is slower
#endif
  Chunk chunk;
  chunk.data.reset(static_cast<std::byte*>(p));
  chunk.frames = frames;
  return chunk;
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
      slots_(other.slots_),
      groups_(other.groups_),
      pixels_(other.pixels_) {
  chunks_.reserve(other.chunks_.size());
  const std::size_t bytes = frame_bytes();
  for (const Chunk& chunk : other.chunks_) {
    chunks_.push_back(allocate_chunk(chunk.frames, bytes));
    std::memcpy(chunks_.back().data.get(), chunk.data.get(),
                static_cast<std::size_t>(chunk.frames) * bytes);
  }
}

FrameStore& FrameStore::operator=(const FrameStore& other) {
  if (this != &other) *this = FrameStore(other);
  return *this;
}

std::int64_t FrameStore::add(const Descriptor& descriptor, std::int64_t group) {
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
  const bool compact = descriptor.storage == HistogramStorage::kCompact;
  const std::size_t bytes = compact ? descriptor.compact.size() * sizeof(CompactBin)
                                    : descriptor.hist.size() * sizeof(Bin);
  const std::int64_t max_chunk_frames =
      first ? std::max<std::int64_t>(1, static_cast<std::int64_t>(kChunkBytes / bytes))
            : max_chunk_frames_;
  const bool new_group = group == groups();
  Group g = new_group ? Group{} : groups_[static_cast<std::size_t>(group)];

  // Allocate everything that can fail before changing any member.
  Chunk chunk;
  const bool new_chunk = g.used == g.capacity;
  if (new_chunk) {
    if (chunks_.size() >= std::numeric_limits<std::uint32_t>::max()) {
      internal::throw_invalid("FrameStore::add: more than 2^32 - 1 chunks");
    }
    chunk = allocate_chunk(std::clamp<std::int64_t>(g.frames / 2, 1, max_chunk_frames), bytes);
    grow(chunks_, 1);
  }
  grow(slots_, 1);
  if (new_group) grow(groups_, 1);
  grow(pixels_, descriptor.pixels.size());

  // No allocation from here on.
  if (new_chunk) {
    g.chunk = static_cast<std::uint32_t>(chunks_.size());
    g.capacity = chunk.frames;
    g.used = 0;
    chunks_.push_back(std::move(chunk));
  }
  std::byte* slot = chunks_[g.chunk].data.get() + static_cast<std::size_t>(g.used) * bytes;
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
  const std::byte* data =
      chunks_[s.chunk].data.get() + static_cast<std::size_t>(s.slot) * frame_bytes();
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
  for (const Chunk& chunk : chunks_) bytes += chunk_size(chunk.frames, frame_bytes());
  return bytes + pixels_.capacity() * sizeof(Count) + slots_.capacity() * sizeof(Slot) +
         groups_.capacity() * sizeof(Group) + chunks_.capacity() * sizeof(Chunk);
}

void FrameStore::reserve(std::int64_t frames) {
  if (frames <= 0) return;
  slots_.reserve(static_cast<std::size_t>(frames));
  if (storage_ == HistogramStorage::kExact && grid_.cells() > 0) {
    pixels_.reserve(static_cast<std::size_t>(frames) * static_cast<std::size_t>(grid_.cells()));
  }
}

}  // namespace lsgd
