// Superpixel-grid (SG) segmentation, paper Sec. III-B: SLIC-style k-means on
// (x, y, intensity) seeded on a regular grid, where superpixel k keeps the
// identity of grid cell k so that two images can be compared cell by cell.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "lsgd/image.h"
#include "lsgd/options.h"


namespace lsgd {

// The shortest working_side (segmentation.working_side) other than 0.
constexpr int kMinWorkingSide = 16;

struct SegmentationOptions {
  // S_p, the segmentation scale in pixels, in [2, 4096]. The grid has
  // H / (2 S_p) + 1 rows and W / (2 S_p) + 1 columns (see grid_size()).
  int superpixel_size = 40;
  // k-means iterations (assign + update), in [1, 100]. The reference runs 10;
  // 3 is as accurate on corridor, nordland-trimmed and the synthetic street
  // and 3x faster (docs/performance.md); configs/paper.yaml keeps 10.
  int iterations = 3;
  // Divides the squared intensity difference in the fuse distance
  // F_d^2 = d_i^2 / intensity_scale + d_e^2 / distance_scale; in (0, 1e6].
  double intensity_scale = 20.0;
  // Divides the squared pixel distance (pixels^2) in the fuse distance; in (0, 1e6].
  double distance_scale = 1.0;
  // Beyond the paper: a frame whose shorter side is longer than this is
  // scaled down (area averaging) until it is this long before it is
  // segmented and described, so a camera's resolution does not change the
  // grid: the paper's fixed S_p gives a 640x480 frame 63 cells where its
  // 240x192 frames had 12, each cell's histogram a smaller piece of the
  // scene. Pixels, 0 (the frame's own size: the paper) or [16, 16384].
  // The other stages see the frame itself. docs/results.md has the
  // leave-one-sequence-out choice.
  int working_side = 240;

  // Throws InvalidArgument naming the first invalid field.
  void check() const;
  // The options, declared once (lsgd/options.h).
  static const OptionTable<SegmentationOptions>& fields();
};

struct GridSize {
  int rows = 0;
  int cols = 0;
  int cells() const { return rows * cols; }
  bool operator==(const GridSize& o) const { return rows == o.rows && cols == o.cols; }
  bool operator!=(const GridSize& o) const { return !(*this == o); }
};

// Grid of initial centres for an image of width x height pixels and scale S_p,
// as in the reference implementation: rows = height / (2 S_p) + 1 and
// cols = width / (2 S_p) + 1 (integer division), i.e. cells about 2 S_p wide,
// never fewer than one. KITTI 1241x376 with S_p = 40 gives 5 x 16 = 80 cells.
// Throws InvalidArgument for non-positive sizes or S_p.
GridSize grid_size(int width, int height, int superpixel_size);

struct FrameSize {
  int width = 0;
  int height = 0;
};
// The size a width x height frame is segmented at (working_side): the
// shorter side scaled to working_side when it is longer, the longer side in
// proportion (rounded, at least 1); the frame's own size otherwise.
FrameSize working_size(int width, int height, const SegmentationOptions& options);
// The grid of a width x height frame: grid_size() of its working size.
GridSize frame_grid(int width, int height, const SegmentationOptions& options);

// One superpixel centre: mean position (pixels) and mean intensity of its
// pixels, and how many pixels it holds.
struct Centre {
  float x = 0;
  float y = 0;
  float intensity = 0;
  std::int32_t pixels = 0;
};

struct Segmentation {
  GridSize grid;
  int width = 0;
  int height = 0;
  // Cell index (row-major in the grid) of every pixel, row-major, width*height.
  std::vector<std::int32_t> labels;
  // Final centres, one per cell.
  std::vector<Centre> centres;
};

// Receives the image rows in order, each once its labels are final (during
// the last iteration, while the row is still in cache), so that per-pixel
// work on the labels needs no second pass over the image; see
// segment_and_describe() in lsgd/descriptor.h.
class RowSink {
 public:
  // Row y: `width` pixels and their final labels, each in [0, cells).
  virtual void row(int y, const std::uint8_t* pixels, const std::int32_t* labels, int width) = 0;

 protected:
  ~RowSink() = default;
};

// Runs the segmentation. Keeps scratch buffers between calls, so reuse one
// Segmenter per stream of frames; not thread-safe (use one per thread).
class Segmenter {
 public:
  explicit Segmenter(const SegmentationOptions& options = {});
  ~Segmenter();
  Segmenter(Segmenter&&) noexcept;
  Segmenter& operator=(Segmenter&&) noexcept;

  const SegmentationOptions& options() const { return options_; }

  // `image` at its working size (working_size()): `image` itself, or a copy
  // scaled down with cv::INTER_AREA, kept until the next call. What
  // segment_and_describe() segments; segment() takes its image as it is.
  const GrayImage& working(const GrayImage& image);

  // Segments `image` into `out`, reusing out's storage. Every pixel gets a
  // label: each iteration resets the distances, centres are updated to the
  // mean position and intensity of their pixels, an empty cluster keeps its
  // previous centre, and a pixel no window reached joins the nearest centre.
  void segment(const GrayImage& image, Segmentation& out);
  Segmentation segment(const GrayImage& image);
  // The same, handing every row's final labels to `sink` as they are known
  // (out.centres are final only when segment() returns).
  void segment(const GrayImage& image, Segmentation& out, RowSink& sink);

 private:
  void run(const GrayImage& image, Segmentation& out, RowSink* sink);
  void seed(const GrayImage& image, Segmentation& out) const;
  const float* plan(const GrayImage& image, const Segmentation& out, int lanes, float inv_ds);
  void iterate(const GrayImage& image, Segmentation& out, RowSink* sink);
  std::int32_t nearest_centre(const Segmentation& out, int x, int y) const;

  struct Window {
    int x0, x1, y0, y1;
    std::size_t xterm;  // where the centre's x terms start in xterms_
  };
  SegmentationOptions options_;
  // Scratch reused across frames.
  std::vector<float> xterms_;            // per centre: its x-term table (aligned inside)
  std::vector<std::int32_t> lists_;      // the assignment kernel's per-vector segment lists
  std::vector<std::int64_t> sums_;       // per centre: x, y, intensity sums, pixels
  std::vector<Window> windows_;          // per centre, inclusive bounds
  std::vector<std::int64_t> row_start_;  // centres covering row y: row_items_[row_start_[y] ..)
  std::vector<std::int64_t> row_fill_;
  std::vector<std::int32_t> row_items_;
  GrayImage scaled_;                     // working(): the last frame scaled down
  struct Rows;                  // the assignment's row segments (segmentation.cc)
  std::unique_ptr<Rows> rows_;
};

}  // namespace lsgd
