// read_image (include/lsgd/io/sequence.h): formats, damage and truncation,
// bombs refused from the header, read errors. Lists and folders: sequence_test.cc.
#include "lsgd/io/sequence.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/io/config.h"
#include "lsgd/limits.h"
#include "sequence_test_support.h"
#include "test_util.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using lsgd::test::expect_error;

using test_support::random_image;
using test_support::read_bytes;
using test_support::same;
using test_support::SequenceTest;

// ---------------------------------------------------------------- read_image

TEST_F(SequenceTest, PngRoundTripsForGrayBgrAndBgra) {
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4}) {
    const cv::Mat image = random_image(type);
    const std::string p = path("img_" + std::to_string(type) + ".png");
    ASSERT_TRUE(cv::imwrite(p, image));
    const cv::Mat back = read_image(p);
    EXPECT_TRUE(same(back, image)) << "type " << type;
  }
}

TEST_F(SequenceTest, ReadsOtherFormats) {
  const cv::Mat image = random_image(CV_8UC3);
  for (const char* name : {"a.bmp", "a.ppm", "a.jpg"}) {
    ASSERT_TRUE(cv::imwrite(path(name), image)) << name;
    const cv::Mat back = read_image(path(name));
    EXPECT_EQ(back.size(), image.size()) << name;
    EXPECT_EQ(back.type(), CV_8UC3) << name;
  }
  const cv::Mat gray = random_image(CV_8UC1);
  ASSERT_TRUE(cv::imwrite(path("g.pgm"), gray));
  EXPECT_TRUE(same(read_image(path("g.pgm")), gray));
}

TEST_F(SequenceTest, MissingImageIsIoError) {
  const std::string missing = path("missing.png");
  expect_error<IoError>([&] { read_image(missing); }, {missing});
  expect_error<IoError>([&] { read_image(dir_.string()); }, {dir_.string()});
}

TEST_F(SequenceTest, ZeroByteFileIsFormatError) {
  const std::string empty = write("empty.png", "");
  expect_error<FormatError>([&] { read_image(empty); }, {empty, "empty"});
}

TEST_F(SequenceTest, TextFileIsFormatError) {
  const std::string text = write("text.png", "this is not an image\n");
  expect_error<FormatError>([&] { read_image(text); }, {text, "not a decodable image"});
}

TEST_F(SequenceTest, TruncatedPngIsFormatError) {
  const std::string full = path("full.png");
  ASSERT_TRUE(cv::imwrite(full, random_image(CV_8UC3)));
  const std::string bytes = read_bytes(full);
  ASSERT_GT(bytes.size(), 100u);
  const std::string truncated = write("truncated.png", bytes.substr(0, bytes.size() / 2));
  expect_error<FormatError>([&] { read_image(truncated); }, {truncated});
}

// A cut JPEG decodes without an error (the decoder fills the rest with gray
// and only warns): cut anywhere from 1 % to 99.9 %, it must be refused, while
// baseline, progressive and restart-marker JPEGs and one with bytes after its
// end stay readable.
TEST_F(SequenceTest, TruncatedJpegIsFormatErrorAtEveryLength) {
  cv::Mat image(120, 160, CV_8UC3);
  cv::randu(image, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 2);  // compressible, like a photo
  struct Variant {
    const char* name;
    std::vector<int> params;
  };
  const Variant variants[] = {{"baseline", {}},
                              {"progressive", {cv::IMWRITE_JPEG_PROGRESSIVE, 1}},
                              {"restarts", {cv::IMWRITE_JPEG_RST_INTERVAL, 4}}};
  for (const Variant& v : variants) {
    SCOPED_TRACE(v.name);
    std::vector<uchar> encoded;
    ASSERT_TRUE(cv::imencode(".jpg", image, encoded, v.params));
    const std::string bytes(encoded.begin(), encoded.end());
    const std::string full = write(std::string(v.name) + ".jpg", bytes);
    EXPECT_EQ(read_image(full).cols, 160);
    EXPECT_EQ(read_image(write(std::string(v.name) + "-tail.jpg", bytes + "trailing")).cols, 160);
    for (std::size_t cut = bytes.size() / 100; cut < bytes.size(); cut += bytes.size() / 37) {
      const std::string truncated = write("cut.jpg", bytes.substr(0, cut));
      expect_error<FormatError>([&] { read_image(truncated); },
                                {truncated, "truncated or damaged JPEG"});
    }
    // One byte short: the end-of-image marker itself is cut.
    const std::string last = write("last.jpg", bytes.substr(0, bytes.size() - 1));
    expect_error<FormatError>([&] { read_image(last); }, {last, "end-of-image marker"});
  }
}

