#include "lsgd/segmentation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "internal/check.h"
#include "internal/kernels.h"

namespace lsgd {

const OptionTable<SegmentationOptions>& SegmentationOptions::fields() {
  using S = SegmentationOptions;
  static const OptionTable<S> table = {
      integer_option("superpixel_size", &S::superpixel_size, 2, 4096, "pixels",
                     "S_p, the segmentation scale: the grid has H/(2 S_p)+1 rows and W/(2 S_p)+1 "
                     "columns"),
      integer_option("iterations", &S::iterations, 1, 100, "",
                     "k-means iterations (assign + update); the reference runs 10"),
      real_option("intensity_scale", &S::intensity_scale, 0.0, 1e6, true, "",
                  "divides the squared intensity difference in the fuse distance"),
      real_option("distance_scale", &S::distance_scale, 0.0, 1e6, true, "",
                  "divides the squared pixel distance (pixels^2) in the fuse distance"),
      integer_option("working_side", &S::working_side, 0, kMaxImageSide, "pixels",
                     "a frame whose shorter side is longer is scaled down to it before it is "
                     "segmented and described (0: its own size, the paper's; else >= 16)"),
  };
  return table;
}

void SegmentationOptions::check() const {
  check_options(fields(), *this, "segmentation");
  if (working_side > 0 && working_side < kMinWorkingSide) {
    internal::throw_invalid("segmentation.working_side = ", working_side, " must be 0 (off) or at least ",
                            kMinWorkingSide, " pixels");
  }
}

FrameSize working_size(int width, int height, const SegmentationOptions& options) {
  const int side = options.working_side;
  const int shorter = std::min(width, height);
  if (side <= 0 || shorter <= side) return {width, height};
  // The longer side in proportion, rounded to nearest, in 64-bit integers.
  const auto scaled = [&](int longer) {
    const std::int64_t v = (static_cast<std::int64_t>(longer) * side + shorter / 2) / shorter;
    return static_cast<int>(std::max<std::int64_t>(1, v));
  };
  return width <= height ? FrameSize{side, scaled(height)} : FrameSize{scaled(width), side};
}

GridSize frame_grid(int width, int height, const SegmentationOptions& options) {
  const FrameSize s = working_size(width, height, options);
  return grid_size(s.width, s.height, options.superpixel_size);
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

struct Segmenter::Rows {
  std::vector<internal::RowSegment> segments;
};

Segmenter::Segmenter(const SegmentationOptions& options)
    : options_(options), rows_(std::make_unique<Rows>()) {
  options_.check();
}
Segmenter::~Segmenter() = default;
Segmenter::Segmenter(Segmenter&&) noexcept = default;
Segmenter& Segmenter::operator=(Segmenter&&) noexcept = default;

const GrayImage& Segmenter::working(const GrayImage& image) {
  const FrameSize s = working_size(image.width, image.height, options_);
  if (s.width == image.width && s.height == image.height) return image;
  if (image.pixels.size() != static_cast<std::size_t>(image.width) * image.height) {
    internal::throw_invalid("segment: image ", image.width, "x", image.height,
                            " is inconsistent with its pixel buffer");
  }
  scaled_.width = s.width;
  scaled_.height = s.height;
  scaled_.pixels.resize(static_cast<std::size_t>(s.width) * s.height);
  const cv::Mat from(image.height, image.width, CV_8UC1, const_cast<std::uint8_t*>(image.pixels.data()));
  cv::Mat to(s.height, s.width, CV_8UC1, scaled_.pixels.data());
  cv::resize(from, to, to.size(), 0, 0, cv::INTER_AREA);
  return scaled_;
}

Segmentation Segmenter::segment(const GrayImage& image) {
  Segmentation out;
  segment(image, out);
  return out;
}

void Segmenter::segment(const GrayImage& image, Segmentation& out) { run(image, out, nullptr); }

void Segmenter::segment(const GrayImage& image, Segmentation& out, RowSink& sink) {
  run(image, out, &sink);
}

void Segmenter::run(const GrayImage& image, Segmentation& out, RowSink* sink) {
  if (image.empty() ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * image.height) {
    internal::throw_invalid("segment: image ", image.width, "x", image.height,
                            " is empty or inconsistent with its pixel buffer");
  }
  out.width = image.width;
  out.height = image.height;
  out.grid = grid_size(image.width, image.height, options_.superpixel_size);
  out.labels.resize(static_cast<std::size_t>(image.width) * image.height);
  seed(image, out);
  for (int it = 0; it < options_.iterations; ++it) {
    iterate(image, out, it + 1 == options_.iterations ? sink : nullptr);
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

// Each centre's window (+- one cell size around its rounded position, as the
// reference's search range) and x-term table (the same in every row of its
// window; tables aligned for the kernel's vectors of `lanes` floats), and for
// every row the centres whose window covers it, in index order (a counting
// sort by row). Returns where the tables start.
const float* Segmenter::plan(const GrayImage& image, const Segmentation& out, int lanes,
                             float inv_ds) {
  const int cells = out.grid.cells();
  const int half_w = image.width / out.grid.cols;
  const int half_h = image.height / out.grid.rows;
  windows_.resize(static_cast<std::size_t>(cells));
  row_start_.assign(static_cast<std::size_t>(image.height) + 1, 0);
  std::size_t xterms = 0;
  for (int k = 0; k < cells; ++k) {
    const int cx = static_cast<int>(std::lround(out.centres[k].x));
    const int cy = static_cast<int>(std::lround(out.centres[k].y));
    Window& w = windows_[k];
    w.x0 = std::max(0, cx - half_w), w.x1 = std::min(image.width - 1, cx + half_w);
    w.y0 = std::max(0, cy - half_h), w.y1 = std::min(image.height - 1, cy + half_h);
    w.xterm = xterms;
    xterms += static_cast<std::size_t>(internal::x_terms_size(w.x0, w.x1, lanes));
    for (int y = w.y0; y <= w.y1; ++y) ++row_start_[static_cast<std::size_t>(y) + 1];
  }
  constexpr std::size_t kAlign = 64;  // bytes: one cache line, the widest x86 vector
  xterms_.resize(xterms + kAlign / sizeof(float));
  const auto misalign = reinterpret_cast<std::uintptr_t>(xterms_.data()) % kAlign;
  float* const tables = xterms_.data() + (kAlign - misalign) % kAlign / sizeof(float);
  for (int k = 0; k < cells; ++k) {
    const Window& w = windows_[k];
    internal::x_terms(out.centres[k].x, w.x0, w.x1, inv_ds, lanes, tables + w.xterm);
  }
  for (int y = 0; y < image.height; ++y) row_start_[y + 1] += row_start_[y];
  row_items_.resize(static_cast<std::size_t>(row_start_[image.height]));
  row_fill_.assign(row_start_.begin(), row_start_.end() - 1);
  for (int k = 0; k < cells; ++k) {
    for (int y = windows_[k].y0; y <= windows_[k].y1; ++y) row_items_[row_fill_[y]++] = k;
  }
  return tables;
}

// One k-means iteration, row by row so that the working set (one row of
// labels and pixels) stays in the L1 cache:
// - assignment: each centre claims the pixels of its window (+- one cell size,
//   as the reference's search range) whose fuse distance
//   F_d^2 = d_i^2 / intensity_scale + d_e^2 / distance_scale is the smallest
//   so far, centres in index order (ties keep the earlier centre); a SIMD
//   kernel does one row for all centres whose window covers it, keeping the
//   best distances in registers (internal::assign_row);
// - a pixel no window reached (centres move between iterations) joins the
//   centre nearest in position (the reference would index -1);
// - update: every centre moves to the mean position and intensity of its
//   pixels; an empty cluster keeps its previous centre (no division by zero).
//   Labels come in runs along a row (cells are ~2 S_p wide), so the sums are
//   taken per run, x sums by the arithmetic series, exact in 64-bit integers.
// The result equals assigning the whole image, then updating. `sink`, when
// set, gets each row once its labels are final.
void Segmenter::iterate(const GrayImage& image, Segmentation& out, RowSink* sink) {
  const int cells = out.grid.cells();
  const float inv_ds = static_cast<float>(1.0 / options_.distance_scale);
  const int lanes = internal::assign_lanes();
  const float* const tables = plan(image, out, lanes, inv_ds);

  sums_.assign(static_cast<std::size_t>(cells) * 4, 0);
  internal::AssignRow r;
  r.width = image.width;
  r.lanes = lanes;
  r.inv_distance = inv_ds;
  r.inv_intensity = static_cast<float>(1.0 / options_.intensity_scale);
  std::vector<internal::RowSegment>& segments = rows_->segments;
  for (int y = 0; y < image.height; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * image.width;
    const std::uint8_t* p = image.pixels.data() + row;
    std::int32_t* labels = out.labels.data() + row;
    const std::int32_t* const items = row_items_.data() + row_start_[y];
    const int count = static_cast<int>(row_start_[y + 1] - row_start_[y]);
    // Rows covered by the same centres (runs of ~10 rows) share the lists.
    const bool same = y > 0 && count == static_cast<int>(segments.size()) &&
                      std::equal(items, items + count, row_items_.data() + row_start_[y - 1]);
    segments.resize(static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) {
      const std::int32_t k = items[i];
      const Centre& c = out.centres[k];
      const float dy = static_cast<float>(y) - c.y;
      internal::RowSegment& seg = segments[static_cast<std::size_t>(i)];
      seg.x0 = windows_[k].x0;
      seg.x1 = windows_[k].x1;
      seg.cx = c.x;
      seg.intensity = c.intensity;
      seg.row_term = (dy * dy) * inv_ds;
      seg.label = k;
      seg.xterm = tables + windows_[k].xterm;
      seg.xterm_first = internal::x_terms_first(seg.x0, lanes);
    }
    if (!same) internal::assign_lists(segments.data(), count, image.width, lanes, lists_);
    r.pixels = p;
    r.labels = labels;
    r.segments = segments.data();
    r.count = count;
    r.lists = lists_.data();
    internal::assign_row(r);

    int x = internal::row_sums(labels, p, image.width, y, sums_.data());
    while (x < image.width) {  // an unreached pixel: label it, go on from there
      labels[x] = nearest_centre(out, x, y);
      x = internal::row_sums(labels, p, image.width, y, sums_.data(), x);
    }
    if (sink != nullptr) sink->row(y, p, labels, image.width);
  }
  for (int k = 0; k < cells; ++k) {
    Centre& centre = out.centres[k];
    const std::int64_t* s = &sums_[static_cast<std::size_t>(k) * 4];
    centre.pixels = static_cast<std::int32_t>(s[3]);
    if (s[3] == 0) continue;
    const double n = static_cast<double>(s[3]);
    centre.x = static_cast<float>(static_cast<double>(s[0]) / n);
    centre.y = static_cast<float>(static_cast<double>(s[1]) / n);
    centre.intensity = static_cast<float>(static_cast<double>(s[2]) / n);
  }
}

// The centre nearest in position to pixel (x, y), for pixels outside every window.
std::int32_t Segmenter::nearest_centre(const Segmentation& out, int x, int y) const {
  float best = std::numeric_limits<float>::infinity();
  std::int32_t label = 0;
  for (int k = 0; k < out.grid.cells(); ++k) {
    const float dx = x - out.centres[k].x, dy = y - out.centres[k].y;
    const float d = dx * dx + dy * dy;
    if (d < best) best = d, label = k;
  }
  return label;
}

}  // namespace lsgd
