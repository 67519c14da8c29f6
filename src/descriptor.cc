#include "lsgd/descriptor.h"

#include <algorithm>
#include <limits>

#include "internal/check.h"

namespace lsgd {
namespace {

constexpr Count kBinMax = std::numeric_limits<Bin>::max();

// Recounts cell k in 32 bits and stores it saturated (only for cells of more
// than 65535 pixels, whose 16-bit bins may have wrapped).
void recount_saturated(const GrayImage& image, const Segmentation& segmentation, int k, Bin* h) {
  std::vector<Count> wide(kBins, 0);
  const std::size_t n = image.pixels.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (segmentation.labels[i] == k) ++wide[image.pixels[i]];
  }
  for (int b = 0; b < kBins; ++b) h[b] = static_cast<Bin>(std::min(wide[b], kBinMax));
}

}  // namespace

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
  // Labels come in runs along a row: count each run into its cell's histogram.
  for (int y = 0; y < image.height; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * image.width;
    const std::uint8_t* p = image.pixels.data() + row;
    const std::int32_t* labels = segmentation.labels.data() + row;
    int x = 0;
    while (x < image.width) {
      const std::int32_t label = labels[x];
      const auto k = static_cast<std::uint32_t>(label);  // -1 wraps: one compare
      if (k >= static_cast<std::uint32_t>(cells)) {
        internal::throw_invalid("describe: pixel ", row + x, " has label ", label,
                                " outside the ", cells, " cells of its segmentation");
      }
      Bin* h = &out.hist[static_cast<std::size_t>(k) * kBins];
      const int start = x;
      for (; x < image.width && labels[x] == label; ++x) ++h[p[x]];
      out.pixels[k] += static_cast<Count>(x - start);
    }
  }
  for (int k = 0; k < cells; ++k) {
    if (out.pixels[k] > kBinMax) {
      recount_saturated(image, segmentation, k, &out.hist[static_cast<std::size_t>(k) * kBins]);
    }
  }
}

Descriptor describe(const GrayImage& image, const Segmentation& segmentation) {
  Descriptor out;
  describe(image, segmentation, out);
  return out;
}

}  // namespace lsgd