// A damaged scan that still ends in an end-of-image marker (a cut file with
// the marker appended, a block overwritten by a torn write) decodes with only
// libjpeg warnings: refused with the warning, in every variant.
TEST_F(SequenceTest, DamagedJpegScanIsFormatErrorWithLibjpegsWarning) {
  cv::Mat image(120, 160, CV_8UC3);
  cv::randu(image, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 2);
  for (const std::vector<int>& params :
       {std::vector<int>{}, std::vector<int>{cv::IMWRITE_JPEG_PROGRESSIVE, 1},
        std::vector<int>{cv::IMWRITE_JPEG_RST_INTERVAL, 4}}) {
    std::vector<uchar> encoded;
    ASSERT_TRUE(cv::imencode(".jpg", image, encoded, params));
    const std::string bytes(encoded.begin(), encoded.end());
    for (const double f : {0.3, 0.5, 0.9}) {
      const std::string cut = write(
          "cut-eoi.jpg", bytes.substr(0, static_cast<std::size_t>(f * bytes.size())) + "\xFF\xD9");
      expect_error<FormatError>([&] { read_image(cut); }, {cut, "damaged JPEG", "Corrupt JPEG"});
    }
    std::string torn = bytes;
    std::fill(torn.begin() + static_cast<std::ptrdiff_t>(torn.size() / 2),
              torn.begin() + static_cast<std::ptrdiff_t>(torn.size() / 2 + 512), '\0');
    const std::string zeroed = write("torn.jpg", torn);
    expect_error<FormatError>([&] { read_image(zeroed); }, {zeroed, "damaged JPEG"});
  }
}

// A text file without newlines (or a binary file given as a list) is not
// read into memory: a line longer than kMaxLineBytes is an error naming the
// file and the line.
TEST_F(SequenceTest, OverlongLineInAListIsFormatErrorNamingIt) {
  const std::string list = write("long.txt", "a.png\n" + std::string(kMaxLineBytes + 1, 'x'));
  expect_error<FormatError>([&] { read_image_list(list); }, {list, "line 2", "longer than"});
  const std::string ok = write("ok.txt", "a.png\n" + std::string(4000, 'y') + ".png");
  EXPECT_EQ(read_image_list(ok).size(), 2u);
}

// A NUL inside a line (a UTF-16 list, a binary file) names the line: a path
// cut at it was read as another file, and messages were cut there.
TEST_F(SequenceTest, ANulByteInAListIsFormatErrorNamingTheLine) {
  const std::string list = write("nul.txt", std::string("a.png\nb.png\0garbage\nc.png\n", 26));
  expect_error<FormatError>([&] { read_image_list(list); }, {list, "line 2", "NUL byte"});
  const std::string utf16 = write("utf16.txt", std::string("\xff\xfe" "a\0.\0p\0n\0g\0\n\0", 14));
  expect_error<FormatError>([&] { read_image_list(utf16); }, {utf16, "line 1", "UTF-16"});
}

// read_image decodes JPEGs with libjpeg itself (to see its warnings in the
// same pass): the pixels must be exactly cv::imdecode's, for colour and gray,
// optimised, progressive and restart-interval files.
TEST_F(SequenceTest, JpegDecodingEqualsOpenCvs) {
  cv::Mat colour(77, 131, CV_8UC3);
  cv::randu(colour, 0, 255);
  cv::GaussianBlur(colour, colour, cv::Size(5, 5), 2);
  cv::Mat gray;
  cv::cvtColor(colour, gray, cv::COLOR_BGR2GRAY);
  const std::vector<std::vector<int>> variants = {
      {},
      {cv::IMWRITE_JPEG_PROGRESSIVE, 1},
      {cv::IMWRITE_JPEG_RST_INTERVAL, 4},
      {cv::IMWRITE_JPEG_CHROMA_QUALITY, 20},
      {cv::IMWRITE_JPEG_OPTIMIZE, 1},
      {cv::IMWRITE_JPEG_QUALITY, 30}};
  int k = 0;
  for (const cv::Mat& image : {colour, gray}) {
    for (const std::vector<int>& params : variants) {
      std::vector<uchar> encoded;
      ASSERT_TRUE(cv::imencode(".jpg", image, encoded, params));
      const std::string file = write("eq" + std::to_string(k++) + ".jpg",
                                     std::string(encoded.begin(), encoded.end()));
      const cv::Mat ours = read_image(file);
      const cv::Mat theirs = cv::imdecode(encoded, cv::IMREAD_UNCHANGED);
      ASSERT_EQ(ours.type(), theirs.type()) << file;
      ASSERT_EQ(ours.size(), theirs.size()) << file;
      EXPECT_EQ(cv::norm(ours, theirs, cv::NORM_INF), 0.0) << file;
    }
  }
}

