#include "lsgd/frame_store.h"

#include <algorithm>

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

}  // namespace

FrameStore::FrameStore(const FrameStore& other)
    : grid_(other.grid_), size_(other.size_), chunk_frames_(other.chunk_frames_),
      pixels_(other.pixels_) {
  const std::size_t chunk_bins =
      static_cast<std::size_t>(chunk_frames_) * static_cast<std::size_t>(grid_.cells()) * kBins;
  chunks_.reserve(other.chunks_.size());
  for (const auto& chunk : other.chunks_) {
    chunks_.emplace_back(new Bin[chunk_bins]);
    std::copy(chunk.get(), chunk.get() + chunk_bins, chunks_.back().get());
  }
}

FrameStore& FrameStore::operator=(const FrameStore& other) {
  if (this != &other) *this = FrameStore(other);
  return *this;
}

std::int64_t FrameStore::add(const Descriptor& descriptor) {
  const int cells = descriptor.grid.cells();
  if (cells <= 0 || descriptor.hist.size() != static_cast<std::size_t>(cells) * kBins ||
      descriptor.pixels.size() != static_cast<std::size_t>(cells)) {
    internal::throw_invalid("FrameStore::add: descriptor of a ", descriptor.grid.rows, "x",
                            descriptor.grid.cols, " grid has inconsistent storage");
  }
  if (size_ > 0 && descriptor.grid != grid_) {
    internal::throw_invalid("frame grid ", descriptor.grid.rows, "x", descriptor.grid.cols,
                            " differs from the stored frames' ", grid_.rows, "x", grid_.cols,
                            ": every frame must have the same image size");
  }
  const std::size_t frame_bins = static_cast<std::size_t>(cells) * kBins;
  const std::int64_t chunk_frames =
      size_ > 0 ? chunk_frames_
                : std::max<std::int64_t>(1, static_cast<std::int64_t>(kChunkBytes / (frame_bins * sizeof(Bin))));
  // Allocate everything that can fail before changing any member.
  std::unique_ptr<Bin[]> chunk;
  const bool new_chunk = size_ % chunk_frames == 0;
  if (new_chunk) {
    chunk.reset(new Bin[static_cast<std::size_t>(chunk_frames) * frame_bins]);
    grow(chunks_, 1);
  }
  grow(pixels_, descriptor.pixels.size());
  // No allocation from here on.
  if (new_chunk) chunks_.push_back(std::move(chunk));
  grid_ = descriptor.grid;
  chunk_frames_ = chunk_frames;
  Bin* slot = chunks_.back().get() + static_cast<std::size_t>(size_ % chunk_frames) * frame_bins;
  std::copy(descriptor.hist.begin(), descriptor.hist.end(), slot);
  pixels_.insert(pixels_.end(), descriptor.pixels.begin(), descriptor.pixels.end());
  return size_++;
}

DescriptorView FrameStore::view(std::int64_t frame) const {
  if (frame < 0 || frame >= size_) {
    internal::throw_invalid("frame ", frame, " is not stored (", size_, " frames)");
  }
  const std::size_t cells = static_cast<std::size_t>(grid_.cells());
  const Bin* chunk = chunks_[static_cast<std::size_t>(frame / chunk_frames_)].get();
  const std::size_t slot = static_cast<std::size_t>(frame % chunk_frames_);
  return {chunk + slot * cells * kBins, pixels_.data() + static_cast<std::size_t>(frame) * cells,
          grid_.cells()};
}

std::size_t FrameStore::bytes_per_frame() const {
  return static_cast<std::size_t>(grid_.cells()) * (kBins * sizeof(Bin) + sizeof(Count));
}

void FrameStore::reserve(std::int64_t frames) {
  if (frames <= 0 || grid_.cells() == 0) return;
  const std::size_t cells = static_cast<std::size_t>(grid_.cells());
  chunks_.reserve(static_cast<std::size_t>((frames + chunk_frames_ - 1) / chunk_frames_));
  pixels_.reserve(static_cast<std::size_t>(frames) * cells);
}

}  // namespace lsgd
