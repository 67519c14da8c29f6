#include "lsgd/io/files.h"
#include "lsgd/io/sequence.h"

#include <sys/stat.h>

#include <algorithm>
#include <climits>
#include <array>
#include <cctype>
#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <new>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <jpeglib.h>
#include <jerror.h>
#include <string>
#include <system_error>
#include <vector>

#include "internal/check.h"
#include "io/image_header.h"
#include "lsgd/error.h"
#include "lsgd/image.h"
#include "lsgd/limits.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using internal::concat;

constexpr std::array<const char*, 8> kImageExtensions = {".png", ".jpg", ".jpeg", ".bmp",
                                                         ".pgm", ".ppm", ".tif",  ".tiff"};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool has_image_extension(const fs::path& path) {
  const std::string ext = lower(path.extension().string());
  return std::find(kImageExtensions.begin(), kImageExtensions.end(), ext) != kImageExtensions.end();
}

std::string extension_list() {
  std::string out;
  for (const char* ext : kImageExtensions) out += concat(out.empty() ? "" : " ", ext);
  return out;
}

bool is_digit(char c) { return c >= '0' && c <= '9'; }

// Compares the digit runs a[ia, ea) and b[ib, eb) by numeric value without
// converting them (runs may be longer than any integer type). Returns <0, 0, >0.
int compare_digit_runs(const std::string& a, std::size_t ia, std::size_t ea, const std::string& b,
                       std::size_t ib, std::size_t eb) {
  while (ia < ea && a[ia] == '0') ++ia;
  while (ib < eb && b[ib] == '0') ++ib;
  const std::size_t la = ea - ia;
  const std::size_t lb = eb - ib;
  if (la != lb) return la < lb ? -1 : 1;
  return a.compare(ia, la, b, ib, lb);
}

std::size_t digit_run_end(const std::string& s, std::size_t i) {
  while (i < s.size() && is_digit(s[i])) ++i;
  return i;
}

// Natural comparison: <0, 0, >0. Equal values with different leading zeros
// compare equal here; `zeros` receives the first such difference
// (fewer zeros first) to break the tie.
int natural_compare(const std::string& a, const std::string& b, int& zeros) {
  std::size_t i = 0;
  std::size_t j = 0;
  zeros = 0;
  while (i < a.size() && j < b.size()) {
    if (is_digit(a[i]) && is_digit(b[j])) {
      const std::size_t ei = digit_run_end(a, i);
      const std::size_t ej = digit_run_end(b, j);
      const int c = compare_digit_runs(a, i, ei, b, j, ej);
      if (c != 0) return c;
      // Same value: the longer run has more leading zeros.
      if (zeros == 0 && ei - i != ej - j) zeros = (ei - i) < (ej - j) ? -1 : 1;
      i = ei;
      j = ej;
      continue;
    }
    const auto ca = static_cast<unsigned char>(a[i]);
    const auto cb = static_cast<unsigned char>(b[j]);
    if (ca != cb) return ca < cb ? -1 : 1;
    ++i;
    ++j;
  }
  if (i < a.size()) return 1;   // b is a prefix of a
  if (j < b.size()) return -1;  // a is a prefix of b
  return 0;
}

std::string trim(const std::string& line) {
  const char* kSpace = " \t\r\n\f\v";
  const std::size_t first = line.find_first_not_of(kSpace);
  if (first == std::string::npos) return {};
  const std::size_t last = line.find_last_not_of(kSpace);
  return line.substr(first, last - first + 1);
}

}  // namespace

