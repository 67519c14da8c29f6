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

void gradient_codes(const GrayImage& work, const DescriptorOptions& options, GrayImage& codes) {
  const double k = options.own_real("threshold");
  const auto bins = static_cast<int>(options.own_integer("orientations"));
  const int w = work.width, h = work.height;
  const std::size_t n = work.pixels.size();
  // Magnitude and angle of the inner pixels; the border stays flat.
  std::vector<float> magnitude(n, 0.f), angle(n, 0.f);
  double sum = 0;
  for (int y = 1; y + 1 < h; ++y) {
    for (int x = 1; x + 1 < w; ++x) {
      const float gx = static_cast<float>(work.at(x + 1, y)) - static_cast<float>(work.at(x - 1, y));
      const float gy = static_cast<float>(work.at(x, y + 1)) - static_cast<float>(work.at(x, y - 1));
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
      magnitude[i] = std::abs(gx) + std::abs(gy);
      angle[i] = std::atan2(gy, gx);
      sum += magnitude[i];
    }
  }
  const double level = std::max(1.0, k * sum / (static_cast<double>(w) * static_cast<double>(h)));
  constexpr double kPi = 3.14159265358979323846;
  codes.width = w;
  codes.height = h;
  codes.pixels.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (magnitude[i] < level) continue;  // flat: bin 0
    const int b = std::clamp(static_cast<int>(std::floor((angle[i] + kPi) / (2 * kPi) * bins)), 0, bins - 1);
    codes.pixels[i] = static_cast<std::uint8_t>(2 * (b + 1));
  }
}

}  // namespace lsgd
