// Image sequences on disk: a folder of images or a list file, and reading one
// image with errors that name the file.
#pragma once

#include <string>
#include <vector>

namespace cv {
class Mat;
}

namespace lsgd::io {

struct Sequence {
  std::string source;               // the folder or list file it was opened from
  std::vector<std::string> images;  // image paths in frame order
};

// Opens PATH as a sequence:
// - a folder: every regular file with an image extension (.png .jpg .jpeg
//   .bmp .pgm .ppm .tif .tiff, any case) in natural order (2.jpg before 10.jpg);
// - a text file: one image path per line, relative to the file's own folder
//   unless absolute; blank lines and lines starting with '#' are skipped.
// Throws IoError when PATH does not exist or cannot be read, and FormatError
// when it holds no image.
Sequence open_sequence(const std::string& path);

// Natural ordering: digit runs compare by numeric value ("img2" < "img10"),
// the rest byte-wise; ties are broken byte-wise so the order is total.
bool natural_less(const std::string& a, const std::string& b);

// Reads an image as stored (gray, BGR or BGRA, 8-bit). Throws IoError naming
// the file when it is missing or unreadable, FormatError when it is not a
// decodable image (zero-byte, truncated, corrupt) or has an unsupported depth
// (16-bit, float: convert to 8-bit first).
cv::Mat read_image(const std::string& path);

}  // namespace lsgd::io
