#include "lsgd/image.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "internal/check.h"
#include "lsgd/limits.h"

namespace lsgd {
namespace {

int channels_of(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGray8: return 1;
    case PixelFormat::kBgr8:
    case PixelFormat::kRgb8: return 3;
    case PixelFormat::kBgra8: return 4;
  }
  internal::throw_invalid("unknown pixel format ", static_cast<int>(format));
}

void check_view(const ImageView& view) {
  if (view.data == nullptr) internal::throw_invalid("image has no data (null pointer)");
  if (view.width <= 0 || view.height <= 0) {
    internal::throw_invalid("image size ", view.width, "x", view.height, " is empty");
  }
  if (view.width > kMaxImageSide || view.height > kMaxImageSide) {
    internal::throw_invalid("image size ", view.width, "x", view.height,
                            " exceeds the largest supported side of ", kMaxImageSide, " pixels");
  }
  // The image files' bound (lsgd/limits.h), for frames given in memory too
  // (a Python array broadcast to 16384 x 16384 cost 2.2 GB and 8 s).
  if (static_cast<std::int64_t>(view.width) * view.height > kMaxImagePixels) {
    internal::throw_invalid("image size ", view.width, "x", view.height, " exceeds the largest supported ",
                            kMaxImagePixels, " pixels (8192 x 6144)");
  }
  const std::ptrdiff_t row_bytes =
      static_cast<std::ptrdiff_t>(view.width) * channels_of(view.format);
  if (view.stride_bytes < row_bytes) {
    internal::throw_invalid("image stride ", view.stride_bytes, " bytes is shorter than a row (",
                            row_bytes, " bytes)");
  }
}

}  // namespace

void to_gray(const ImageView& view, GrayImage& out) {
  check_view(view);
  const int channels = channels_of(view.format);
  const cv::Mat in(view.height, view.width, CV_8UC(channels), const_cast<std::uint8_t*>(view.data),
                   static_cast<std::size_t>(view.stride_bytes));
  out.width = view.width;
  out.height = view.height;
  out.pixels.resize(static_cast<std::size_t>(view.width) * view.height);
  cv::Mat gray(view.height, view.width, CV_8UC1, out.pixels.data());
  switch (view.format) {
    case PixelFormat::kGray8: in.copyTo(gray); break;
    case PixelFormat::kBgr8: cv::cvtColor(in, gray, cv::COLOR_BGR2GRAY); break;
    case PixelFormat::kRgb8: cv::cvtColor(in, gray, cv::COLOR_RGB2GRAY); break;
    case PixelFormat::kBgra8: cv::cvtColor(in, gray, cv::COLOR_BGRA2GRAY); break;
  }
}

GrayImage to_gray(const ImageView& view) {
  GrayImage out;
  to_gray(view, out);
  return out;
}

void to_gray(const cv::Mat& image, GrayImage& out) {
  if (image.empty()) internal::throw_invalid("image is empty (0x0 or no data)");
  if (image.dims != 2) internal::throw_invalid("image has ", image.dims, " dimensions, expected 2");
  if (image.depth() != CV_8U) {
    const char* depth = image.depth() == CV_16U   ? "16-bit unsigned"
                        : image.depth() == CV_16S ? "16-bit signed"
                        : image.depth() == CV_32F ? "32-bit float"
                        : image.depth() == CV_64F ? "64-bit float"
                                                  : "non-8-bit";
    internal::throw_invalid("image type ", cv::typeToString(image.type()), " (", depth,
                            ") is not supported: the LSGD descriptor is a histogram of 8-bit "
                            "intensities; convert first, e.g. mat.convertTo(out, CV_8U, 1.0 / 257)");
  }
  ImageView view;
  view.data = image.ptr<std::uint8_t>(0);
  view.width = image.cols;
  view.height = image.rows;
  view.stride_bytes = static_cast<std::ptrdiff_t>(image.step[0]);
  switch (image.channels()) {
    case 1: view.format = PixelFormat::kGray8; break;
    case 3: view.format = PixelFormat::kBgr8; break;
    case 4: view.format = PixelFormat::kBgra8; break;
    default:
      internal::throw_invalid("image type ", cv::typeToString(image.type()), " has ",
                              image.channels(), " channels: expected 1 (gray), 3 (BGR) or 4 (BGRA)");
  }
  to_gray(view, out);
}

GrayImage to_gray(const cv::Mat& image) {
  GrayImage out;
  to_gray(image, out);
  return out;
}

ImageView view_of(const GrayImage& image) {
  return {image.pixels.data(), image.width, image.height, image.width, PixelFormat::kGray8};
}

}  // namespace lsgd