std::vector<std::string> list_images(const std::string& path, NameOrder order) {
  std::error_code ec;
  fs::directory_iterator it(path, ec);
  if (ec) throw IoError(concat("cannot read folder '", path, "': ", ec.message()));
  std::vector<std::string> names;
  for (const fs::directory_iterator end; it != end; it.increment(ec)) {
    // Everything with an image name is a frame: a dangling or looping link,
    // or a folder (or a link to one) named like an image too, so that it is
    // reported when read (and skipped) instead of vanishing and shifting
    // every later frame id.
    if (has_image_extension(it->path())) names.push_back(it->path().filename().string());
    if (static_cast<std::int64_t>(names.size()) > kMaxFrames) {
      throw FormatError(concat("folder '", path, "' holds more than ", kMaxFrames,
                               " images, the most a sequence may have"));
    }
  }
  if (ec) throw IoError(concat("cannot read folder '", path, "': ", ec.message()));
  if (names.empty()) {
    throw FormatError(
        concat("no images in folder '", path, "' (looked for ", extension_list(), ", any case)"));
  }
  if (order == NameOrder::kNatural) {
    std::sort(names.begin(), names.end(), natural_less);
  } else {
    std::sort(names.begin(), names.end());
  }
  std::vector<std::string> images;
  images.reserve(names.size());
  for (const std::string& name : names) images.push_back((fs::path(path) / name).string());
  return images;
}

