// Tests of the image input layer (include/lsgd/image.h): conversion of gray,
// BGR, RGB and BGRA 8-bit images to a contiguous gray image, and rejection of
// every unsupported input with InvalidArgument.
#include "lsgd/image.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "lsgd/error.h"
#include "lsgd/limits.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::message_of;
using test::splitmix64;

// Random 8-bit image of the given type (CV_8UC1/3/4), deterministic per seed.
cv::Mat random_mat(int rows, int cols, int type, std::uint64_t seed) {
  cv::Mat m(rows, cols, type);
  std::uint64_t s = seed;
  for (int y = 0; y < rows; ++y) {
    std::uint8_t* row = m.ptr<std::uint8_t>(y);
    for (std::size_t i = 0; i < static_cast<std::size_t>(cols) * m.channels(); ++i) {
      row[i] = static_cast<std::uint8_t>(splitmix64(s) & 0xFF);
    }
  }
  return m;
}

// Compares a GrayImage with an 8-bit single-channel cv::Mat pixel by pixel.
void expect_equal(const GrayImage& gray, const cv::Mat& expected) {
  ASSERT_EQ(expected.type(), CV_8UC1);
  ASSERT_EQ(gray.width, expected.cols);
  ASSERT_EQ(gray.height, expected.rows);
  ASSERT_EQ(gray.pixels.size(), static_cast<std::size_t>(gray.width) * gray.height);
  int mismatches = 0;
  for (int y = 0; y < expected.rows; ++y) {
    for (int x = 0; x < expected.cols; ++x) {
      if (gray.at(x, y) != expected.at<std::uint8_t>(y, x)) ++mismatches;
    }
  }
  EXPECT_EQ(mismatches, 0);
}

// A view of the pixels of `m` (which must outlive it), read as `format`.
ImageView view_of_mat(const cv::Mat& m, PixelFormat format) {
  return ImageView{m.ptr<std::uint8_t>(0), m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step[0]),
                   format};
}

// Copies `src` row by row into a buffer whose rows are `stride` bytes apart;
// the padding bytes are filled with garbage that must never be read.
std::vector<std::uint8_t> padded_copy(const cv::Mat& src, std::size_t stride) {
  const std::size_t row_bytes = static_cast<std::size_t>(src.cols) * src.elemSize();
  std::vector<std::uint8_t> buffer(stride * src.rows, 0xA5);
  for (int y = 0; y < src.rows; ++y) std::memcpy(&buffer[y * stride], src.ptr(y), row_bytes);
  return buffer;
}

TEST(ImageMat, GrayIsCopiedUnchanged) {
  const cv::Mat m = random_mat(37, 53, CV_8UC1, 1);
  expect_equal(to_gray(m), m);
}

TEST(ImageMat, BgrMatchesCvtColor) {
  const cv::Mat m = random_mat(41, 67, CV_8UC3, 2);
  cv::Mat expected;
  cv::cvtColor(m, expected, cv::COLOR_BGR2GRAY);
  expect_equal(to_gray(m), expected);
}

TEST(ImageMat, BgraMatchesCvtColorAndIgnoresAlpha) {
  cv::Mat m = random_mat(29, 31, CV_8UC4, 3);
  cv::Mat expected;
  cv::cvtColor(m, expected, cv::COLOR_BGRA2GRAY);
  const GrayImage a = to_gray(m);
  expect_equal(a, expected);
  // Changing only alpha changes nothing.
  std::vector<cv::Mat> planes;
  cv::split(m, planes);
  planes[3].setTo(cv::Scalar(7));
  cv::Mat m2;
  cv::merge(planes, m2);
  EXPECT_EQ(to_gray(m2).pixels, a.pixels);
}

TEST(ImageMat, KnownBgrWeights) {
  // Pure blue, green, red, white, black: OpenCV weights 0.114 B, 0.587 G, 0.299 R.
  cv::Mat m(1, 5, CV_8UC3);
  m.at<cv::Vec3b>(0, 0) = {255, 0, 0};
  m.at<cv::Vec3b>(0, 1) = {0, 255, 0};
  m.at<cv::Vec3b>(0, 2) = {0, 0, 255};
  m.at<cv::Vec3b>(0, 3) = {255, 255, 255};
  m.at<cv::Vec3b>(0, 4) = {0, 0, 0};
  const GrayImage g = to_gray(m);
  EXPECT_EQ(g.at(0, 0), 29);
  EXPECT_EQ(g.at(1, 0), 150);
  EXPECT_EQ(g.at(2, 0), 76);
  EXPECT_EQ(g.at(3, 0), 255);
  EXPECT_EQ(g.at(4, 0), 0);
}

