#include "lsgd/segmentation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "internal/check.h"

namespace lsgd {

void SegmentationOptions::check() const {
  internal::check_range("segmentation.superpixel_size", superpixel_size, 2, 4096, "pixels");
  internal::check_range("segmentation.iterations", iterations, 1, 100);
  internal::check_range_open_low("segmentation.intensity_scale", intensity_scale, 0.0, 1e6);
  internal::check_range_open_low("segmentation.distance_scale", distance_scale, 0.0, 1e6);
}

GridSize grid_size(int width, int height, int superpixel_size) {
  if (width <= 0 || height <= 0) {
    internal::throw_invalid("grid_size: image size ", width, "x", height, " is empty");
  }
  if (superpixel_size <= 0) {
    internal::throw_invalid("grid_size: superpixel_size = ", superpixel_size, " must be > 0");
  }
  const std::int64_t step = 2 * static_cast<std::int64_t>(superpixel_size);  // no int overflow
  return {static_cast<int>(height / step + 1), static_cast<int>(width / step + 1)};
}

Segmenter::Segmenter(const SegmentationOptions& options) : options_(options) {
  options_.check();
}

Segmentation Segmenter::segment(const GrayImage& image) {
  Segmentation out;
  segment(image, out);
  return out;
}

void Segmenter::segment(const GrayImage& image, Segmentation& out) {
  if (image.empty() || image.pixels.size() != static_cast<std::size_t>(image.width) * image.height) {
    internal::throw_invalid("segment: image ", image.width, "x", image.height,
                            " is empty or inconsistent with its pixel buffer");
  }
  out.width = image.width;
  out.height = image.height;
  out.grid = grid_size(image.width, image.height, options_.superpixel_size);
  out.labels.resize(static_cast<std::size_t>(image.width) * image.height);
  distance_.resize(out.labels.size());
  seed(image, out);
  for (int it = 0; it < options_.iterations; ++it) {
    assign(image, out);
    update(image, out);
  }
}

// Grid seeds at ((i + 0.5) W / cols, (j + 0.5) H / rows), truncated to whole
// pixels as in the reference, each moved to the lowest-gradient pixel of its
// 3x3 neighbourhood (standard SLIC seeding).
void Segmenter::seed(const GrayImage& image, Segmentation& out) const {
  const GridSize g = out.grid;
  const double cell_w = static_cast<double>(image.width) / g.cols;
  const double cell_h = static_cast<double>(image.height) / g.rows;
  auto gradient = [&](int x, int y) {
    const int gx = image.at(x + 1, y) - image.at(x - 1, y);
    const int gy = image.at(x, y + 1) - image.at(x, y - 1);
    return gx * gx + gy * gy;
  };
  out.centres.assign(g.cells(), Centre{});
  for (int r = 0; r < g.rows; ++r) {
    for (int c = 0; c < g.cols; ++c) {
      int x = static_cast<int>((c + 0.5) * cell_w);
      int y = static_cast<int>((r + 0.5) * cell_h);
      if (x >= 1 && y >= 1 && x < image.width - 1 && y < image.height - 1) {
        // Move only to a strictly lower gradient: on ties (flat areas) the seed stays put.
        int best_x = x, best_y = y, best = gradient(x, y);
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 1 || ny < 1 || nx >= image.width - 1 || ny >= image.height - 1) continue;
            const int grad = gradient(nx, ny);
            if (grad < best) best = grad, best_x = nx, best_y = ny;
          }
        }
        x = best_x, y = best_y;
      }
      Centre& centre = out.centres[r * g.cols + c];
      centre.x = static_cast<float>(x);
      centre.y = static_cast<float>(y);
      centre.intensity = image.at(x, y);
    }
  }
}

// Each centre claims the pixels of its window (+- one cell size, as the
// reference's search range) whose fuse distance
// F_d^2 = d_i^2 / intensity_scale + d_e^2 / distance_scale is the smallest so far.
void Segmenter::assign(const GrayImage& image, Segmentation& out) {
  std::fill(distance_.begin(), distance_.end(), std::numeric_limits<float>::infinity());
  std::fill(out.labels.begin(), out.labels.end(), -1);
  const GridSize g = out.grid;
  const int half_w = image.width / g.cols;
  const int half_h = image.height / g.rows;
  const float inv_ds = static_cast<float>(1.0 / options_.distance_scale);
  const float inv_is = static_cast<float>(1.0 / options_.intensity_scale);
  for (int k = 0; k < g.cells(); ++k) {
    const Centre& centre = out.centres[k];
    const int cx = static_cast<int>(std::lround(centre.x));
    const int cy = static_cast<int>(std::lround(centre.y));
    const int x0 = std::max(0, cx - half_w), x1 = std::min(image.width - 1, cx + half_w);
    const int y0 = std::max(0, cy - half_h), y1 = std::min(image.height - 1, cy + half_h);
    for (int y = y0; y <= y1; ++y) {
      const float dy = y - centre.y;
      const float row_term = dy * dy * inv_ds;
      const std::size_t row = static_cast<std::size_t>(y) * image.width;
      for (int x = x0; x <= x1; ++x) {
        const float dx = x - centre.x;
        const float di = image.pixels[row + x] - centre.intensity;
        const float d = di * di * inv_is + dx * dx * inv_ds + row_term;
        if (d < distance_[row + x]) {
          distance_[row + x] = d;
          out.labels[row + x] = k;
        }
      }
    }
  }
  assign_unreached(out);
}

// Centres move between iterations, so a pixel can fall outside every window;
// it joins the centre nearest in position (the reference would index -1).
void Segmenter::assign_unreached(Segmentation& out) const {
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      std::int32_t& label = out.labels[static_cast<std::size_t>(y) * out.width + x];
      if (label >= 0) continue;
      float best = std::numeric_limits<float>::infinity();
      for (int k = 0; k < out.grid.cells(); ++k) {
        const float dx = x - out.centres[k].x, dy = y - out.centres[k].y;
        const float d = dx * dx + dy * dy;
        if (d < best) best = d, label = k;
      }
    }
  }
}

// k-means update: every centre moves to the mean position and intensity of its
// pixels; an empty cluster keeps its previous centre (no division by zero).
void Segmenter::update(const GrayImage& image, Segmentation& out) {
  const int cells = out.grid.cells();
  sums_.assign(static_cast<std::size_t>(cells) * 3, 0.0);
  for (auto& centre : out.centres) centre.pixels = 0;
  for (int y = 0; y < image.height; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * image.width;
    for (int x = 0; x < image.width; ++x) {
      const std::int32_t k = out.labels[row + x];
      double* s = &sums_[static_cast<std::size_t>(k) * 3];
      s[0] += x;
      s[1] += y;
      s[2] += image.pixels[row + x];
      ++out.centres[k].pixels;
    }
  }
  for (int k = 0; k < cells; ++k) {
    Centre& centre = out.centres[k];
    if (centre.pixels == 0) continue;
    const double n = centre.pixels;
    centre.x = static_cast<float>(sums_[k * 3] / n);
    centre.y = static_cast<float>(sums_[k * 3 + 1] / n);
    centre.intensity = static_cast<float>(sums_[k * 3 + 2] / n);
  }
}

}  // namespace lsgd
