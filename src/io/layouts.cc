#include "lsgd/io/files.h"
#include "lsgd/io/layouts.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <locale>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "internal/check.h"
#include "internal/registry.h"
#include "lsgd/error.h"
#include "lsgd/limits.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using internal::concat;

constexpr int kKittiCameras = 4;
constexpr const char* kKittiCameraNames[kKittiCameras] = {"gray left", "gray right", "colour left",
                                                          "colour right"};

// PATH without a trailing separator, so filename() and parent_path() work.
fs::path clean(const std::string& path) {
  fs::path p = fs::path(path).lexically_normal();
  if (!p.has_filename() && p.has_parent_path()) p = p.parent_path();
  return p;
}

bool is_folder(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

bool is_file(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

// X when `dir` is named image_X with X in [0, 3], else -1.
int image_folder_camera(const fs::path& dir) {
  const std::string name = dir.filename().string();
  if (name.size() != 7 || name.compare(0, 6, "image_") != 0) return -1;
  const int c = name[6] - '0';
  return c >= 0 && c < kKittiCameras ? c : -1;
}

// Anything named `p` (a folder, a device, a dangling link): what a layout
// that expects a file there is about, so it can say what is wrong with it.
bool exists_as_anything(const fs::path& p) {
  std::error_code ec;
  return fs::exists(fs::symlink_status(p, ec));
}

// True when `dir` holds times.txt (whatever it is: open_kitti says what is
// wrong with one that is not a file) and at least one image_X folder.
bool is_kitti_sequence(const fs::path& dir) {
  if (!exists_as_anything(dir / "times.txt")) return false;
  for (int c = 0; c < kKittiCameras; ++c) {
    if (is_folder(dir / ("image_" + std::to_string(c)))) return true;
  }
  return false;
}

// " (found image_2, image_3)" or a hint when there is no camera folder at all.
std::string found_cameras(const fs::path& dir) {
  std::string found;
  for (int c = 0; c < kKittiCameras; ++c) {
    if (is_folder(dir / ("image_" + std::to_string(c)))) {
      found += concat(found.empty() ? "" : ", ", "image_", c);
    }
  }
  if (found.empty()) return "; it has no image_0..image_3 folder: is it a KITTI odometry sequence?";
  return concat("; it has ", found, ": choose one with --camera");
}

// "5" -> "05"; InvalidArgument unless 1 to 6 digits.
std::string kitti_sequence_name(const std::string& nn) {
  bool digits = !nn.empty() && nn.size() <= 6;
  for (char c : nn) digits = digits && c >= '0' && c <= '9';
  if (!digits) {
    internal::throw_invalid("KITTI sequence '", nn, "' is not a sequence number (00, 01, ... 21)");
  }
  return nn.size() == 1 ? "0" + nn : nn;
}

// Non-blank lines of times.txt, each a finite number; FormatError naming file:line.
std::vector<double> read_timestamps(const fs::path& times) {
  check_input_file(times.string(), "KITTI times file");
  std::ifstream in(times, std::ios::binary);
  if (!in) throw IoError(concat("cannot read '", times.string(), "'"));
  skip_utf8_bom(in);
  std::vector<double> stamps;
  std::string line;
  for (std::int64_t number = 1; read_line(in, line, times.string(), number); ++number) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream fields(line);
    fields.imbue(std::locale::classic());
    double t = 0;
    std::string rest;
    if (!(fields >> t) || (fields >> rest) || !std::isfinite(t)) {
      throw FormatError(
          concat(times.string(), ":", number, ": expected one timestamp, got '", line, "'"));
    }
    stamps.push_back(t);
  }
  if (in.bad()) throw IoError(concat("error while reading '", times.string(), "'"));
  return stamps;
}

// KITTI frames are 000000.png, 000001.png, ...: a gap would shift every later id.
void check_kitti_names(const std::vector<std::string>& images, const fs::path& folder) {
  for (std::size_t i = 0; i < images.size(); ++i) {
    char expected[32];
    std::snprintf(expected, sizeof(expected), "%06zu", i);
    const fs::path name = fs::path(images[i]).filename();
    if (name.stem().string() != expected) {
      throw FormatError(concat("KITTI image folder '", folder.string(), "': frame ", i, " is '",
                               name.string(), "', expected '", expected, name.extension().string(),
                               "' (a missing or extra file would shift every later frame id)"));
    }
  }
}

Sequence open_kitti(const std::string& path, const SequenceOptions& options) {
  fs::path dir = clean(path);
  int camera = options.camera;
  if (!options.kitti_sequence.empty()) {
    const fs::path root = dir;
    dir = root / "sequences" / kitti_sequence_name(options.kitti_sequence);
    if (!is_folder(dir)) {
      throw IoError(concat("KITTI sequence folder '", dir.string(),
                           "' does not exist (with a sequence number, PATH is the dataset root "
                           "holding sequences/NN)"));
    }
  } else {
    if (!is_folder(dir)) {
      throw IoError(concat("KITTI sequence '", path, "' does not exist or is not a folder"));
    }
    if (const int named = image_folder_camera(dir); named >= 0) {
      if (camera >= 0 && camera != named) {
        internal::throw_invalid("camera ", camera, " conflicts with the image folder '", path,
                                "' (camera ", named, ")");
      }
      camera = named;
      dir = dir.parent_path();
    }
  }
  if (camera < 0) camera = 0;
  const fs::path folder = dir / ("image_" + std::to_string(camera));
  if (!is_folder(folder)) {
    throw FormatError(concat("KITTI sequence '", dir.string(), "' has no image_", camera,
                             " folder (camera ", camera, ": ", kKittiCameraNames[camera], ")",
                             found_cameras(dir)));
  }
  const fs::path times = dir / "times.txt";
  if (!is_file(times)) {
    std::error_code ec;
    const fs::file_status st = fs::status(times, ec);
    const std::string what = !exists_as_anything(times)     ? "has no times.txt"
                             : fs::is_directory(st)         ? "has a times.txt that is a folder"
                             : !fs::exists(st)              ? "has a times.txt that is a broken link"
                                                            : "has a times.txt that is not a regular file (a device or a pipe)";
    throw FormatError(concat("KITTI sequence '", dir.string(), "' ", what,
                             " (one line per frame; to read the images without "
                             "it use --layout folder on '",
                             folder.string(), "')"));
  }
  Sequence sequence;
  sequence.source = folder.string();
  sequence.images = list_images(folder.string());
  check_kitti_names(sequence.images, folder);
  sequence.stamps = read_timestamps(times);
  sequence.files = {times.string()};
  const auto stamps = static_cast<std::int64_t>(sequence.stamps.size());
  const auto frames = static_cast<std::int64_t>(sequence.images.size());
  if (stamps != frames) {
    throw FormatError(concat("KITTI sequence: '", folder.string(), "' holds ", frames,
                             " images but '", times.string(), "' has ", stamps,
                             " timestamps (one per frame): incomplete download or extraction?"));
  }
  return sequence;
}

Sequence open_fabmap(const std::string& path, Side side) {
  if (!is_folder(clean(path))) {
    throw IoError(concat("FAB-MAP image folder '", path, "' does not exist or is not a folder"));
  }
  const std::vector<std::string> files = list_images(path);
  if (files.size() % 2 != 0) {
    throw FormatError(concat("FAB-MAP folder '", path, "' holds ", files.size(),
                             " images, an odd number: left and right images alternate (0001 "
                             "left, 0002 right, ...), so one is missing or extra (last: '",
                             fs::path(files.back()).filename().string(), "')"));
  }
  Sequence sequence;
  sequence.source = path;
  if (side == Side::kBoth) {
    sequence.images = files;
    return sequence;
  }
  sequence.images.reserve(files.size() / 2);
  for (std::size_t i = side == Side::kLeft ? 0 : 1; i < files.size(); i += 2) {
    sequence.images.push_back(files[i]);
  }
  return sequence;
}

// The list file of a dataset folder (lsgd's datasets, `lsgd demo --output`):
// DIR/sequence.txt; empty when `path` is not a folder holding one.
std::string dataset_list(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return "";
  const fs::path list = fs::path(path) / kDatasetList;
  return is_file(list) ? list.string() : "";
}

Sequence open_plain(const std::string& path, const Layout& layout) {
  std::error_code ec;
  const bool folder = fs::is_directory(path, ec);
  if (layout == kListLayout && folder && !dataset_list(path).empty()) {
    return open_sequence(dataset_list(path));
  }
  if (layout == kListLayout && folder) {
    internal::throw_invalid("layout list needs a list file, but '", path,
                            "' is a folder (use --layout folder or auto)");
  }
  if ((layout == kFolderLayout || layout == kNeuLayout) && !folder && fs::exists(path, ec)) {
    internal::throw_invalid("layout ", layout, " needs a folder, but '", path,
                            "' is a file (a list file? use --layout list or auto)");
  }
  if (layout != kNeuLayout) return open_sequence(path);
  if (!folder) throw IoError(concat("sequence '", path, "' does not exist"));
  // The authors' code sorts readdir() names as strings: their frame k is the
  // k-th name in byte order, which their loopinf files refer to.
  Sequence sequence;
  sequence.source = path;
  sequence.images = list_images(path, NameOrder::kBytewise);
  return sequence;
}

Sequence open_folder(const std::string& path, const SequenceOptions&) {
  return open_plain(path, kFolderLayout);
}
Sequence open_list(const std::string& path, const SequenceOptions&) {
  return open_plain(path, kListLayout);
}
Sequence open_neu(const std::string& path, const SequenceOptions&) {
  return open_plain(path, kNeuLayout);
}
Sequence open_fabmap_layout(const std::string& path, const SequenceOptions& options) {
  return open_fabmap(path, options.side);
}

// A KITTI sequence folder, or one of its image_X folders.
bool detect_kitti(const std::string& path, const SequenceOptions&) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return false;
  const fs::path dir = clean(path);
  return is_kitti_sequence(dir) ||
         (image_folder_camera(dir) >= 0 && exists_as_anything(dir.parent_path() / "times.txt"));
}