TEST(ImageMat, ReusesOutputAcrossSizes) {
  GrayImage out;
  to_gray(random_mat(50, 60, CV_8UC3, 4), out);
  EXPECT_EQ(out.width, 60);
  EXPECT_EQ(out.height, 50);
  const cv::Mat small = random_mat(7, 9, CV_8UC1, 5);
  to_gray(small, out);
  expect_equal(out, small);
}

TEST(ImageMat, NonContiguousRoiConvertsCorrectly) {
  const cv::Mat big = random_mat(80, 120, CV_8UC3, 6);
  const cv::Mat roi = big(cv::Rect(13, 7, 51, 33));
  ASSERT_FALSE(roi.isContinuous());
  cv::Mat expected;
  cv::cvtColor(roi.clone(), expected, cv::COLOR_BGR2GRAY);
  expect_equal(to_gray(roi), expected);

  const cv::Mat big_gray = random_mat(80, 120, CV_8UC1, 7);
  const cv::Mat roi_gray = big_gray(cv::Rect(5, 9, 17, 40));
  ASSERT_FALSE(roi_gray.isContinuous());
  expect_equal(to_gray(roi_gray), roi_gray.clone());
}

TEST(ImageMat, SingleColumnAndSingleRowRoi) {
  const cv::Mat big = random_mat(30, 40, CV_8UC1, 8);
  const cv::Mat column = big.col(17);
  expect_equal(to_gray(column), column.clone());
  const cv::Mat row = big.row(3);
  expect_equal(to_gray(row), row.clone());
}

TEST(ImageView, GrayViewEqualsMat) {
  const cv::Mat m = random_mat(19, 23, CV_8UC1, 9);
  expect_equal(to_gray(view_of_mat(m, PixelFormat::kGray8)), m);
}

TEST(ImageView, PaddedStrideEqualsUnpadded) {
  for (const auto& [type, format] :
       std::vector<std::pair<int, PixelFormat>>{{CV_8UC1, PixelFormat::kGray8},
                                                {CV_8UC3, PixelFormat::kBgr8},
                                                {CV_8UC3, PixelFormat::kRgb8},
                                                {CV_8UC4, PixelFormat::kBgra8}}) {
    SCOPED_TRACE(static_cast<int>(format));
    const cv::Mat m = random_mat(21, 33, type, 10 + type);
    const std::size_t row_bytes = static_cast<std::size_t>(m.cols) * m.elemSize();
    ASSERT_TRUE(m.isContinuous());
    const ImageView tight{m.ptr<std::uint8_t>(0), m.cols, m.rows,
                          static_cast<std::ptrdiff_t>(row_bytes), format};
    const std::vector<std::uint8_t> buffer = padded_copy(m, row_bytes + 13);
    const ImageView padded{buffer.data(), m.cols, m.rows,
                           static_cast<std::ptrdiff_t>(row_bytes + 13), format};
    const GrayImage a = to_gray(tight);
    const GrayImage b = to_gray(padded);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.pixels, b.pixels);
  }
}

TEST(ImageView, BgrViewMatchesCvtColor) {
  const cv::Mat m = random_mat(17, 26, CV_8UC3, 11);
  cv::Mat expected;
  cv::cvtColor(m, expected, cv::COLOR_BGR2GRAY);
  expect_equal(to_gray(view_of_mat(m, PixelFormat::kBgr8)), expected);
}

TEST(ImageView, BgraViewMatchesCvtColor) {
  const cv::Mat m = random_mat(17, 26, CV_8UC4, 12);
  cv::Mat expected;
  cv::cvtColor(m, expected, cv::COLOR_BGRA2GRAY);
  expect_equal(to_gray(view_of_mat(m, PixelFormat::kBgra8)), expected);
}

