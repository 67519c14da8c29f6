// The size an image file declares in its header, read before anything is
// decoded (internal to lsgd_io): a 500-byte file may claim 30000 x 30000
// pixels, and a decoder allocates what the header says before it finds the
// data missing. io::read_image refuses a declared size beyond the limits
// (lsgd/image.h) from these bytes alone.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace lsgd::io::header {

struct ImageHeader {
  std::string format;   // "JPEG", "PNG", "BMP", "PNM", "TIFF", "WebP"; empty: not one lsgd reads
  std::int64_t width = -1;   // -1: the header does not say (a damaged header)
  std::int64_t height = -1;
  int pnm_maxval = 0;  // PNM (P2, P3, P5, P6, P7): its maxval; 0 otherwise
  // Bits per sample the header declares (PNG, TIFF, PNM); 0 where it does
  // not say or the format has 8 at most. `float_samples`: TIFF's
  // SampleFormat 3.
  int sample_bits = 0;
  bool float_samples = false;
  // TIFF: TileWidth and TileLength (a tile is decoded whole, whatever the
  // image's size); -1 for an image in strips and for the other formats.
  std::int64_t tile_width = -1;
  std::int64_t tile_height = -1;
  // Why the file is refused before any decoding, when its structure alone
  // shows it (a PNG chunk longer than the file, more compressed pixel data
  // than the declared pixels can need); empty otherwise.
  std::string damage;
};

// The format the bytes start with and the size their header declares.
// Never throws; reads nothing beyond `bytes`.
ImageHeader read_header(const std::vector<unsigned char>& bytes);

// "JPEG, PNG, BMP, PGM/PPM/PBM/PAM, TIFF or WebP": the formats read_header knows.
const char* known_formats();

}  // namespace lsgd::io::header
