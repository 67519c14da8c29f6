// Image input layer: every frame enters the library as an 8-bit image (gray,
// BGR, RGB or BGRA) and is converted once to a contiguous 8-bit gray image.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cv {
class Mat;
}

namespace lsgd {

// Channel layout of an 8-bit interleaved image.
enum class PixelFormat { kGray8, kBgr8, kRgb8, kBgra8 };

// Non-owning view of caller memory, for callers without OpenCV (a camera
// driver buffer, a ROS message). stride_bytes is the distance between rows.
struct ImageView {
  const std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  std::ptrdiff_t stride_bytes = 0;
  PixelFormat format = PixelFormat::kGray8;
};

// Contiguous 8-bit gray image, row-major, stride == width.
struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;

  std::uint8_t at(int x, int y) const { return pixels[static_cast<std::size_t>(y) * width + x]; }
  bool empty() const { return width == 0 || height == 0; }
};

// Largest accepted side, in pixels: bounds memory (labels and distances are
// 8 bytes per pixel) and keeps every pixel index inside 32 bits.
constexpr int kMaxImageSide = 16384;

// Converts to gray with OpenCV's BGR2GRAY weights (0.299 R + 0.587 G + 0.114 B),
// as the reference implementation does. Throws InvalidArgument for a null or
// zero-size image, a side above kMaxImageSide, more than kMaxImagePixels
// pixels (lsgd/limits.h) or a stride shorter than a row.
void to_gray(const ImageView& view, GrayImage& out);
GrayImage to_gray(const ImageView& view);

// Accepts CV_8UC1 (gray), CV_8UC3 (BGR, OpenCV's order) and CV_8UC4 (BGRA,
// alpha ignored). Rejects with InvalidArgument naming the type: empty images,
// 16-bit and floating-point images (the LSGD descriptor is a histogram of 8-bit
// intensities; convert explicitly, e.g. mat.convertTo(out, CV_8U, 1.0 / 257)),
// and 2-channel images.
void to_gray(const cv::Mat& image, GrayImage& out);
GrayImage to_gray(const cv::Mat& image);

// Wraps a gray image without copying (for OpenCV-based callers and tests).
ImageView view_of(const GrayImage& image);

}  // namespace lsgd
