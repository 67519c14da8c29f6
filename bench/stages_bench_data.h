// The images and stores lsgd_stages_bench measures on (stages_bench_data.cc):
// procedural images, real descriptors of distinct places, and stores of
// frames interpolated along a looping route between them.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/frame_store.h"

namespace stages_bench {

struct Size {
  int width;
  int height;
};
constexpr Size kKitti{1241, 376};  // 5 x 16 = 80 cells with S_p = 40
constexpr Size kSmall{320, 240};   // 4 x 5 = 20 cells with S_p = 40

// A smooth textured BGR image of a scene (seed); `shift` moves the camera
// horizontally over it, so two shifts of one seed overlap like consecutive frames.
cv::Mat make_bgr(int width, int height, std::uint32_t seed, int shift = 0);
// The image segmented and described with the default options.
lsgd::Descriptor describe_image(const cv::Mat& bgr);
// Real descriptors of distinct places of one size, computed once.
const std::vector<lsgd::Descriptor>& places(Size size);
// A store of the first `frames` route frames (built once, grown on demand).
const lsgd::FrameStore& route_store(Size size, std::int64_t frames,
                                    lsgd::HistogramStorage storage = lsgd::HistogramStorage::kExact);
// A query that revisits the route: frame `j` of the route under another seed.
lsgd::Descriptor route_query(Size size, std::int64_t j,
                             lsgd::HistogramStorage storage = lsgd::HistogramStorage::kExact);
// "cells<N>_<W>x<H>".
std::string size_label(Size size);

}  // namespace stages_bench
