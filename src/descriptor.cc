#include "lsgd/descriptor.h"

#include "internal/check.h"

namespace lsgd {

void describe(const GrayImage& image, const Segmentation& segmentation, Descriptor& out) {
  if (image.width != segmentation.width || image.height != segmentation.height ||
      segmentation.labels.size() != image.pixels.size()) {
    internal::throw_invalid("describe: image ", image.width, "x", image.height,
                            " does not match its segmentation ", segmentation.width, "x",
                            segmentation.height);
  }
  const int cells = segmentation.grid.cells();
  out.grid = segmentation.grid;
  out.hist.assign(static_cast<std::size_t>(cells) * kBins, 0);
  out.pixels.assign(static_cast<std::size_t>(cells), 0);
  const std::size_t n = image.pixels.size();
  for (std::size_t i = 0; i < n; ++i) {
    const auto k = static_cast<std::uint32_t>(segmentation.labels[i]);  // -1 wraps: one compare
    if (k >= static_cast<std::uint32_t>(cells)) {
      internal::throw_invalid("describe: pixel ", i, " has label ", segmentation.labels[i],
                              " outside the ", cells, " cells of its segmentation");
    }
    ++out.hist[static_cast<std::size_t>(k) * kBins + image.pixels[i]];
  }
  for (int k = 0; k < cells; ++k) {
    const Count* h = &out.hist[static_cast<std::size_t>(k) * kBins];
    Count total = 0;
    for (int b = 0; b < kBins; ++b) total += h[b];
    out.pixels[k] = total;
  }
}

Descriptor describe(const GrayImage& image, const Segmentation& segmentation) {
  Descriptor out;
  describe(image, segmentation, out);
  return out;
}

}  // namespace lsgd
