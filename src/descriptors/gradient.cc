#include "lsgd/descriptors/gradient.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace lsgd {

std::vector<OwnOption> gradient_options() {
  return {
      {"threshold", OptionKind::kReal, "1.5", 0, 100, true, {}, "",
       "a pixel whose |gx| + |gy| is below this times the frame's mean is flat (bin 0)"},
      {"orientations", OptionKind::kInteger, "32", 4, 127, false, {}, "",
       "bins of gradient orientation over the full circle"},
  };
}

namespace {

// The central difference of the inner pixel (x, y): |gx| + |gy| and atan2(gy, gx).
struct Gradient {
  float gx, gy;
  float magnitude() const { return std::abs(gx) + std::abs(gy); }
};
Gradient gradient_at(const GrayImage& work, int x, int y) {
  return {static_cast<float>(work.at(x + 1, y)) - static_cast<float>(work.at(x - 1, y)),
          static_cast<float>(work.at(x, y + 1)) - static_cast<float>(work.at(x, y - 1))};
}

}  // namespace

void gradient_codes(const GrayImage& work, const DescriptorOptions& options, GrayImage& codes) {
  // Its own options, read from the declared list (no registry lookup a frame).
  static const std::vector<OwnOption> declared = gradient_options();
  const double k = own_real(options.own, declared, options.type, "threshold");
  const auto bins = static_cast<int>(own_integer(options.own, declared, options.type, "orientations"));
  const int w = work.width, h = work.height;
  // Two passes over the inner pixels, no buffer: the mean magnitude, then the
  // orientation of each pixel above the level; the border stays flat (bin 0).
  double sum = 0;
  for (int y = 1; y + 1 < h; ++y) {
    for (int x = 1; x + 1 < w; ++x) sum += gradient_at(work, x, y).magnitude();
  }
  const double level = std::max(1.0, k * sum / (static_cast<double>(w) * static_cast<double>(h)));
  constexpr double kPi = 3.14159265358979323846;
  codes.width = w;
  codes.height = h;
  codes.pixels.assign(work.pixels.size(), 0);
  for (int y = 1; y + 1 < h; ++y) {
    for (int x = 1; x + 1 < w; ++x) {
      const Gradient g = gradient_at(work, x, y);
      if (g.magnitude() < level) continue;  // flat: bin 0
      const float angle = std::atan2(g.gy, g.gx);
      const int b = std::clamp(static_cast<int>(std::floor((angle + kPi) / (2 * kPi) * bins)), 0, bins - 1);
      codes.pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)] =
          static_cast<std::uint8_t>(2 * (b + 1));
    }
  }
}

}  // namespace lsgd