// What cannot be a frame is refused before it is opened: a pipe would block
// forever, a device never ends, a huge file would be read into memory.
TEST_F(SequenceTest, SpecialAndHugeFilesAreRefusedBeforeReading) {
  const std::string fifo = path("pipe.jpg");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expect_error<IoError>([&] { read_image(fifo); }, {fifo, "not a regular file"});
  expect_error<IoError>([&] { read_image("/dev/zero"); }, {"/dev/zero", "not a regular file"});
  const std::string huge = path("huge.jpg");
  {
    std::ofstream f(huge);  // sparse: no disk space used
  }
  fs::resize_file(huge, static_cast<std::uintmax_t>(kMaxImageFileBytes) + 1);
  expect_error<FormatError>([&] { read_image(huge); }, {huge, "bytes, more than"});
  expect_error<IoError>([&] { check_input_file(fifo, "list file"); }, {"list file", fifo});
  const std::string list = path("list.txt");
  ASSERT_EQ(::mkfifo(list.c_str(), 0600), 0);
  expect_error<IoError>([&] { open_sequence(list); }, {list, "neither a folder nor a regular file"});
  expect_error<IoError>([&] { read_image_list(list); }, {list, "not a regular file"});
  EXPECT_NO_THROW(check_input_file(huge, "anything"));  // no size limit asked
}

// A dangling or looping link with an image name is a frame that cannot be
// read (reported, skipped), not a gap that shifts every later frame id.
TEST_F(SequenceTest, BrokenLinksStayInTheFolderListing) {
  const fs::path folder = fs::path(path("links"));
  fs::create_directories(folder);
  ASSERT_TRUE(cv::imwrite((folder / "1.png").string(), random_image(CV_8UC1)));
  fs::create_symlink(folder / "missing.png", folder / "2.png");  // dangling
  fs::create_symlink(folder / "4.png", folder / "3.png");        // a loop
  fs::create_symlink(folder / "3.png", folder / "4.png");
  ASSERT_TRUE(cv::imwrite((folder / "5.png").string(), random_image(CV_8UC1)));
  // A folder, or a link to one, with an image name keeps its place too.
  fs::create_directories(folder / "6.png");
  fs::create_symlink(folder / "6.png", folder / "7.png");
  ASSERT_TRUE(cv::imwrite((folder / "8.png").string(), random_image(CV_8UC1)));
  const auto images = list_images(folder.string());
  ASSERT_EQ(images.size(), 8u);
  EXPECT_EQ(fs::path(images[4]).filename(), "5.png");
  EXPECT_EQ(fs::path(images[7]).filename(), "8.png");
  expect_error<IoError>([&] { read_image(images[1]); }, {images[1], "does not exist"});
  expect_error<IoError>([&] { read_image(images[2]); }, {images[2], "cannot be accessed"});
  expect_error<IoError>([&] { read_image(images[5]); }, {images[5], "is a folder"});
  expect_error<IoError>([&] { read_image(images[6]); }, {images[6], "is a folder"});
  EXPECT_EQ(read_image(images[4]).cols, random_image(CV_8UC1).cols);
}

TEST_F(SequenceTest, SixteenBitPngIsFormatError) {
  cv::Mat deep(8, 8, CV_16UC1, cv::Scalar(1000));
  const std::string p = path("deep.png");
  ASSERT_TRUE(cv::imwrite(p, deep));
  ASSERT_EQ(cv::imread(p, cv::IMREAD_UNCHANGED).depth(), CV_16U);  // the file really is 16-bit
  expect_error<FormatError>([&] { read_image(p); }, {p, "16-bit", "8-bit"});
}