std::vector<std::string> read_image_list(const std::string& path) {
  check_input_file(path, "list file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(concat("cannot read list file '", path, "'"));
  skip_utf8_bom(in);
  const fs::path folder = fs::path(path).parent_path();
  std::vector<std::string> images;
  std::string line;
  for (std::int64_t number = 1; read_line(in, line, path, number); ++number) {
    // A UTF-8 BOM at the start of any line: lists joined with cat keep each
    // file's own (no file name starts with U+FEFF).
    if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    const std::string entry = trim(line);
    if (entry.empty() || entry[0] == '#') continue;
    // No file name holds a NUL: the line is damaged (a UTF-16 list, a binary
    // file), and a path cut at it would name another file.
    if (entry.find('\0') != std::string::npos) {
      throw FormatError(concat("list file '", path, "' line ", number, " holds a NUL byte (a UTF-16 "
                               "or binary file?): list one UTF-8 path per line"));
    }
    // Longer than any path the system opens (PATH_MAX with its NUL): the line
    // is no path. Skipped, it was named whole, twice, on every skip line (a
    // 1 MB list of 15 such lines wrote 2 MB on stderr).
    if (entry.size() >= PATH_MAX) {
      throw FormatError(concat("list file '", path, "' line ", number, " is ", entry.size(),
                               " bytes long, more than any path the system opens (", PATH_MAX - 1,
                               "): list one path per line"));
    }
    const fs::path image(entry);
    images.push_back(image.is_absolute() ? image.string() : (folder / image).string());
    if (static_cast<std::int64_t>(images.size()) > kMaxFrames) {
      throw FormatError(concat("list file '", path, "' lists more than ", kMaxFrames,
                               " images, the most a sequence may have"));
    }
  }
  if (in.bad()) throw IoError(concat("cannot read list file '", path, "'"));
  if (images.empty()) {
    throw FormatError(concat("list file '", path,
                             "' lists no images (one path per line; blank lines and lines "
                             "starting with '#' are skipped)"));
  }
  return images;
}

namespace {

const char* depth_name(int depth) {
  switch (depth) {
    case CV_8S:
      return "8-bit signed";
    case CV_16U:
      return "16-bit unsigned";
    case CV_16S:
      return "16-bit signed";
    case CV_32S:
      return "32-bit integer";
    case CV_32F:
      return "32-bit float";
    case CV_64F:
      return "64-bit float";
    case CV_16F:
      return "16-bit float";
    default:
      return "unknown";
  }
}

// Reads the whole file; IoError when it is missing or unreadable.
std::vector<unsigned char> read_bytes(const std::string& path) {
  check_input_file(path, "image", kMaxImageFileBytes);
  return read_file(path, "image", kMaxImageFileBytes);
}

// JPEG decoders fill a truncated file with gray and only warn, so a cut JPEG
// would decode as a plausible frame. Walks the marker segments and the
// entropy-coded data of every scan up to the end-of-image marker (EOI);
// returns false when the bytes end before it.
bool jpeg_reaches_eoi(const std::vector<unsigned char>& b) {
  const std::size_t n = b.size();
  std::size_t p = 2;  // after SOI
  while (true) {
    if (p >= n || b[p] != 0xFF) return false;
    while (p < n && b[p] == 0xFF) ++p;  // fill bytes
    if (p >= n) return false;
    const unsigned char marker = b[p++];
    if (marker == 0xD9) return true;                                    // EOI
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // no length
    if (p + 2 > n) return false;
    const std::size_t length = static_cast<std::size_t>(b[p]) << 8 | b[p + 1];
    if (length < 2 || p + length > n) return false;
    p += length;
    if (marker != 0xDA) continue;  // not a scan
    // Entropy-coded data: ends at an 0xFF that is neither stuffing (0xFF00)
    // nor a restart marker.
    while (true) {
      while (p < n && b[p] != 0xFF) ++p;
      if (p + 1 >= n) return false;
      const unsigned char next = b[p + 1];
      if (next == 0x00 || (next >= 0xD0 && next <= 0xD7) || next == 0xFF) {
        p += next == 0xFF ? 1 : 2;
        continue;
      }
      break;  // p is at the next marker
    }
  }
}

// What libjpeg says about a JPEG's data: it decodes damaged scans with only
// warnings (and fills what it lost), so a file whose entropy-coded data was
// cut, overwritten or bit-flipped can still decode to a plausible frame.
// Reads every scan to its DCT coefficients (no inverse DCT, no colour
// conversion: the entropy decoding that finds the damage, about a third of a
// full decode) and returns the first warning that means lost data, or "".
// JPEG has no checksum: a flip that still decodes without a warning cannot be
// told from a real image (docs/reliability.md).
struct JpegCheck {
  jpeg_error_mgr pub;
  jpeg_progress_mgr progress;
  std::jmp_buf jump;
  std::string damage;   // the first warning that means lost data
  std::string refused;  // more scans than kMaxJpegScans
};

void jpeg_fail(j_common_ptr info) {
  JpegCheck* check = reinterpret_cast<JpegCheck*>(info->err);
  char text[JMSG_LENGTH_MAX];
  (*info->err->format_message)(info, text);
  check->damage = text;
  std::longjmp(check->jump, 1);
}

void jpeg_message(j_common_ptr info, int level) {
  if (level >= 0) return;  // trace messages
  JpegCheck* check = reinterpret_cast<JpegCheck*>(info->err);
  const int code = info->err->msg_code;
  // Extraneous bytes before a marker: the Huffman decoder finished the scan
  // before its data did, i.e. it lost its place (a flipped bit in the scan
  // shows up as this far more often than as a bad code).
  const bool lost = code == JWRN_HIT_MARKER || code == JWRN_HUFF_BAD_CODE ||
                    code == JWRN_JPEG_EOF || code == JWRN_MUST_RESYNC ||
                    code == JWRN_ARITH_BAD_CODE || code == JWRN_BOGUS_PROGRESSION ||
                    code == JWRN_NOT_SEQUENTIAL || code == JWRN_EXTRANEOUS_DATA;
  if (lost && check->damage.empty()) {
    char text[JMSG_LENGTH_MAX];
    (*info->err->format_message)(info, text);
    check->damage = text;
    // The file is refused: decoding on (libjpeg would) only costs time; a
    // 396 KB file repeating one progressive scan 10,000 times took 118 s.
    std::longjmp(check->jump, 1);
  }
}

// Called by libjpeg as it reads; stops a JPEG of more than kMaxJpegScans
// scans (libjpeg-turbo's djpeg -maxscans does the same).
void jpeg_progress(j_common_ptr info) {
  JpegCheck* check = reinterpret_cast<JpegCheck*>(info->err);
  const int scan = reinterpret_cast<j_decompress_ptr>(info)->input_scan_number;
  if (scan > kMaxJpegScans) {
    check->refused = concat("a progressive JPEG of more than ", kMaxJpegScans,
                            " scans (encoders write up to a few dozen), each a pass over every "
                            "coefficient: refused at scan ", scan);
    std::longjmp(check->jump, 1);
  }
}

// Decodes a JPEG with libjpeg-turbo in one pass, watching its warnings:
// returns the first one that means lost data ("" when none). A gray or
// three-component (YCbCr, RGB) JPEG is decoded into `out` (8-bit gray or
// BGR) as OpenCV's decoder does it (the same library, default DCT and
// upsampling: tests/sequence_test.cc checks equality with cv::imdecode);
// other colour spaces (CMYK) are only checked, with `out` left empty, and
// decoded by OpenCV after.
// `refused`: set, with nothing decoded, when a progressive (or multi-scan)
// JPEG would need more than kMaxJpegCoefficientBytes for its coefficients.
std::string decode_jpeg(const std::vector<unsigned char>& bytes, cv::Mat& out, std::string& refused) {
  jpeg_decompress_struct info{};
  JpegCheck check{};
  info.err = jpeg_std_error(&check.pub);
  check.pub.error_exit = jpeg_fail;
  check.pub.emit_message = jpeg_message;
  check.progress.progress_monitor = jpeg_progress;
  if (setjmp(check.jump) != 0) {
    jpeg_destroy_decompress(&info);
    out.release();
    refused = check.refused;
    return check.refused.empty() ? check.damage : "";
  }
  jpeg_create_decompress(&info);
  info.progress = &check.progress;
  jpeg_mem_src(&info, bytes.data(), static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(&info, TRUE);
  if (jpeg_has_multiple_scans(&info)) {  // every coefficient is kept until the last scan
    std::int64_t coefficients = 0;
    for (int c = 0; c < info.num_components; ++c) {
      coefficients += static_cast<std::int64_t>(info.comp_info[c].width_in_blocks) *
                      info.comp_info[c].height_in_blocks * DCTSIZE2 * sizeof(JCOEF);
    }
    if (coefficients > kMaxJpegCoefficientBytes) {
      refused = concat("a progressive JPEG of ", info.image_width, " x ", info.image_height,
                       " pixels needs ", coefficients >> 20, " MB to decode, above the ",
                       kMaxJpegCoefficientBytes >> 20, " MB lsgd allows (nothing was decoded)");
      jpeg_destroy_decompress(&info);
      return "";
    }
  }
  const bool gray = info.num_components == 1;
  const bool colour = info.num_components == 3 &&
                      (info.jpeg_color_space == JCS_YCbCr || info.jpeg_color_space == JCS_RGB);
  if (gray || colour) {
    info.out_color_space = gray ? JCS_GRAYSCALE : JCS_EXT_BGR;
    jpeg_start_decompress(&info);
    out.create(static_cast<int>(info.output_height), static_cast<int>(info.output_width),
               gray ? CV_8UC1 : CV_8UC3);
    while (info.output_scanline < info.output_height) {
      JSAMPROW row = out.ptr<JSAMPLE>(static_cast<int>(info.output_scanline));
      jpeg_read_scanlines(&info, &row, 1);
    }
  } else {
    jpeg_read_coefficients(&info);  // the entropy decoding, where damage shows
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  if (!check.damage.empty()) out.release();
  return check.damage;
}

void check_decoded(const cv::Mat& image, const std::string& path) {
  if (image.depth() != CV_8U) {
    throw FormatError(concat("image '", path, "' has ", depth_name(image.depth()),
                             " depth; only 8-bit images are supported: convert it to 8-bit"));
  }
  const int channels = image.channels();
  if (channels != 1 && channels != 3 && channels != 4) {
    throw FormatError(concat("image '", path, "' has ", channels,
                             " channels; only 1 (gray), 3 (BGR) or 4 (BGRA) are supported"));
  }
}

}  // namespace

bool skip_utf8_bom(std::istream& in) {
  const std::streampos start = in.tellg();
  char bom[3] = {};
  if (in.read(bom, 3) && bom[0] == '\xEF' && bom[1] == '\xBB' && bom[2] == '\xBF') return true;
  in.clear();
  in.seekg(start);
  return false;
}

void check_input_file(const std::string& path, const std::string& what, std::int64_t max_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int error = errno;
    throw IoError(concat(what, " '", path, "' ",
                         error == ENOENT ? std::string("does not exist")
                                         : concat("cannot be accessed: ", std::strerror(error))));
  }
  if (S_ISDIR(st.st_mode)) throw IoError(concat(what, " '", path, "' is a folder"));
  if (!S_ISREG(st.st_mode)) {
    throw IoError(concat(what, " '", path,
                         "' is not a regular file (a pipe, device or socket), which could block "
                         "or never end"));
  }
  if (max_bytes >= 0 && st.st_size > max_bytes) {
    throw FormatError(concat(what, " '", path, "' has ", st.st_size, " bytes, more than the ",
                             max_bytes, " this lsgd reads"));
  }
}

bool natural_less(const std::string& a, const std::string& b) {
  int zeros = 0;
  const int c = natural_compare(a, b, zeros);
  if (c != 0) return c < 0;
  if (zeros != 0) return zeros < 0;
  return a < b;  // only reached for equal strings, kept for safety
}

Sequence open_sequence(const std::string& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (status.type() == fs::file_type::not_found || path.empty()) {
    throw IoError(concat("sequence '", path, "' does not exist"));
  }
  if (ec) throw IoError(concat("cannot access sequence '", path, "': ", ec.message()));
  Sequence sequence;
  sequence.source = path;
  if (fs::is_directory(status)) {
    sequence.images = list_images(path);
  } else if (has_image_extension(path)) {
    throw FormatError(
        concat("sequence '", path, "' is a single image; give a folder of images or a list file"));
  } else if (fs::is_regular_file(status)) {
    sequence.images = read_image_list(path);
    sequence.files = {path};
  } else {
    throw IoError(concat("sequence '", path, "' is neither a folder nor a regular file"));
  }
  return sequence;
}

namespace {

// The pixels of an image file whose header was checked: libjpeg for a JPEG
// (one pass that also sees its warnings, which OpenCV drops), OpenCV for the
// rest. FormatError for a damaged file.
cv::Mat decode(const std::vector<unsigned char>& bytes, bool jpeg, const std::string& path) {
  cv::Mat image;
  // One decoding pass that also sees libjpeg's warnings (OpenCV drops them).
  if (jpeg) {
    std::string refused;
    if (const std::string damage = decode_jpeg(bytes, image, refused); !damage.empty()) {
      throw FormatError(concat("image '", path, "' is a damaged JPEG: ", damage));
    }
    if (!refused.empty()) throw FormatError(concat("image '", path, "': ", refused));
  }
  if (image.empty()) {  // not a JPEG, or one libjpeg only checked (CMYK)
    // IMREAD_UNCHANGED keeps gray/BGR/BGRA and the stored depth; it does not
    // apply EXIF orientation, so frames are used exactly as stored.
    image = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  }
  if (image.empty()) {
    throw FormatError(concat("'", path,
                             "' is not a decodable image (corrupt, truncated or unsupported "
                             "format)"));
  }
  return image;
}

// What a header declares that lsgd does not read, refused before any
// decoder allocates it: more pixels or larger tiles.
void check_declared_size(const header::ImageHeader& declared, const std::string& path) {
  if (declared.width > kMaxImageSide || declared.height > kMaxImageSide ||
      declared.width * declared.height > kMaxImagePixels) {
    throw FormatError(concat("image '", path, "' declares ", declared.width, " x ", declared.height,
                             " pixels, more than lsgd reads (sides up to ", kMaxImageSide, ", ",
                             kMaxImagePixels, " pixels in all); nothing was decoded"));
  }
  // A TIFF's tile is decoded whole into a buffer of its own: a 180-byte
  // file of 64 x 64 pixels in tiles of 32768 x 32752 cost 4.3 GB and 12 s.
  if (declared.tile_width > kMaxImageSide || declared.tile_height > kMaxImageSide ||
      std::max<std::int64_t>(declared.tile_width, 0) * std::max<std::int64_t>(declared.tile_height, 0) >
          kMaxImagePixels) {
    throw FormatError(concat("image '", path, "' declares tiles of ", declared.tile_width, " x ",
                             declared.tile_height, " pixels, more than lsgd reads (sides up to ", kMaxImageSide,
                             ", ", kMaxImagePixels, " pixels in all); nothing was decoded"));
  }
}

}  // namespace

cv::Mat read_image(const std::string& path) { return read_image(path, 0, 0); }

cv::Mat read_image(const std::string& path, int width, int height) {
  const std::vector<unsigned char> bytes = read_bytes(path);
  if (bytes.empty()) throw FormatError(concat("image '", path, "' is an empty file (0 bytes)"));
  // The size the header declares, checked before a decoder allocates it.
  const header::ImageHeader declared = header::read_header(bytes);
  if (declared.format.empty()) {
    throw FormatError(concat("'", path, "' is not a decodable image: it does not start as one of the "
                             "formats lsgd reads (", header::known_formats(), ")"));
  }
  const bool jpeg = declared.format == "JPEG";
  if (jpeg && !jpeg_reaches_eoi(bytes)) {
    throw FormatError(concat("image '", path, "' is a truncated or damaged JPEG: its ",
                             bytes.size(), " bytes end before the end-of-image marker"));
  }
  if (declared.width <= 0 || declared.height <= 0) {
    throw FormatError(concat("image '", path, "' is a damaged ", declared.format,
                             ": its header gives no size"));
  }
  check_declared_size(declared, path);
  // Damage the structure shows (after the size: a bomb is said as one).
  if (!declared.damage.empty()) {
    throw FormatError(concat("image '", path, "' is a damaged ", declared.format, ": ", declared.damage));
  }
  // Samples of more than 8 bits are refused from the header too: a 391 KB
  // 16-bit RGBA PNG of 8192 x 6144 pixels cost 458 MB and 2.3 s decoded
  // before its depth was refused.
  if (declared.sample_bits > 8) {
    throw FormatError(concat("image '", path, "' has ", declared.sample_bits, "-bit ",
                             declared.float_samples ? "floating-point " : "",
                             "samples (its header says); only 8-bit images are supported: convert it to "
                             "8-bit (nothing was decoded)"));
  }
  // Another size than the stored frames': refused before decoding (an
  // 8192 x 6144 PNG in a 160 x 120 run cost 313 MB and 1.5 s first).
  if (width > 0 && height > 0 && (declared.width != width || declared.height != height)) {
    throw InvalidArgument(concat("the frame is ", declared.width, "x", declared.height, ", not ",
                                 width, "x", height, " as the frames before it",
                                 ": every frame must have the same size (image '", path,
                                 "', its header; nothing was decoded)"));
  }
  // A decoder's allocation failing (a memory limit) says so, naming the file,
  // rather than ending the run in std::bad_alloc or OpenCV's bare message.
  const auto out_of_memory = [&] {
    return Error(concat("out of memory while decoding image '", path, "' (", declared.width, " x ",
                        declared.height, " pixels declared)"));
  };
  cv::Mat image;
  try {
    image = decode(bytes, jpeg, path);
    check_decoded(image, path);
    // A PNM's samples go from 0 to its maxval: OpenCV keeps them as stored.
    if (declared.pnm_maxval > 0 && declared.pnm_maxval < 255) {
      image.convertTo(image, CV_8U, 255.0 / declared.pnm_maxval);
    }
  } catch (const std::bad_alloc&) {
    throw out_of_memory();
  } catch (const cv::Exception& e) {
    if (e.code == cv::Error::StsNoMem) throw out_of_memory();
    throw FormatError(concat("'", path, "' is not a decodable image: ", e.what()));
  }
  return image;
}

}  // namespace lsgd::io