// The layouts, built-in ones first (register_layout()).
internal::Registry<LayoutType>& registry() {
  static internal::Registry<LayoutType> layouts(
      "layout",
      {
          {kFolderLayout, "every image of a folder, natural order", open_folder},
          {kListLayout, "a text file listing image paths, or a dataset folder's sequence.txt",
           open_list},
          {kKittiLayout, "KITTI odometry: sequences/NN/image_<camera>, times.txt", open_kitti,
           detect_kitti},
          {kFabmapLayout, "FAB-MAP City Centre / New College: alternating left and right images",
           open_fabmap_layout},
          {kNeuLayout, "the LSGDDN authors' NEU set: file names in byte order", open_neu},
      });
  return layouts;
}

}  // namespace

std::vector<LayoutType> layout_types() { return registry().entries(); }

void register_layout(const LayoutType& layout) {
  registry().add(layout, "register_layout", kAutoLayout);
}

std::vector<std::string> layout_names() { return registry().name_list(kAutoLayout); }

Layout parse_layout(const std::string& name) { return registry().parse(name, kAutoLayout); }

Side parse_side(const std::string& name) {
  if (name == "left") return Side::kLeft;
  if (name == "right") return Side::kRight;
  if (name == "both") return Side::kBoth;
  internal::throw_invalid("side '", name, "' is not one of left, right, both");
}