TEST_F(SequenceTest, FloatTiffIsFormatError) {
  cv::Mat real(8, 8, CV_32FC1, cv::Scalar(0.5));
  const std::string p = path("real.tiff");
  bool written = false;
  try {
    written = cv::imwrite(p, real);
  } catch (const cv::Exception&) {
  }
  if (!written) GTEST_SKIP() << "this OpenCV cannot write float TIFF";
  expect_error<FormatError>([&] { read_image(p); }, {p, "float"});
}

// Samples of more than 8 bits, which lsgd does not read, are refused from
// the header, before any decoding: a 391 KB 16-bit RGBA PNG of 8192 x 6144
// pixels cost 458 MB and 2.3 s decoded before its depth was refused.
TEST_F(SequenceTest, SamplesOfMoreThan8BitsAreRefusedFromTheHeader) {
  const cv::Mat deep(8, 8, CV_16UC4, cv::Scalar(1000, 2000, 3000, 4000));
  for (const char* ext : {".png", ".tiff"}) {
    SCOPED_TRACE(ext);
    std::vector<uchar> b;
    ASSERT_TRUE(cv::imencode(ext, deep, b));
    const std::string p = write(std::string("deep") + ext, std::string(b.begin(), b.end()));
    expect_error<FormatError>([&] { read_image(p); }, {p, "16-bit samples", "8-bit", "nothing was decoded"});
  }
  const std::string pgm = write("deep.pgm", "P5 2 2 65535\n" + std::string(8, 'x'));
  expect_error<FormatError>([&] { read_image(pgm); }, {pgm, "16-bit samples", "nothing was decoded"});
  // The bomb: an RGBA 16-bit PNG's header claiming 8192 x 6144 pixels.
  std::vector<uchar> b;
  ASSERT_TRUE(cv::imencode(".png", deep, b));
  std::string bomb(b.begin(), b.end());
  for (const auto& [at, v] : {std::pair<std::size_t, std::uint32_t>{16, 8192}, {20, 6144}}) {
    for (int k = 0; k < 4; ++k) bomb[at + k] = static_cast<char>(v >> (24 - 8 * k));
  }
  const std::string p = write("deep-bomb.png", bomb);
  expect_error<FormatError>([&] { read_image(p); }, {p, "16-bit samples", "nothing was decoded"});
}

// A TIFF's tile is decoded whole, whatever the image's size: a 180-byte
// file of 64 x 64 pixels in tiles of 32768 x 32752 cost 4.3 GB and 12 s
// before it was refused as not decodable. Tiles larger than an image lsgd
// reads are refused from the header; 64 x 64 pixels in one 256 x 256 tile
// (the usual tile, larger than the image) are read.
TEST_F(SequenceTest, TiffTilesLargerThanAnImageLsgdReadsAreRefusedFromTheHeader) {
  // A little-endian TIFF of 64 x 64 pixels, 8-bit gray, uncompressed, in
  // one tile of the given size.
  const auto tiff = [](std::uint32_t tile_width, std::uint32_t tile_height, const std::string& pixels) {
    std::string b = std::string("II*\0", 4);
    const auto u16 = [&](std::uint32_t v) { b += static_cast<char>(v & 0xFF), b += static_cast<char>(v >> 8); };
    const auto u32 = [&](std::uint32_t v) { u16(v & 0xFFFF), u16(v >> 16); };
    u32(8 + static_cast<std::uint32_t>(pixels.size()));
    b += pixels;
    const std::vector<std::array<std::uint32_t, 3>> entries = {  // tag, type, value
        {256, 4, 64}, {257, 4, 64}, {258, 3, 8}, {259, 3, 1}, {262, 3, 1}, {277, 3, 1},
        {322, 4, tile_width}, {323, 4, tile_height}, {324, 4, 8},
        {325, 4, static_cast<std::uint32_t>(pixels.size())}};
    u16(static_cast<std::uint32_t>(entries.size()));
    for (const auto& [tag, type, value] : entries) {
      u16(tag), u16(type), u32(1);
      if (type == 3) {
        u16(value), u16(0);
      } else {
        u32(value);
      }
    }
    u32(0);
    return b;
  };
  for (const auto& [w, h] : {std::pair<std::uint32_t, std::uint32_t>{32768, 32752}, {16384, 16384}, {8192, 8192}}) {
    const std::string p = write("tiles.tiff", tiff(w, h, std::string(64, '\0')));
    expect_error<FormatError>([&] { read_image(p); },
                              {p, "declares tiles of " + std::to_string(w) + " x " + std::to_string(h),
                               "nothing was decoded"});
  }
  const cv::Mat image = read_image(write("tile.tiff", tiff(256, 256, std::string(256 * 256, '\x7f'))));
  EXPECT_EQ(image.cols, 64);
  EXPECT_EQ(image.at<unsigned char>(63, 63), 0x7f);
}

