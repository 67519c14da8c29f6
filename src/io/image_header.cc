#include "io/image_header.h"

#include <algorithm>
#include <cctype>
#include <cstring>

namespace lsgd::io::header {
namespace {

using Bytes = std::vector<unsigned char>;

bool starts_with(const Bytes& b, const char* magic, std::size_t n, std::size_t at = 0) {
  return b.size() >= at + n && std::memcmp(b.data() + at, magic, n) == 0;
}

// Unsigned integers of n bytes at `at`, big- or little-endian; -1 when cut.
std::int64_t be(const Bytes& b, std::size_t at, std::size_t n) {
  if (b.size() < at + n) return -1;
  std::int64_t v = 0;
  for (std::size_t i = 0; i < n; ++i) v = (v << 8) | b[at + i];
  return v;
}
std::int64_t le(const Bytes& b, std::size_t at, std::size_t n) {
  if (b.size() < at + n) return -1;
  std::int64_t v = 0;
  for (std::size_t i = n; i-- > 0;) v = (v << 8) | b[at + i];
  return v;
}

// JPEG: the first start-of-frame segment's height and width.
void read_jpeg(const Bytes& b, ImageHeader& h) {
  std::size_t at = 2;
  while (at + 4 <= b.size()) {
    if (b[at] != 0xFF) return;
    const unsigned char marker = b[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) {
      at += 2;
      continue;
    }
    const std::int64_t length = be(b, at + 2, 2);
    if (length < 2) return;
    const bool frame = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 &&
                       marker != 0xCC;
    if (frame) {
      const std::int64_t height = be(b, at + 5, 2), width = be(b, at + 7, 2);
      if (height > 0 && width > 0) h.height = height, h.width = width;  // 0: set later (DNL)
      return;
    }
    if (marker == 0xDA || marker == 0xD9) return;  // scan data before any frame: damaged
    at += 2 + static_cast<std::size_t>(length);
  }
}

// PNG: IHDR's size, then a walk over the chunks' lengths alone (nothing is
// inflated). libpng allocates a chunk's claimed length before it reads it
// (a 141-byte file whose tEXt claims 2 GB cost 2 GB and 8 s), and inflates
// every byte of IDAT even beyond the image's rows (1 MB of IDAT holding
// 960 MB of zeros: 3 s, then the frame was kept). A chunk must lie inside
// the file, and IDAT may hold no more than the declared rows could take
// stored uncompressed (deflate's stored blocks add 5 bytes per 65,535).
void read_png(const Bytes& b, ImageHeader& h) {
  if (!starts_with(b, "IHDR", 4, 12)) return;
  h.width = be(b, 16, 4), h.height = be(b, 20, 4);
  const std::int64_t depth = be(b, 24, 1), colour = be(b, 25, 1), interlace = be(b, 28, 1);
  h.sample_bits = static_cast<int>(std::max<std::int64_t>(depth, 0));
  const int channels = colour == 0 || colour == 3 ? 1 : colour == 2 ? 3 : colour == 4 ? 2 : colour == 6 ? 4 : 0;
  std::int64_t idat = 0;
  std::size_t at = 8;
  while (at + 8 <= b.size()) {
    const std::int64_t length = be(b, at, 4);
    const std::string type(reinterpret_cast<const char*>(b.data() + at + 4), 4);
    if (length > (std::int64_t{1} << 31) - 1 ||
        static_cast<std::int64_t>(at) + 12 + length > static_cast<std::int64_t>(b.size())) {
      h.damage = "chunk '" + type + "' at byte " + std::to_string(at) + " claims " + std::to_string(length) +
                 " bytes, beyond the file's " + std::to_string(b.size()) + " (truncated or damaged)";
      return;
    }
    if (type == "IDAT") idat += length;
    if (type == "IEND") break;
    at += 12 + static_cast<std::size_t>(length);
  }
  // A size beyond what lsgd reads is refused by read_image anyway (and the
  // bound below would overflow for sides near 2^32).
  if (channels == 0 || depth <= 0 || depth > 16 || h.width <= 0 || h.height <= 0 || h.width > 65535 ||
      h.height > 65535) {
    return;
  }
  const std::int64_t row = (h.width * channels * depth + 7) / 8 + 1;  // and its filter byte
  // Adam7 passes each start their rows with a filter byte and round up.
  const std::int64_t raw = h.height * row + (interlace == 1 ? 15 * (h.height + 8) : 0);
  const std::int64_t most = raw + (raw / 65535 + 1) * 5 + 64;
  if (idat > most) {
    h.damage = "its pixel data (IDAT) holds " + std::to_string(idat) + " compressed bytes, more than the " +
               std::to_string(most) + " its " + std::to_string(h.width) + " x " + std::to_string(h.height) +
               " pixels can need: not inflated";
  }
}

// Plain (ASCII) PNM samples after the header, from byte `at`: P1 bits 0 and 1
// (white space between them optional), P2 and P3 decimal numbers up to
// maxval, '#' comments anywhere. A file cut short, or with a sample that is
// no number or above maxval, is damaged, said here (OpenCV printed its own
// "can't read data" or "Unexpected code" text on stderr, or clipped).
void read_plain_pnm_samples(const Bytes& b, std::size_t at, char kind, ImageHeader& h) {
  const std::int64_t need = h.width * h.height * (kind == '3' ? 3 : 1);
  const std::int64_t maxval = kind == '1' ? 1 : h.pnm_maxval;
  if (maxval <= 0) return;  // the decoder refuses it
  std::int64_t have = 0;
  while (at < b.size() && have < need) {
    const auto c = static_cast<char>(b[at]);
    if (c == '#') {
      while (at < b.size() && b[at] != '\n' && b[at] != '\r') ++at;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++at;
    } else if (c >= '0' && c <= '9') {
      std::int64_t v = 0;
      // A bitmap's bits need no separator: one digit is one sample.
      do {
        v = std::min<std::int64_t>(v * 10 + (static_cast<char>(b[at]) - '0'), 1LL << 40);
        ++at;
      } while (kind != '1' && at < b.size() && b[at] >= '0' && b[at] <= '9');
      if (v > maxval) {
        h.damage = "its sample " + std::to_string(have) + " is " + std::to_string(v) + ", above its maxval " +
                   std::to_string(maxval);
        return;
      }
      ++have;
    } else {
      h.damage = "its sample " + std::to_string(have) + " is not a number (byte " + std::to_string(at) + ")";
      return;
    }
  }
  if (have < need) {
    h.damage = "it holds " + std::to_string(have) + " of the " + std::to_string(need) + " samples its " +
               std::to_string(h.width) + " x " + std::to_string(h.height) + " pixels need (truncated)";
  }
}

// PNM: "P1" .. "P6" then width, height (and maxval but for bitmaps), separated
// by white space and '#' comments; "P7" (PAM): WIDTH, HEIGHT, MAXVAL lines.
void read_pnm(const Bytes& b, ImageHeader& h) {
  const char kind = static_cast<char>(b[1]);
  std::size_t at = 2;
  // The next token of the header ("" at its end or when too long).
  const auto token = [&]() {
    std::string t;
    while (at < b.size()) {
      const auto c = static_cast<char>(b[at]);
      if (c == '#') {
        while (at < b.size() && b[at] != '\n' && b[at] != '\r') ++at;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        ++at;
      } else {
        break;
      }
    }
    while (at < b.size() && !std::isspace(b[at]) && b[at] != '#' && t.size() < 24) {
      t += static_cast<char>(b[at++]);
    }
    return t;
  };
  const auto number = [](const std::string& t) -> std::int64_t {
    if (t.empty() || t.size() > 18) return -1;
    std::int64_t v = 0;
    for (const char c : t) {
      if (c < '0' || c > '9') return -1;
      v = v * 10 + (c - '0');
    }
    return v;
  };
  std::int64_t depth = kind == '6' ? 3 : 1;
  if (kind == '7') {
    for (int tokens = 0; tokens < 64; ++tokens) {
      const std::string t = token();
      if (t.empty() || t == "ENDHDR") break;
      if (t == "WIDTH") h.width = number(token());
      if (t == "HEIGHT") h.height = number(token());
      if (t == "DEPTH") depth = number(token());
      if (t == "MAXVAL") h.pnm_maxval = static_cast<int>(std::min<std::int64_t>(number(token()), 1 << 20));
    }
  } else {
    h.width = number(token());
    h.height = number(token());
    if (kind != '1' && kind != '4') {
      h.pnm_maxval = static_cast<int>(std::min<std::int64_t>(number(token()), 1 << 20));
    }
  }
  if (h.pnm_maxval > 255) h.sample_bits = 16;
  if (h.width <= 0 || h.height <= 0 || depth <= 0 || depth > 4 || h.width > (1 << 20) || h.height > (1 << 20)) {
    return;
  }
  if (kind < '4') {
    read_plain_pnm_samples(b, at, kind, h);
    return;
  }
  // Binary pixels (P4 bits, P5, P6, P7) start after one white-space byte: a
  // file with fewer than its pixels need is truncated, said here (OpenCV
  // printed its own "can't read data" line for it on stderr before lsgd's).
  const std::int64_t sample = h.pnm_maxval > 255 ? 2 : 1;
  const std::int64_t need = kind == '4' ? h.height * ((h.width + 7) / 8) : h.width * h.height * depth * sample;
  const auto start = static_cast<std::int64_t>(std::min(at + 1, b.size()));
  const std::int64_t have = static_cast<std::int64_t>(b.size()) - start;
  if (have < need) {
    h.damage = "its pixel data holds " + std::to_string(have) + " bytes, fewer than the " + std::to_string(need) +
               " its " + std::to_string(h.width) + " x " + std::to_string(h.height) + " pixels need (truncated)";
  }
}

// TIFF and BigTIFF: ImageWidth (256), ImageLength (257), BitsPerSample
// (258: its first value, inline or at its offset), TileWidth (322),
// TileLength (323) and SampleFormat (339) of the first IFD.
void read_tiff(const Bytes& b, ImageHeader& h) {
  const bool little = b[0] == 'I';
  const auto u = [&](std::size_t at, std::size_t n) { return little ? le(b, at, n) : be(b, at, n); };
  const std::int64_t version = u(2, 2);
  const bool big = version == 43;
  std::int64_t ifd = big ? u(8, 8) : u(4, 4);
  if (ifd < 8 || static_cast<std::uint64_t>(ifd) >= b.size()) return;
  const auto at = static_cast<std::size_t>(ifd);
  const std::int64_t count = big ? u(at, 8) : u(at, 2);
  const std::size_t entry = big ? 20 : 12, first = at + (big ? 8 : 2);
  for (std::int64_t k = 0; k < count && k < 4096; ++k) {
    const std::size_t e = first + static_cast<std::size_t>(k) * entry;
    const std::int64_t tag = u(e, 2), type = u(e + 2, 2);
    if (tag < 0 || type < 0) return;
    const std::size_t value = e + (big ? 12 : 8);
    const std::int64_t v = type == 3 ? u(value, 2) : type == 4 ? u(value, 4) : type == 16 ? u(value, 8) : -1;
    if (tag == 256 || tag == 257) (tag == 256 ? h.width : h.height) = v;
    if (tag == 322 || tag == 323) (tag == 322 ? h.tile_width : h.tile_height) = v;
    if (tag == 339) h.float_samples = v == 3;
    if (tag == 258 && type == 3) {
      const std::int64_t n = big ? u(e + 4, 8) : u(e + 4, 4);
      const std::int64_t offset = n * 2 <= (big ? 8 : 4) ? static_cast<std::int64_t>(value)
                                                         : (big ? u(value, 8) : u(value, 4));
      const std::int64_t bits = offset < 0 ? -1 : u(static_cast<std::size_t>(offset), 2);
      h.sample_bits = static_cast<int>(std::clamp<std::int64_t>(bits, 0, 1 << 16));
    }
  }
}

// WebP: the lossy (VP8), lossless (VP8L) or extended (VP8X) header's size.
void read_webp(const Bytes& b, ImageHeader& h) {
  if (starts_with(b, "VP8 ", 4, 12) && b.size() >= 30 && b[23] == 0x9D && b[24] == 0x01 && b[25] == 0x2A) {
    h.width = le(b, 26, 2) & 0x3FFF;
    h.height = le(b, 28, 2) & 0x3FFF;
  } else if (starts_with(b, "VP8L", 4, 12) && b.size() >= 25 && b[20] == 0x2F) {
    const std::int64_t bits = le(b, 21, 4);
    h.width = (bits & 0x3FFF) + 1;
    h.height = ((bits >> 14) & 0x3FFF) + 1;
  } else if (starts_with(b, "VP8X", 4, 12) && b.size() >= 30) {
    h.width = le(b, 24, 3) + 1;
    h.height = le(b, 27, 3) + 1;
  }
}

}  // namespace

ImageHeader read_header(const Bytes& b) {
  ImageHeader h;
  if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) {
    h.format = "JPEG";
    read_jpeg(b, h);
  } else if (starts_with(b, "\x89PNG\r\n\x1a\n", 8)) {
    h.format = "PNG";
    read_png(b, h);
  } else if (starts_with(b, "BM", 2)) {
    h.format = "BMP";
    const std::int64_t size = le(b, 14, 4);
    if (size == 12) {
      h.width = le(b, 18, 2), h.height = le(b, 20, 2);
    } else if (size >= 16) {
      const std::int64_t w = le(b, 18, 4), ht = le(b, 22, 4);
      if (w >= 0 && ht >= 0) {
        h.width = static_cast<std::int32_t>(static_cast<std::uint32_t>(w));
        const auto signed_height = static_cast<std::int32_t>(static_cast<std::uint32_t>(ht));
        h.height = signed_height < 0 ? -static_cast<std::int64_t>(signed_height) : signed_height;  // top-down
      }
    }
  } else if (b.size() >= 3 && b[0] == 'P' && b[1] >= '1' && b[1] <= '7' &&
             std::isspace(b[2])) {
    h.format = "PNM";
    read_pnm(b, h);
  } else if (starts_with(b, "II*\0", 4) || starts_with(b, "MM\0*", 4) || starts_with(b, "II+\0", 4) ||
             starts_with(b, "MM\0+", 4)) {
    h.format = "TIFF";
    read_tiff(b, h);
  } else if (starts_with(b, "RIFF", 4) && starts_with(b, "WEBP", 4, 8)) {
    h.format = "WebP";
    read_webp(b, h);
  }
  return h;
}

const char* known_formats() { return "JPEG, PNG, BMP, PGM/PPM/PBM/PAM, TIFF or WebP"; }

}  // namespace lsgd::io::header
