// LSGD descriptor, paper Sec. III-C: one 256-bin intensity histogram per
// superpixel-grid cell, stored as one contiguous block of cells * 256 counts.
#pragma once

#include <cstdint>
#include <vector>

#include "lsgd/image.h"
#include "lsgd/segmentation.h"

namespace lsgd {

constexpr int kBins = 256;  // one bin per 8-bit intensity
using Count = std::uint32_t;

// Non-owning view of one frame's descriptor (inside a Descriptor or a FrameStore).
struct DescriptorView {
  const Count* hist = nullptr;    // cells * kBins counts, cell-major
  const Count* pixels = nullptr;  // cells pixel counts (sum of each cell's histogram)
  int cells = 0;
};

struct Descriptor {
  GridSize grid;
  std::vector<Count> hist;    // cells * kBins
  std::vector<Count> pixels;  // cells

  DescriptorView view() const { return {hist.data(), pixels.data(), grid.cells()}; }
};

// Builds the descriptor of `image` from its segmentation (same size; throws
// InvalidArgument otherwise). Reuses out's storage.
void describe(const GrayImage& image, const Segmentation& segmentation, Descriptor& out);
Descriptor describe(const GrayImage& image, const Segmentation& segmentation);

}  // namespace lsgd