std::string to_string(Side side) {
  switch (side) {
    case Side::kLeft:
      return "left";
    case Side::kRight:
      return "right";
    case Side::kBoth:
      return "both";
  }
  return "unknown";
}

void FrameSelection::check() const {
  internal::check_range<std::int64_t>("first", first, 0, 1'000'000'000'000);
  internal::check_range<std::int64_t>("every", every, 1, kMaxWindowFrames);
  if (last != -1 && last < first) {
    internal::throw_invalid("last = ", last, " must be >= first = ", first, " (or -1: the end)");
  }
}

std::vector<std::int64_t> FrameSelection::kept(std::int64_t frames) const {
  check();
  if (first >= frames) {
    internal::throw_invalid("first = ", first, " is beyond the sequence's ", frames,
                            " frames (0-based: at most ", frames - 1, ")");
  }
  if (last >= frames) {
    internal::throw_invalid("last = ", last, " is beyond the sequence's ", frames,
                            " frames (0-based: at most ", frames - 1, "; -1 means the end)");
  }
  const std::int64_t end = last < 0 ? frames - 1 : last;
  std::vector<std::int64_t> out;
  out.reserve(static_cast<std::size_t>((end - first) / every + 1));
  for (std::int64_t i = first; i <= end; i += every) out.push_back(i);
  return out;
}

void SequenceOptions::check() const {
  if (camera < -1 || camera >= kKittiCameras) {
    internal::throw_invalid("camera = ", camera, " is out of range: must be 0, 1, 2 or 3");
  }
  if (!kitti_sequence.empty()) kitti_sequence_name(kitti_sequence);
  parse_layout(layout);
  selection.check();
}

Layout detect_layout(const std::string& path, const SequenceOptions& options) {
  if (options.layout != kAutoLayout) return parse_layout(options.layout);
  if (!options.kitti_sequence.empty()) return kKittiLayout;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (path.empty() || status.type() == fs::file_type::not_found) {
    throw IoError(concat("sequence '", path, "' does not exist"));
  }
  if (ec) throw IoError(concat("cannot access sequence '", path, "': ", ec.message()));
  for (const LayoutType& t : layout_types()) {
    if (t.detect != nullptr && t.detect(path, options)) return t.name;
  }
  if (!fs::is_directory(status)) return kListLayout;
  if (!dataset_list(path).empty()) return kListLayout;  // a dataset folder: its own order
  return kFolderLayout;
}

Sequence open_layout(const std::string& path, const SequenceOptions& options) {
  options.check();
  const Layout layout = detect_layout(path, options);
  if (layout != kKittiLayout && (!options.kitti_sequence.empty() || options.camera >= 0)) {
    internal::throw_invalid("a KITTI sequence number or camera was given, but '", path,
                            "' is opened with layout ", layout);
  }
  return registry().find(layout).open(path, options);
}

Sequence subsample(const Sequence& sequence, const FrameSelection& selection) {
  if (selection.keeps_all()) return sequence;
  const auto kept = selection.kept(static_cast<std::int64_t>(sequence.images.size()));
  Sequence out;
  out.source = sequence.source;
  out.files = sequence.files;
  out.images.reserve(kept.size());
  for (std::int64_t i : kept) out.images.push_back(sequence.images[static_cast<std::size_t>(i)]);
  if (!sequence.stamps.empty()) {
    for (std::int64_t i : kept) out.stamps.push_back(sequence.stamps[static_cast<std::size_t>(i)]);
  }
  return out;
}

Sequence open_sequence(const std::string& path, const SequenceOptions& options) {
  return subsample(open_layout(path, options), options.selection);
}

}  // namespace lsgd::io
