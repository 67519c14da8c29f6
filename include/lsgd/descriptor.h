// LSGD descriptor, paper Sec. III-C: one 256-bin intensity histogram per
// superpixel-grid cell, stored as one contiguous block of cells * 256 counts.
// Bins are 16-bit: exact for every bin below 65535 pixels (a cell would need
// more than 65535 pixels of one intensity, i.e. cells larger than 256 x 256
// pixels, to saturate); a fuller bin is stored as 65535. Half the memory and
// memory traffic of the 32-bit counts of the reference implementation.
#pragma once

#include <cstdint>
#include <vector>

#include "lsgd/image.h"
#include "lsgd/segmentation.h"

namespace lsgd {

constexpr int kBins = 256;  // one bin per 8-bit intensity
using Bin = std::uint16_t;    // one histogram bin (saturating at 65535)
using Count = std::uint32_t;  // pixels in a cell

// Non-owning view of one frame's descriptor (inside a Descriptor or a FrameStore).
struct DescriptorView {
  const Bin* hist = nullptr;       // cells * kBins counts, cell-major
  const Count* pixels = nullptr;  // cells pixel counts (sum of each cell's histogram before saturation)
  int cells = 0;
};

struct Descriptor {
  GridSize grid;
  std::vector<Bin> hist;      // cells * kBins
  std::vector<Count> pixels;  // cells

  DescriptorView view() const { return {hist.data(), pixels.data(), grid.cells()}; }
};

// Builds the descriptor of `image` from its segmentation (same size; throws
// InvalidArgument otherwise). Reuses out's storage.
void describe(const GrayImage& image, const Segmentation& segmentation, Descriptor& out);
Descriptor describe(const GrayImage& image, const Segmentation& segmentation);

}  // namespace lsgd
