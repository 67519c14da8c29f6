// Contiguous storage of every stored frame's descriptor: frame i occupies a
// fixed-stride slot, so memory grows linearly with the number of frames and a
// scan over frames walks memory in order. Frame ids are dense: 0, 1, 2, ...
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "lsgd/descriptor.h"

namespace lsgd {

class FrameStore {
 public:
  FrameStore() = default;

  // The grid is fixed by the first frame added; later frames must match it
  // (throws InvalidArgument otherwise, leaving the store unchanged).
  std::int64_t add(const Descriptor& descriptor);

  std::int64_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const GridSize& grid() const { return grid_; }
  DescriptorView view(std::int64_t frame) const;

  // Bytes of descriptor data held per frame.
  std::size_t bytes_per_frame() const;
  void reserve(std::int64_t frames);

 private:
  GridSize grid_;
  std::int64_t size_ = 0;
  std::vector<Bin> hist_;
  std::vector<Count> pixels_;
};

}  // namespace lsgd
