// Image sequences on disk: a folder of images or a list file, and reading one
// image with errors that name the file. Dataset layouts (KITTI, FAB-MAP, NEU)
// and frame subsampling are in layouts.h.
#pragma once

#include <cstdint>
#include <istream>
#include <string>
#include <vector>

namespace cv {
class Mat;
}

namespace lsgd::io {

// Consumes a UTF-8 byte-order mark at the stream's position, if there is
// one (editors on Windows write it at the start of text files); every text
// reader of lsgd calls it after opening, so the mark never reaches a parser.
bool skip_utf8_bom(std::istream& in);

// Checks, before it is opened, that `path` can be read as `what` ("image",
// "list file", "config", ...): an existing regular file (a folder, a pipe or
// a device would fail, block or never end) of at most max_bytes (-1: any
// size). Throws IoError (missing, not a regular file) or FormatError (too
// large), naming the file.
void check_input_file(const std::string& path, const std::string& what,
                      std::int64_t max_bytes = -1);

struct Sequence {
  std::string source;               // the folder or list file it was opened from
  std::vector<std::string> images;  // image paths in frame order
  // The files besides the images that it was read from (a list file, a
  // dataset folder's sequence.txt, KITTI's times.txt): inputs, which no
  // output of a command may replace.
  std::vector<std::string> files;
  // Each image's time stamp in seconds when the layout gives them (KITTI's
  // times.txt), else empty: lsgd run passes them to Detector::process and
  // writes them in its CSV's stamp column.
  std::vector<double> stamps;
};

// Opens PATH as a sequence:
// - a folder: every regular file with an image extension (.png .jpg .jpeg
//   .bmp .pgm .ppm .tif .tiff, any case) in natural order (2.jpg before 10.jpg);
// - a text file: one image path per line, relative to the file's own folder
//   unless absolute; blank lines and lines starting with '#' are skipped.
// Throws IoError when PATH does not exist or cannot be read, and FormatError
// when it holds no image.
Sequence open_sequence(const std::string& path);

// How image files of a folder are ordered.
enum class NameOrder {
  kNatural,  // natural_less: "2.jpg" before "10.jpg"
  kBytewise  // std::string's operator<: "10.jpg" before "2.jpg" (what `ls` and many tools do)
};

// The image files of `folder` (regular files with an image extension, any
// case; subfolders are not searched) as paths `folder/name`, in `order`.
// Throws IoError when the folder cannot be read and FormatError when it holds
// no image.
std::vector<std::string> list_images(const std::string& folder,
                                     NameOrder order = NameOrder::kNatural);

// Reads a list file: one image path per line, relative to the file's own
// folder unless absolute; blank lines, '#' comments and a UTF-8 BOM skipped.
// The images are not checked. IoError when unreadable, FormatError when it
// lists no image.
std::vector<std::string> read_image_list(const std::string& list_file);

// Natural ordering: digit runs compare by numeric value ("img2" < "img10"),
// the rest byte-wise; ties are broken byte-wise so the order is total.
bool natural_less(const std::string& a, const std::string& b);

// Reads an image as stored (gray, BGR or BGRA, 8-bit). Throws IoError naming
// the file when it is missing or unreadable, FormatError when it is not a
// decodable image (zero-byte, truncated, corrupt) or has an unsupported depth
// (16-bit, float: convert to 8-bit first).
cv::Mat read_image(const std::string& path);
// The same for a frame that must be width x height (the frames already
// stored): one whose header declares another size is refused from the header
// (InvalidArgument, the detector's message), before any pixel is decoded.
cv::Mat read_image(const std::string& path, int width, int height);

}  // namespace lsgd::io
