#include "lsgd/frame_store.h"

#include <algorithm>
#include <cstdlib>
#include <new>
#include <type_traits>

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

std::size_t bins_per_cell(HistogramStorage storage) {
  return storage == HistogramStorage::kCompact ? kCompactBins : kBins;
}

}  // namespace

void FrameStore::FreeChunk::operator()(void* p) const { std::free(p); }

template <typename T>
FrameStore::Chunk<T> FrameStore::allocate_chunk(std::size_t elements) {
  static_assert(std::is_trivially_default_constructible_v<T>, "chunks hold raw bins");
  constexpr std::size_t kHugePage = std::size_t{2} << 20;
  const std::size_t bytes = (elements * sizeof(T) + kHugePage - 1) / kHugePage * kHugePage;
  void* p = std::aligned_alloc(kHugePage, bytes);
  if (p == nullptr) throw std::bad_alloc();
#ifdef __linux__
  madvise(p, bytes, MADV_HUGEPAGE);  // a hint: without huge pages it is just slower
#endif
  return Chunk<T>(static_cast<T*>(p));
}

template <typename T>
void FrameStore::copy_chunks(const std::vector<Chunk<T>>& from, std::size_t elements,
                             std::vector<Chunk<T>>& to) {
  to.reserve(from.size());
  for (const auto& chunk : from) {
    to.push_back(allocate_chunk<T>(elements));
    std::copy(chunk.get(), chunk.get() + elements, to.back().get());
  }
}

FrameStore::FrameStore(const FrameStore& other)
    : grid_(other.grid_),
      storage_(other.storage_),
      cell_pixels_(other.cell_pixels_),
      size_(other.size_),
      chunk_frames_(other.chunk_frames_),
      pixels_(other.pixels_) {
  const std::size_t chunk_bins = static_cast<std::size_t>(chunk_frames_) *
                                 static_cast<std::size_t>(grid_.cells()) * bins_per_cell(storage_);
  copy_chunks(other.chunks_, chunk_bins, chunks_);
  copy_chunks(other.compact_chunks_, chunk_bins, compact_chunks_);
}

FrameStore& FrameStore::operator=(const FrameStore& other) {
  if (this != &other) *this = FrameStore(other);
  return *this;
}

template <typename T>
void FrameStore::add_slot(const std::vector<T>& data, std::vector<Chunk<T>>& chunks,
                          const std::vector<Count>& pixels) {
  const std::size_t frame_bins = data.size();
  const std::int64_t chunk_frames =
      size_ > 0 ? chunk_frames_
                : std::max<std::int64_t>(
                      1, static_cast<std::int64_t>(kChunkBytes / (frame_bins * sizeof(T))));
  // Allocate everything that can fail before changing any member.
  Chunk<T> chunk;
  const bool new_chunk = size_ % chunk_frames == 0;
  if (new_chunk) {
    chunk = allocate_chunk<T>(static_cast<std::size_t>(chunk_frames) * frame_bins);
    grow(chunks, 1);
  }
  grow(pixels_, pixels.size());
  // No allocation from here on.
  if (new_chunk) chunks.push_back(std::move(chunk));
  chunk_frames_ = chunk_frames;
  T* slot = chunks.back().get() + static_cast<std::size_t>(size_ % chunk_frames) * frame_bins;
  std::copy(data.begin(), data.end(), slot);
  pixels_.insert(pixels_.end(), pixels.begin(), pixels.end());
}

std::int64_t FrameStore::add(const Descriptor& descriptor) {
  descriptor.check_consistent("FrameStore::add");
  if (size_ > 0 && descriptor.grid != grid_) {
    internal::throw_invalid("frame grid ", descriptor.grid.rows, "x", descriptor.grid.cols,
                            " differs from the stored frames' ", grid_.rows, "x", grid_.cols,
                            ": every frame must have the same image size");
  }
  if (size_ > 0 && descriptor.storage != storage_) {
    internal::throw_invalid("FrameStore::add: a ", to_string(descriptor.storage),
                            " descriptor cannot join a store of ", to_string(storage_),
                            " descriptors");
  }
  if (size_ > 0 && descriptor.storage == HistogramStorage::kCompact &&
      descriptor.cell_pixels != cell_pixels_) {
    internal::throw_invalid("FrameStore::add: compact descriptor with ", descriptor.cell_pixels,
                            " pixels per cell differs from the stored frames' ", cell_pixels_,
                            ": every frame must have the same image size");
  }
  if (descriptor.storage == HistogramStorage::kCompact) {
    add_slot(descriptor.compact, compact_chunks_, descriptor.pixels);
  } else {
    add_slot(descriptor.hist, chunks_, descriptor.pixels);
  }
  grid_ = descriptor.grid;
  storage_ = descriptor.storage;
  cell_pixels_ = descriptor.cell_pixels;
  return size_++;
}

DescriptorView FrameStore::view(std::int64_t frame) const {
  if (frame < 0 || frame >= size_) {
    internal::throw_invalid("frame ", frame, " is not stored (", size_, " frames)");
  }
  const std::size_t cells = static_cast<std::size_t>(grid_.cells());
  const auto chunk = static_cast<std::size_t>(frame / chunk_frames_);
  const auto slot = static_cast<std::size_t>(frame % chunk_frames_);
  DescriptorView v;
  v.cells = grid_.cells();
  if (storage_ == HistogramStorage::kCompact) {
    v.compact = compact_chunks_[chunk].get() + slot * cells * kCompactBins;
    v.cell_pixels = cell_pixels_;
  } else {
    v.hist = chunks_[chunk].get() + slot * cells * kBins;
    v.pixels = pixels_.data() + static_cast<std::size_t>(frame) * cells;
  }
  return v;
}

std::size_t FrameStore::bytes_per_frame() const {
  return Descriptor::bytes_per_frame(storage_, grid_.cells());
}

void FrameStore::reserve(std::int64_t frames) {
  if (frames <= 0 || grid_.cells() == 0) return;
  const std::size_t cells = static_cast<std::size_t>(grid_.cells());
  const auto chunks = static_cast<std::size_t>((frames + chunk_frames_ - 1) / chunk_frames_);
  if (storage_ == HistogramStorage::kCompact) {
    compact_chunks_.reserve(chunks);
  } else {
    chunks_.reserve(chunks);
    pixels_.reserve(static_cast<std::size_t>(frames) * cells);
  }
}

}  // namespace lsgd