// The size a header declares is checked before anything is decoded: a few
// hundred bytes claiming 30000 x 30000 pixels (decompression bombs) are
// refused at once, in every format lsgd reads (issue 35).
TEST_F(SequenceTest, ImagesDeclaringTooManyPixelsAreRefusedFromTheHeader) {
  const cv::Mat small = random_image(CV_8UC3);
  const auto encode = [&](const char* ext, std::vector<int> params = {}) {
    std::vector<uchar> b;
    EXPECT_TRUE(cv::imencode(ext, small, b, params)) << ext;
    return std::string(b.begin(), b.end());
  };
  const auto put_be16 = [](std::string& b, std::size_t at, int v) {
    b[at] = static_cast<char>(v >> 8), b[at + 1] = static_cast<char>(v & 0xFF);
  };
  const auto put_be32 = [](std::string& b, std::size_t at, std::uint32_t v) {
    for (int k = 0; k < 4; ++k) b[at + k] = static_cast<char>(v >> (24 - 8 * k));
  };
  const auto put_le32 = [](std::string& b, std::size_t at, std::uint32_t v) {
    for (int k = 0; k < 4; ++k) b[at + k] = static_cast<char>(v >> (8 * k));
  };
  std::vector<std::pair<std::string, std::string>> bombs;  // name, bytes
  for (const bool progressive : {false, true}) {
    std::string jpeg = encode(".jpg", {cv::IMWRITE_JPEG_PROGRESSIVE, progressive ? 1 : 0});
    const std::size_t sof = jpeg.find(progressive ? "\xFF\xC2" : "\xFF\xC0");
    ASSERT_NE(sof, std::string::npos);
    put_be16(jpeg, sof + 5, 30000);
    put_be16(jpeg, sof + 7, 30000);
    bombs.emplace_back(progressive ? "progressive.jpg" : "baseline.jpg", jpeg);
  }
  std::string png = encode(".png");
  put_be32(png, 16, 30000);
  put_be32(png, 20, 30000);
  bombs.emplace_back("bomb.png", png);
  std::string bmp = encode(".bmp");
  put_le32(bmp, 18, 30000);
  put_le32(bmp, 22, 30000);
  bombs.emplace_back("bomb.bmp", bmp);
  bombs.emplace_back("bomb.pgm", "P5\n# a comment\n30000 30000\n255\n" + std::string(64, 'x'));
  bombs.emplace_back("wide.pgm", "P5 16385 1 255\n" + std::string(64, 'x'));
  bombs.emplace_back("many.pgm", "P5 8192 8192 255\n" + std::string(64, 'x'));  // 67 M pixels
  for (const auto& [name, bytes] : bombs) {
    SCOPED_TRACE(name);
    const std::string p = write(name, bytes);
    expect_error<FormatError>([&] { read_image(p); }, {p, "declares", "nothing was decoded"});
  }
  // Not one of the formats lsgd reads (a GIF): refused, naming them.
  const std::string gif = write("a.gif", std::string("GIF89a\x10\x00\x10\x00", 10) + std::string(40, '\0'));
  expect_error<FormatError>([&] { read_image(gif); }, {gif, "not a decodable image", "JPEG, PNG"});
}

