// read_image (include/lsgd/io/sequence.h) on progressive JPEGs of many
// scans, written here with libjpeg's own scan scripts: each scan is a pass
// over every coefficient, so their number is a CPU bomb (issue 35).
#include "lsgd/io/sequence.h"

#include <gtest/gtest.h>

// jpeglib.h needs FILE and size_t declared first.
#include <cstdio>
#include <cstddef>
#include <cstdlib>
#include <jpeglib.h>

#include <chrono>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "lsgd/error.h"
#include "lsgd/limits.h"
#include "sequence_test_support.h"
#include "test_util.h"

namespace lsgd::io {
namespace {

using lsgd::test::expect_error;
using test_support::SequenceTest;

// A gray progressive JPEG of `image` in the scans `script` lists.
std::string encode_progressive(const cv::Mat& image, const std::vector<jpeg_scan_info>& script) {
  jpeg_compress_struct info{};
  jpeg_error_mgr error{};
  info.err = jpeg_std_error(&error);
  jpeg_create_compress(&info);
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&info, &buffer, &size);
  info.image_width = static_cast<JDIMENSION>(image.cols);
  info.image_height = static_cast<JDIMENSION>(image.rows);
  info.input_components = 1;
  info.in_color_space = JCS_GRAYSCALE;
  jpeg_set_defaults(&info);
  info.scan_info = script.data();
  info.num_scans = static_cast<int>(script.size());
  jpeg_start_compress(&info, TRUE);
  for (int y = 0; y < image.rows; ++y) {
    JSAMPROW row = const_cast<JSAMPROW>(image.ptr<JSAMPLE>(y));
    jpeg_write_scanlines(&info, &row, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  std::string bytes(reinterpret_cast<const char*>(buffer), size);
  std::free(buffer);
  return bytes;
}

// The DC scan, then coefficients 1 .. `split` each in a first scan (Al 1)
// and a refinement (Ah 1), then the rest of the band in one scan: a valid
// progression of 2 * split + 2 scans.
std::vector<jpeg_scan_info> scans_of(int split) {
  std::vector<jpeg_scan_info> script;
  const auto scan = [&](int ss, int se, int ah, int al) {
    jpeg_scan_info s{};
    s.comps_in_scan = 1;
    s.component_index[0] = 0;
    s.Ss = ss, s.Se = se, s.Ah = ah, s.Al = al;
    script.push_back(s);
  };
  scan(0, 0, 0, 0);
  for (int k = 1; k <= split; ++k) scan(k, k, 0, 1);
  for (int k = 1; k <= split; ++k) scan(k, k, 1, 0);
  scan(split + 1, 63, 0, 0);
  return script;
}

// A valid progression of more than kMaxJpegScans scans is refused as it
// reaches scan 101; one of 98 scans decodes as OpenCV decodes it.
TEST_F(SequenceTest, AJpegOfMoreScansThanEncodersWriteIsRefused) {
  cv::Mat image(64, 96, CV_8UC1);
  cv::randu(image, 0, 255);
  const std::string many = write("many.jpg", encode_progressive(image, scans_of(60)));  // 122 scans
  expect_error<FormatError>([&] { read_image(many); },
                            {many, "more than 100 scans", "refused at scan 101"});
  const std::string fewer = write("fewer.jpg", encode_progressive(image, scans_of(48)));  // 98 scans
  const cv::Mat read = read_image(fewer);
  EXPECT_TRUE(test_support::same(read, cv::imread(fewer, cv::IMREAD_UNCHANGED)));
}

// A scan repeated (an inconsistent progression, which libjpeg warns of and
// decodes on) is refused at the first repetition: a 396 KB file repeating
// one scan 10,000 times took 118 s, 1000 times 14 s, before the refusal.
TEST_F(SequenceTest, AJpegRepeatingAScanIsRefusedAtTheFirstRepetition) {
  const cv::Mat flat(2048, 2048, CV_8UC1, cv::Scalar(128));
  // The DC, the AC band's first pass (Al 1) and its refinement (Ah 1).
  std::vector<jpeg_scan_info> script(3);
  for (jpeg_scan_info& s : script) s.comps_in_scan = 1, s.component_index[0] = 0;
  script[1].Ss = script[2].Ss = 1;
  script[1].Se = script[2].Se = 63;
  script[1].Al = script[2].Ah = 1;
  std::string jpeg = encode_progressive(flat, script);
  // The last scan (the refinement), from its SOS marker to the EOI.
  const std::size_t eoi = jpeg.rfind("\xFF\xD9");
  const std::size_t last = jpeg.rfind("\xFF\xDA");
  ASSERT_NE(eoi, std::string::npos);
  ASSERT_LT(last, eoi);
  const std::string scan = jpeg.substr(last, eoi - last);
  std::string repeated = jpeg.substr(0, eoi);
  for (int k = 0; k < 2000; ++k) repeated += scan;
  const std::string p = write("repeated.jpg", repeated + "\xFF\xD9");
  const auto start = std::chrono::steady_clock::now();
  expect_error<FormatError>([&] { read_image(p); }, {p, "damaged JPEG", "Inconsistent progression"});
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
}

}  // namespace
}  // namespace lsgd::io
