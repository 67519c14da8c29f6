#include "lsgd/frame_store.h"

#include "internal/check.h"

namespace lsgd {

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
  grid_ = descriptor.grid;
  hist_.insert(hist_.end(), descriptor.hist.begin(), descriptor.hist.end());
  pixels_.insert(pixels_.end(), descriptor.pixels.begin(), descriptor.pixels.end());
  return size_++;
}

DescriptorView FrameStore::view(std::int64_t frame) const {
  if (frame < 0 || frame >= size_) {
    internal::throw_invalid("frame ", frame, " is not stored (", size_, " frames)");
  }
  const std::size_t cells = static_cast<std::size_t>(grid_.cells());
  const std::size_t f = static_cast<std::size_t>(frame);
  return {hist_.data() + f * cells * kBins, pixels_.data() + f * cells, grid_.cells()};
}

std::size_t FrameStore::bytes_per_frame() const {
  return static_cast<std::size_t>(grid_.cells()) * (kBins * sizeof(Bin) + sizeof(Count));
}

void FrameStore::reserve(std::int64_t frames) {
  if (frames <= 0 || grid_.cells() == 0) return;
  const std::size_t cells = static_cast<std::size_t>(grid_.cells());
  hist_.reserve(static_cast<std::size_t>(frames) * cells * kBins);
  pixels_.reserve(static_cast<std::size_t>(frames) * cells);
}

}  // namespace lsgd