// A PNG's chunks are walked before libpng sees them (issue 35): a chunk
// longer than the file (a 141-byte file whose tEXt claimed 2 GB cost 2 GB
// and 8 s) and more compressed pixel data than the declared pixels can need
// (1 MB of IDAT holding 960 MB of zeros took 3 s and was kept as a frame)
// are refused without inflating anything; a real PNG is read as before.
TEST_F(SequenceTest, PngChunksLongerThanTheFileOrThePixelsAreRefused) {
  std::vector<uchar> b;
  ASSERT_TRUE(cv::imencode(".png", random_image(CV_8UC1), b));  // 23 x 17 gray, incompressible
  const std::string png(b.begin(), b.end());
  ASSERT_EQ(png.substr(12, 4), "IHDR");
  const std::string head = png.substr(0, 33);  // signature and IHDR
  const auto chunk = [](std::uint32_t length, const std::string& type, const std::string& data) {
    std::string c;
    for (int k = 0; k < 4; ++k) c += static_cast<char>(length >> (24 - 8 * k));
    return c + type + data + std::string(4, '\0');  // the CRC is never read
  };
  const std::string text = write("text.png", head + chunk(0x7ffffff0u, "tEXt", std::string(100, 'a')).substr(0, 108));
  expect_error<FormatError>([&] { read_image(text); },
                            {text, "damaged PNG", "chunk 'tEXt' at byte 33 claims 2147483632 bytes"});
  const std::string idat =
      write("idat.png", head + chunk(30000, "IDAT", std::string(30000, 'x')) + chunk(0, "IEND", ""));
  expect_error<FormatError>([&] { read_image(idat); },
                            {idat, "damaged PNG", "IDAT) holds 30000 compressed bytes", "23 x 17"});
  const std::string cut = write("cut.png", png.substr(0, png.size() / 2));
  expect_error<FormatError>([&] { read_image(cut); }, {cut, "damaged PNG", "truncated or damaged"});
  EXPECT_EQ(read_image(write("whole.png", png)).cols, 23);
}

// A frame that must have the stored frames' size is refused from its header
// when it declares another (an 8192 x 6144 PNG in a 160 x 120 run was
// decoded first: 313 MB, 1.5 s); the run's skip names it.
TEST_F(SequenceTest, AFrameOfAnotherSizeIsRefusedFromItsHeader) {
  std::vector<uchar> b;
  ASSERT_TRUE(cv::imencode(".png", random_image(CV_8UC3), b));  // 23 x 17
  const std::string p = write("other.png", std::string(b.begin(), b.end()));
  expect_error<InvalidArgument>([&] { read_image(p, 40, 30); },
                                {p, "the frame is 23x17, not 40x30 as the frames before it", "nothing was decoded"});
  EXPECT_EQ(read_image(p, 23, 17).cols, 23);
  EXPECT_EQ(read_image(p, 0, 0).cols, 23);  // no size to keep
}

// A progressive JPEG keeps every coefficient until its last scan: one that
// would need more than kMaxJpegCoefficientBytes is refused from its header.
TEST_F(SequenceTest, AProgressiveJpegNeedingTooMuchMemoryIsRefused) {
  const cv::Mat small = random_image(CV_8UC3);
  std::vector<uchar> b;
  ASSERT_TRUE(cv::imencode(".jpg", small, b, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}));
  std::string jpeg(b.begin(), b.end());
  const std::size_t sof = jpeg.find("\xFF\xC2");
  ASSERT_NE(sof, std::string::npos);
  ASSERT_EQ(jpeg[sof + 9], 3);  // three components: sampled 4:4:4 from now on
  for (int c = 0; c < 3; ++c) jpeg[sof + 11 + 3 * c] = 0x11;
  // 8192 x 6000: 49 M pixels (within kMaxImagePixels), 4:4:4, 295 MB of coefficients.
  jpeg[sof + 5] = static_cast<char>(6000 >> 8), jpeg[sof + 6] = static_cast<char>(6000 & 0xFF);
  jpeg[sof + 7] = static_cast<char>(8192 >> 8), jpeg[sof + 8] = static_cast<char>(8192 & 0xFF);
  const std::string p = write("deep.jpg", jpeg);
  expect_error<FormatError>([&] { read_image(p); }, {p, "progressive JPEG of 8192 x 6000", "MB to decode"});
}

// A PNM's samples run from 0 to its maxval: scaled to 0 .. 255.
TEST_F(SequenceTest, PnmMaxvalIsHonoured) {
  const std::string p = write("fifteen.pgm", std::string("P5\n2 2\n15\n\x00\x0F\x07\x08", 15));
  const cv::Mat m = read_image(p);
  ASSERT_EQ(m.type(), CV_8UC1);
  EXPECT_EQ(m.at<uchar>(0, 0), 0);
  EXPECT_EQ(m.at<uchar>(0, 1), 255);
  EXPECT_EQ(m.at<uchar>(1, 0), 119);
  EXPECT_EQ(m.at<uchar>(1, 1), 136);
  const std::string full = write("full.pgm", std::string("P5\n2 1\n255\n\x00\x0F", 13));
  EXPECT_EQ(read_image(full).at<uchar>(0, 1), 15);
}

