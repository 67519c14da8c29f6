// The index's graph key of a frame and the graph's distance between keys
// (search mode "index", src/search/index.cc).
//
// A frame's key: per cell, its histogram pooled into kKeyBins bins of
// kBins / kKeyBins intensities, normalised to kKeyMass (rounded), so a cell's
// key is 16 bytes and a frame's key cells * 16 bytes (1,280 bytes for a
// 1241x376 frame at 80 cells, an eighth of its compact descriptor). Pooling
// adjacent bins never increases an L1 distance, so the key distance
// sum_k sqrt(SAD_k) (reference metric; sum_k SAD_k for the L1 metrics) is a
// coarse lower-bound-like proxy of the metric that reads 1/8 (compact) or 1/32
// (exact) of the bytes, from the graph's own memory next to the links.
#pragma once

#include <cstdint>

#include "lsgd/descriptor.h"

namespace lsgd::internal {

constexpr int kKeyBins = 16;
constexpr int kKeyMass = 255;

// Writes the key of `d` (d.cells * kKeyBins bytes) to `key`.
void make_key(const DescriptorView& d, std::uint8_t* key);

// What the graph's distance function reads: the key length and the metric
// (the reference metric sums square roots of the cells' SADs).
struct KeySpaceParam {
  int cells = 0;
  bool sqrt = false;
};

// The distance between keys a and b: sum over cells of the cell's SAD, or of
// its square root (param: a KeySpaceParam). hnswlib's DISTFUNC.
float key_distance(const void* a, const void* b, const void* param);

}  // namespace lsgd::internal