TEST(ImageView, RgbEqualsBgrWithSwappedChannels) {
  const cv::Mat bgr = random_mat(25, 38, CV_8UC3, 13);
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  const GrayImage a = to_gray(view_of_mat(bgr, PixelFormat::kBgr8));
  const GrayImage b = to_gray(view_of_mat(rgb, PixelFormat::kRgb8));
  EXPECT_EQ(a.pixels, b.pixels);
  // And reading the BGR buffer as RGB is a different image (the weights differ).
  EXPECT_NE(to_gray(view_of_mat(bgr, PixelFormat::kRgb8)).pixels, a.pixels);
}

TEST(ImageView, ViewOfRoundTrips) {
  const GrayImage g = to_gray(random_mat(12, 15, CV_8UC1, 14));
  const ImageView v = view_of(g);
  EXPECT_EQ(v.data, g.pixels.data());
  EXPECT_EQ(v.width, 15);
  EXPECT_EQ(v.height, 12);
  EXPECT_EQ(v.stride_bytes, 15);
  EXPECT_EQ(v.format, PixelFormat::kGray8);
  EXPECT_EQ(to_gray(v).pixels, g.pixels);
}

TEST(ImageView, OneByOneAndMaxSide) {
  const std::uint8_t pixel = 77;
  const GrayImage g = to_gray(ImageView{&pixel, 1, 1, 1, PixelFormat::kGray8});
  ASSERT_EQ(g.pixels.size(), 1u);
  EXPECT_EQ(g.at(0, 0), 77);
  // A side of exactly kMaxImageSide is accepted.
  std::vector<std::uint8_t> row(kMaxImageSide, 9);
  const GrayImage wide = to_gray(ImageView{row.data(), kMaxImageSide, 1, kMaxImageSide,
                                           PixelFormat::kGray8});
  EXPECT_EQ(wide.width, kMaxImageSide);
  EXPECT_EQ(wide.height, 1);
}

// ---- rejections

TEST(ImageReject, EmptyMat) {
  EXPECT_THROW(to_gray(cv::Mat()), InvalidArgument);
  EXPECT_THROW(to_gray(cv::Mat(0, 10, CV_8UC1)), InvalidArgument);
}

TEST(ImageReject, SixteenBitMentions16Bit) {
  const cv::Mat m(10, 10, CV_16UC1, cv::Scalar(1000));
  EXPECT_THROW(to_gray(m), InvalidArgument);
  const std::string msg = message_of<InvalidArgument>([&] { to_gray(m); });
  EXPECT_NE(msg.find("16-bit"), std::string::npos) << msg;
  const std::string msg3 = message_of<InvalidArgument>([&] { to_gray(cv::Mat(4, 4, CV_16UC3)); });
  EXPECT_NE(msg3.find("16-bit"), std::string::npos) << msg3;
}

TEST(ImageReject, FloatAndSigned) {
  EXPECT_THROW(to_gray(cv::Mat(10, 10, CV_32FC1, cv::Scalar(0.5))), InvalidArgument);
  EXPECT_THROW(to_gray(cv::Mat(10, 10, CV_64FC1, cv::Scalar(0.5))), InvalidArgument);
  EXPECT_THROW(to_gray(cv::Mat(10, 10, CV_32FC3)), InvalidArgument);
  EXPECT_THROW(to_gray(cv::Mat(10, 10, CV_16SC1)), InvalidArgument);
  EXPECT_THROW(to_gray(cv::Mat(10, 10, CV_8SC1)), InvalidArgument);
  const std::string msg = message_of<InvalidArgument>([] { to_gray(cv::Mat(3, 3, CV_32FC1)); });
  EXPECT_NE(msg.find("float"), std::string::npos) << msg;
}

TEST(ImageReject, TwoChannels) {
  const cv::Mat m(10, 10, CV_8UC2, cv::Scalar(1, 2));
  EXPECT_THROW(to_gray(m), InvalidArgument);
  const std::string msg = message_of<InvalidArgument>([&] { to_gray(m); });
  EXPECT_NE(msg.find("2 channels"), std::string::npos) << msg;
}

