#include "lsgd/io/files.h"
#include "lsgd/eval/gt_formats.h"

#include <matio.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <utility>

#include "internal/check.h"
#include "internal/registry.h"
#include "internal/numbers.h"
#include "lsgd/error.h"
#include "lsgd/io/sequence.h"
#include "lsgd/limits.h"

namespace lsgd::eval {

using internal::concat;

namespace {

// ---- text helpers ---------------------------------------------------------

std::ifstream open_text(const std::string& path, const char* what) {
  io::check_input_file(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(concat("cannot open ", what, " '", path, "'"));
  io::skip_utf8_bom(in);
  return in;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// Whitespace-separated fields of a line; empty for blank and '#' comment lines.
std::vector<std::string> fields_of(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t i = 0;
  while (true) {
    while (i < line.size() && is_space(line[i])) ++i;
    if (i == line.size() || (fields.empty() && line[i] == '#')) break;
    std::size_t end = i;
    while (end < line.size() && !is_space(line[end])) ++end;
    fields.push_back(line.substr(i, end - i));
    i = end;
  }
  return fields;
}

bool parse_int(const std::string& text, long long& value) { return internal::parses_as(text, value); }

bool parse_double(const std::string& text, double& value) { return internal::parses_as(text, value); }

// ---- detection --------------------------------------------------------------

bool has_mat_extension(const std::string& path) {
  if (path.size() < 4) return false;
  std::string ext = path.substr(path.size() - 4);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".mat";
}

// What the text lines of a file look like, gathered in one pass.
struct TextShape {
  std::int64_t lines = 0;       // data lines
  std::size_t columns = 0;      // fields per data line (all equal, else an error)
  bool integers = true;         // every field an integer
  bool minus_one = false;       // some second field is -1
  bool other_negative = false;  // some other negative value
  bool consecutive = true;      // data line k starts with k
  bool tabs = true;             // every data line contains a tab
};

TextShape text_shape(std::istream& in, const std::string& path) {
  TextShape shape;
  std::string line;
  for (std::int64_t number = 1; io::read_line(in, line, path, number); ++number) {
    const auto fields = fields_of(line);
    if (fields.empty()) continue;
    if (shape.lines == 0) shape.columns = fields.size();
    if (fields.size() != shape.columns) {
      throw FormatError(concat("cannot tell the ground-truth format of '", path, "': line ", number,
                               " has ", fields.size(), " fields, the first data line ",
                               shape.columns, "; pass the format explicitly"));
    }
    for (std::size_t f = 0; f < fields.size(); ++f) {
      long long iv = 0;
      double dv = 0;
      if (parse_int(fields[f], iv)) {
        if (f == 0 && iv != shape.lines) shape.consecutive = false;
        if (iv == -1 && f == 1) {
          shape.minus_one = true;
        } else if (iv < 0) {
          shape.other_negative = true;
        }
      } else if (parse_double(fields[f], dv)) {
        shape.integers = false;
      } else {
        throw FormatError(concat("cannot tell the ground-truth format of '", path, "': line ",
                                 number, ": '", fields[f], "' is not a number"));
      }
    }
    shape.tabs = shape.tabs && line.find('\t') != std::string::npos;
    ++shape.lines;
  }
  return shape;
}

// ---- pairs with the frame count taken from the file ------------------------

GroundTruth read_pairs_counted(const std::string& path, std::int64_t frames) {
  if (frames >= 0) return read_pairs(path, frames);
  std::ifstream in = open_text(path, "ground-truth file");
  long long max_id = -1;
  std::string line;
  for (std::int64_t number = 1; io::read_line(in, line, path, number); ++number) {
    // The header write_pairs() wrote holds the count: frames after the last
    // loop have no pair to count them.
    const PairsHeader header = number == 1 ? pairs_header(line) : PairsHeader{};
    if (header.frames >= 0 && header.frames <= kMaxFrames) return read_pairs(path, header.frames);
    const auto fields = fields_of(line);
    long long a = 0, b = 0;
    if (fields.size() == 2 && parse_int(fields[0], a) && parse_int(fields[1], b)) {
      max_id = std::max({max_id, a, b});
    }
  }
  if (max_id >= kMaxFrames) {
    throw FormatError(concat(path, ": frame id ", max_id, " is implausibly large (at most ",
                             kMaxFrames, " frames are supported)"));
  }
  // Malformed lines are left to read_pairs, which names them.
  return read_pairs(path, max_id + 1);
}

// ---- poses grid -------------------------------------------------------------

struct Cell {
  std::int64_t x, y, z;
  bool operator==(const Cell& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellHash {
  std::size_t operator()(const Cell& c) const {
    std::uint64_t h = static_cast<std::uint64_t>(c.x) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(c.y) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(c.z) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return static_cast<std::size_t>(h);
  }
};

}  // namespace

// ---- names and options ------------------------------------------------------

namespace {

GroundTruth open_pairs(const std::string& path, const GtOptions& options) {
  return read_pairs_counted(path, options.frames);
}
GroundTruth open_mat(const std::string& path, const GtOptions& options) {
  return read_mat(path, options.frames, options.mat_variable);
}
GroundTruth open_loopinf(const std::string& path, const GtOptions& options) {
  return read_loopinf(path, options.frames);
}
GroundTruth open_kitti_poses(const std::string& path, const GtOptions& options) {
  const auto poses = read_kitti_poses(path);
  const auto n = static_cast<std::int64_t>(poses.size());
  if (options.frames >= 0 && n != options.frames) {
    throw FormatError(concat("'", path, "' has ", n, " poses but the sequence has ",
                             options.frames, " frames"));
  }
  try {
    return groundtruth_from_poses(poses, options.poses_distance, options.poses_min_gap);
  } catch (const InvalidArgument& e) {  // a coordinate or the pairs: the file's
    throw FormatError(concat("KITTI poses '", path, "': ", e.what()));
  }
}

// The formats, built-in ones first (register_gt_format()).
internal::Registry<GtFormatType>& registry() {
  static internal::Registry<GtFormatType> formats(
      "ground-truth format",
      {
          {kPairsGtFormat, "'q m' per line, 0-based", open_pairs},
          {kMatGtFormat, "a MATLAB N x N loop matrix", open_mat},
          {kKittiPosesGtFormat, "KITTI poses, a loop within 10 m and 100 frames by default",
           open_kitti_poses},
          {kLoopinfGtFormat, "the LSGDDN authors' 'frame<TAB>loop_frame', -1 = none",
           open_loopinf},
      });
  return formats;
}

}  // namespace

std::vector<GtFormatType> gt_format_types() { return registry().entries(); }

void register_gt_format(const GtFormatType& format) {
  registry().add(format, "register_gt_format", kAutoGtFormat);
}

std::vector<std::string> gt_format_names() { return registry().name_list(kAutoGtFormat); }

GtFormat parse_gt_format(const std::string& name) { return registry().parse(name, kAutoGtFormat); }

void GtOptions::check() const {
  internal::check_range<std::int64_t>("ground truth frames", frames, -1, kMaxFrames);
  internal::check_range_open_low("ground truth poses_distance", poses_distance, 0.0, 1e6, "metres");
  internal::check_range<std::int64_t>("ground truth poses_min_gap", poses_min_gap, 0, kMaxWindowFrames,
                                      "frames");
  parse_gt_format(format);
}

// ---- detection and dispatch ---------------------------------------------------

GtFormat detect_gt_format(const std::string& path) {
  io::check_input_file(path, "ground-truth file");
  // Only formats registered from outside have a `detect`: the built-in ones
  // are told apart below.
  for (const GtFormatType& t : gt_format_types()) {
    if (t.detect != nullptr && t.detect(path)) return t.name;
  }
  std::ifstream in = open_text(path, "ground-truth file");
  std::string head(128, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  if (head.rfind("MATLAB", 0) == 0 && head.find("MAT-file") < 116) return kMatGtFormat;
  if (head.find('\0') != std::string::npos) {
    if (has_mat_extension(path)) return kMatGtFormat;  // MAT v4: no text header
    throw FormatError(concat("cannot tell the ground-truth format of '", path,
                             "': a binary file without a MAT-file header"));
  }
  in.clear();
  in.seekg(0);
  io::skip_utf8_bom(in);
  const TextShape shape = text_shape(in, path);
  if (shape.lines == 0) {
    throw FormatError(concat("cannot tell the ground-truth format of '", path,
                             "': no data lines (empty or only comments)"));
  }
  if (shape.columns == 12 || shape.columns == 13) return kKittiPosesGtFormat;
  if (shape.columns == 2 && shape.integers) {
    if (shape.consecutive && !shape.other_negative && (shape.minus_one || shape.tabs)) {
      return kLoopinfGtFormat;
    }
    if (!shape.minus_one && !shape.other_negative) return kPairsGtFormat;
  }
  throw FormatError(concat("cannot tell the ground-truth format of '", path, "': ", shape.columns,
                           shape.integers ? " integer" : " numeric",
                           " fields per line fit neither pairs ('q m'), loopinf ('k<TAB>j' on line "
                           "k) nor KITTI poses (12 or 13 numbers)"));
}

GroundTruth load_groundtruth(const std::string& path, const GtOptions& options) {
  options.check();
  const GtFormat format =
      options.format == kAutoGtFormat ? detect_gt_format(path) : options.format;
  return registry().find(format).open(path, options);
}


// ---- readers --------------------------------------------------------------------

std::vector<Pose> read_kitti_poses(const std::string& path) {
  std::ifstream in = open_text(path, "poses file");
  std::vector<Pose> poses;
  std::size_t columns = 0;
  std::string line;
  for (std::int64_t number = 1; io::read_line(in, line, path, number); ++number) {
    const auto fields = fields_of(line);
    if (fields.empty()) continue;
    if (columns == 0) columns = fields.size();
    if ((fields.size() != 12 && fields.size() != 13) || fields.size() != columns) {
      throw FormatError(concat(path, ":", number, ": expected ",
                               columns == fields.size() ? "12 or 13" : std::to_string(columns),
                               " numbers (a 3x4 pose, optionally after a timestamp), got ",
                               fields.size()));
    }
    std::array<double, 13> v{};
    for (std::size_t f = 0; f < fields.size(); ++f) {
      if (!parse_double(fields[f], v[f]) || !std::isfinite(v[f])) {
        throw FormatError(concat(path, ":", number, ": field ", f + 1, " '", fields[f],
                                 "' is not a finite number"));
      }
    }
    const std::size_t t = columns - 12;  // skip the timestamp
    poses.push_back({v[t + 3], v[t + 7], v[t + 11]});
  }
  if (in.bad()) throw IoError(concat("error while reading '", path, "'"));
  if (poses.empty()) throw FormatError(concat("'", path, "' holds no poses"));
  return poses;
}

GroundTruth groundtruth_from_poses(const std::vector<Pose>& poses, double distance,
                                   std::int64_t min_gap) {
  internal::check_range_open_low("poses distance", distance, 0.0, 1e6, "metres");
  internal::check_range<std::int64_t>("poses min_gap", min_gap, 0, kMaxWindowFrames, "frames");
  const auto n = static_cast<std::int64_t>(poses.size());
  GroundTruth gt(n);
  // Cells of side `distance`, or larger when the poses span more than 1e14
  // such cells (a tiny distance in range): pairs are still tested exactly,
  // a cell only finds the candidates.
  double extent = 0;
  for (const Pose& p : poses) {
    for (const double v : {p.x, p.y, p.z}) {
      if (!(std::abs(v) <= 1e12)) {
        internal::throw_invalid("camera centre coordinate ", v, " is not finite or beyond 1e12 metres");
      }
      extent = std::max(extent, std::abs(v));
    }
  }
  const double side = std::max(distance, extent / 1e14);
  const auto cell_of = [side](const Pose& p) {
    const auto index = [side](double v) {
      const double c = std::floor(v / side);
      if (!(std::abs(c) < 1e15)) {
        internal::throw_invalid("camera centre coordinate ", v, " is not finite or too large");
      }
      return static_cast<std::int64_t>(c);
    };
    return Cell{index(p.x), index(p.y), index(p.z)};
  };
  // A pair closer than `distance` lies in the same or adjacent cells.
  std::unordered_map<Cell, std::vector<std::int64_t>, CellHash> grid;
  const double d2 = distance * distance;
  for (std::int64_t i = 0; i < n; ++i) {
    const Pose& p = poses[static_cast<std::size_t>(i)];
    const Cell c = cell_of(p);
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({c.x + dx, c.y + dy, c.z + dz});
          if (it == grid.end()) continue;
          for (std::int64_t j : it->second) {  // ascending, all < i
            if (i - j <= min_gap) break;
            const Pose& o = poses[static_cast<std::size_t>(j)];
            const double ex = p.x - o.x, ey = p.y - o.y, ez = p.z - o.z;
            if (ex * ex + ey * ey + ez * ez < d2) gt.add(i, j);
          }
        }
      }
    }
    grid[c].push_back(i);
  }
  return gt;
}

GroundTruth read_loopinf(const std::string& path, std::int64_t frames) {
  std::ifstream in = open_text(path, "loopinf file");
  std::vector<std::pair<long long, std::int64_t>> loops;  // (loop frame, line number) per frame
  std::string line;
  for (std::int64_t number = 1; io::read_line(in, line, path, number); ++number) {
    const auto fields = fields_of(line);
    if (fields.empty()) continue;
    long long k = 0, j = 0;
    if (fields.size() != 2 || !parse_int(fields[0], k) || !parse_int(fields[1], j)) {
      throw FormatError(
          concat(path, ":", number, ": expected 'frame<TAB>loop_frame', got '", line, "'"));
    }
    if (k != static_cast<long long>(loops.size())) {
      throw FormatError(concat(path, ":", number, ": expected frame ", loops.size(), ", got ", k,
                               " (loopinf has one line per frame, in order)"));
    }
    if (j < -1) throw FormatError(concat(path, ":", number, ": loop frame ", j, " is negative"));
    loops.emplace_back(j, number);
  }
  if (in.bad()) throw IoError(concat("error while reading '", path, "'"));
  const auto lines = static_cast<std::int64_t>(loops.size());
  if (frames >= 0 && lines != frames) {
    throw FormatError(
        concat("'", path, "' has ", lines, " frames (lines) but the sequence has ", frames));
  }
  GroundTruth gt(lines);
  for (std::int64_t k = 0; k < lines; ++k) {
    const auto [j, number] = loops[static_cast<std::size_t>(k)];
    if (j == -1) continue;
    if (j >= lines) {
      throw FormatError(concat(path, ":", number, ": loop frame ", j, " of frame ", k,
                               " is outside the ", lines, " frames"));
    }
    gt.add(k, j);
  }
  return gt;
}

// ---- statistics ---------------------------------------------------------------------

GtStats gt_stats(const GroundTruth& gt, std::int64_t min_gap) {
  internal::check_range<std::int64_t>("min_gap", min_gap, 0, kMaxWindowFrames, "frames");
  GtStats s;
  s.frames = gt.frames();
  s.pairs = gt.pairs();
  s.min_gap = min_gap;
  std::vector<std::int64_t> gaps;
  gaps.reserve(static_cast<std::size_t>(gt.pairs()));
  std::vector<std::int64_t> in_loop;  // every frame of every pair, then made unique
  for (const std::int64_t q : gt.queries()) {
    const auto& matches = gt.matches(q);
    ++s.positives;
    if (gt.has_loop(q, min_gap)) ++s.window_positives;
    in_loop.push_back(q);
    for (std::int64_t m : matches) {
      in_loop.push_back(m);
      gaps.push_back(q - m);
      if (q - m > min_gap) ++s.window_pairs;
    }
  }
  std::sort(in_loop.begin(), in_loop.end());
  s.frames_in_loops =
      std::unique(in_loop.begin(), in_loop.end()) - in_loop.begin();
  if (!gaps.empty()) {
    std::sort(gaps.begin(), gaps.end());
    const std::size_t h = gaps.size() / 2;
    s.gap_min = gaps.front();
    s.gap_max = gaps.back();
    s.gap_median = gaps.size() % 2 ? static_cast<double>(gaps[h])
                                   : 0.5 * static_cast<double>(gaps[h - 1] + gaps[h]);
  }
  return s;
}

}  // namespace lsgd::eval