// A binary PNM with fewer pixel bytes than its header declares is refused
// as truncated from its header (OpenCV printed its own "can't read data"
// line on stderr first); with every byte it reads.
TEST_F(SequenceTest, TruncatedPnmIsRefusedFromItsHeader) {
  const std::pair<std::string, std::size_t> images[] = {
      {"P5\n4 4\n255\n", 16}, {"P6\n4 4\n255\n", 48}, {"P5\n4 4\n65535\n", 32},
      {"P4\n9 4\n", 8},       {"P7\nWIDTH 4\nHEIGHT 4\nDEPTH 3\nMAXVAL 255\nTUPLTYPE RGB\nENDHDR\n", 48}};
  int k = 0;
  for (const auto& [header, pixels] : images) {
    SCOPED_TRACE(header);
    const std::string cut = write("cut" + std::to_string(k) + ".pnm", header + std::string(pixels - 1, '\x40'));
    expect_error<FormatError>([&] { read_image(cut); }, {"image '" + cut + "'", "(truncated)"});
    const std::string whole = write("whole" + std::to_string(k++) + ".pnm", header + std::string(pixels, '\x40'));
    if (header.find("65535") == std::string::npos) {  // 16-bit samples are refused as such
      EXPECT_EQ(read_image(whole).cols, header[1] == '4' ? 9 : 4);
    }
  }
}

// Plain (ASCII) PNM: cut short, a sample that is no number or above maxval
// is refused from lsgd's own walk of the samples (OpenCV printed its own
// multi-line "can't read data" or "Unexpected code" text on stderr, or
// clipped the sample); a whole one, comments and unseparated bits included,
// reads as OpenCV reads it.
TEST_F(SequenceTest, PlainPnmSamplesAreCheckedBeforeDecoding) {
  const std::pair<std::string, std::string> bad[] = {
      {"P2\n4 4\n255\n" + std::string("1 2 3 4 5 6 7 8"), "it holds 8 of the 16 samples"},
      {"P3\n2 2\n255\n1 2 3 4 5 6 7 8 9 10 11", "it holds 11 of the 12 samples"},
      {"P1\n4 2\n0101 011", "it holds 7 of the 8 samples"},
      {"P2\n2 1\n100\n5 x", "its sample 1 is not a number"},
      {"P2\n2 1\n255\n5 99999", "its sample 1 is 99999, above its maxval 255"},
      {"P1\n2 1\n0 2", "its sample 1 is 2, above its maxval 1"}};
  int k = 0;
  for (const auto& [text, expected] : bad) {
    SCOPED_TRACE(text);
    const std::string path = write("plain" + std::to_string(k++) + ".pnm", text);
    expect_error<FormatError>([&] { read_image(path); }, {"image '" + path + "'", expected});
  }
  const std::string bits = write("bits.pbm", "P1\n# four by two\n4 2\n0101\n1 0 # end\n 1 0\n");
  const cv::Mat m = read_image(bits);
  ASSERT_EQ(m.cols, 4);
  const std::string gray = write("gray.pgm", "P2 2 2 15 0 15 7 8\n");
  const cv::Mat g = read_image(gray);
  ASSERT_EQ(g.type(), CV_8UC1);
  EXPECT_EQ(g.at<uchar>(0, 1), 255);
}

// A read error of the system (EIO; /proc/self/mem gives one at offset 0)
// is an IoError naming the file and the reason, for an image, a list file
// and a config, never the stream library's bare "basic_filebuf::underflow".
TEST_F(SequenceTest, ReadErrorsNameTheFileAndTheReason) {
  const std::string eio = "/proc/self/mem";
  std::error_code ec;
  if (!fs::is_regular_file(eio, ec)) GTEST_SKIP() << eio << " is not here";
  expect_error<IoError>([&] { read_image(eio); }, {"image '" + eio + "'", "Input/output error"});
  expect_error<IoError>([&] { read_image_list(eio); }, {eio, "line 1", "Input/output error"});
  expect_error<IoError>([&] { load_config(eio); }, {"config '" + eio + "'", "Input/output error"});
}

}  // namespace
}  // namespace lsgd::io
