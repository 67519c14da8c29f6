// The "gradient" descriptor (descriptor.type, beyond the paper): each pixel
// counted by its gradient orientation instead of its gray level, so that a
// cell's histogram describes the directions of its edges, which a change of
// lighting (an exposure, a gamma, night) moves far less than gray levels.
// Central differences at the working size; the orientation atan2(gy, gx) in
// `orientations` equal bins; a pixel whose |gx| + |gy| is below `threshold`
// times the frame's mean (at least 1) counted as flat, bin 0. Bin b's code
// is 2 (b + 1), so compact storage (two codes a bin) never merges two
// orientations. docs/results.md measures it against intensity.
#pragma once

#include <vector>

#include "lsgd/descriptor.h"

namespace lsgd {

// DescriptorType::make of "gradient".
void gradient_codes(const GrayImage& work, const DescriptorOptions& options, GrayImage& codes);
// Its own options: descriptor.gradient.threshold, descriptor.gradient.orientations.
std::vector<OwnOption> gradient_options();

}  // namespace lsgd