TEST(ImageReject, ThreeDimensionalMat) {
  const int sizes[3] = {4, 5, 6};
  const cv::Mat m(3, sizes, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(to_gray(m), InvalidArgument);
}

TEST(ImageReject, MatSideAboveMax) {
  const cv::Mat m(1, kMaxImageSide + 1, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(to_gray(m), InvalidArgument);
  const cv::Mat t(kMaxImageSide + 1, 1, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(to_gray(t), InvalidArgument);
}

TEST(ImageReject, NullData) {
  EXPECT_THROW(to_gray(ImageView{nullptr, 10, 10, 10, PixelFormat::kGray8}), InvalidArgument);
}

TEST(ImageReject, ZeroOrNegativeSize) {
  std::vector<std::uint8_t> buf(100, 0);
  EXPECT_THROW(to_gray(ImageView{buf.data(), 0, 10, 10, PixelFormat::kGray8}), InvalidArgument);
  EXPECT_THROW(to_gray(ImageView{buf.data(), 10, 0, 10, PixelFormat::kGray8}), InvalidArgument);
  EXPECT_THROW(to_gray(ImageView{buf.data(), -3, 10, 10, PixelFormat::kGray8}), InvalidArgument);
  EXPECT_THROW(to_gray(ImageView{buf.data(), 10, -1, 10, PixelFormat::kGray8}), InvalidArgument);
}

TEST(ImageReject, StrideTooShort) {
  std::vector<std::uint8_t> buf(10 * 10 * 4, 0);
  EXPECT_THROW(to_gray(ImageView{buf.data(), 10, 10, 9, PixelFormat::kGray8}), InvalidArgument);
  EXPECT_THROW(to_gray(ImageView{buf.data(), 10, 10, 29, PixelFormat::kBgr8}), InvalidArgument);
  EXPECT_THROW(to_gray(ImageView{buf.data(), 10, 10, 29, PixelFormat::kRgb8}), InvalidArgument);
  EXPECT_THROW(to_gray(ImageView{buf.data(), 10, 10, 39, PixelFormat::kBgra8}), InvalidArgument);
  EXPECT_THROW(to_gray(ImageView{buf.data(), 10, 10, 0, PixelFormat::kGray8}), InvalidArgument);
  EXPECT_THROW(to_gray(ImageView{buf.data(), 10, 10, -10, PixelFormat::kGray8}), InvalidArgument);
  // Exactly one row is fine.
  EXPECT_NO_THROW(to_gray(ImageView{buf.data(), 10, 10, 40, PixelFormat::kBgra8}));
}

TEST(ImageReject, SideAboveMax) {
  std::vector<std::uint8_t> buf(kMaxImageSide + 1, 0);
  EXPECT_THROW(to_gray(ImageView{buf.data(), kMaxImageSide + 1, 1, kMaxImageSide + 1,
                                 PixelFormat::kGray8}),
               InvalidArgument);
  EXPECT_THROW(to_gray(ImageView{buf.data(), 1, kMaxImageSide + 1, 1, PixelFormat::kGray8}),
               InvalidArgument);
}

// The image files' pixel bound holds for frames in memory: refused before
// any pixel is read (the view's rows lie beyond its one row of data).
TEST(ImageReject, MorePixelsThanAnImageFileMayDeclare) {
  std::vector<std::uint8_t> row(kMaxImageSide, 7);
  try {
    to_gray(ImageView{row.data(), kMaxImageSide, kMaxImageSide, kMaxImageSide, PixelFormat::kGray8});
    ADD_FAILURE() << "a 16384 x 16384 frame was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("16384x16384 exceeds the largest supported"), std::string::npos)
        << e.what();
  }
}

TEST(ImageReject, UnknownPixelFormat) {
  std::vector<std::uint8_t> buf(100, 0);
  EXPECT_THROW(to_gray(ImageView{buf.data(), 10, 10, 10, static_cast<PixelFormat>(42)}),
               InvalidArgument);
}

TEST(ImageReject, RejectionIsAnLsgdError) {
  // InvalidArgument derives from lsgd::Error and std::runtime_error.
  EXPECT_THROW(to_gray(cv::Mat()), Error);
  EXPECT_THROW(to_gray(cv::Mat()), std::runtime_error);
}

}  // namespace
}  // namespace lsgd
