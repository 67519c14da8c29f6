// Readers for the loop ground-truth formats researchers publish, detection of
// a file's format by its content, loop ground truth derived from KITTI poses,
// and summary statistics. Every reader returns a GroundTruth (groundtruth.h);
// `lsgd gt convert` writes any of them as the pairs text format.
//
// Formats, registered by name (register_gt_format(); the built-in ones first;
// ../shared/docs/evaluation.md describes where each comes from):
//   pairs        "q m" per line, 0-based, '#' comments (read_pairs)
//   mat          MATLAB N x N loop matrix (v4, v5 or v7.3 through matio):
//                GT(r, c) = 1: a loop between frames r and c (entries 0 or 1)
//   kitti-poses  KITTI odometry poses, one row-major 3x4 matrix per line
//                (12 columns, or 13 with a leading timestamp)
//   loopinf      the LSGDDN authors' "frame<TAB>loop_frame", -1 = none, one
//                line per frame
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lsgd/eval/groundtruth.h"

namespace lsgd::eval {

// A format is its registered name, or kAutoGtFormat.
using GtFormat = std::string;
inline constexpr const char* kAutoGtFormat = "auto";
inline constexpr const char* kPairsGtFormat = "pairs";
inline constexpr const char* kMatGtFormat = "mat";
inline constexpr const char* kKittiPosesGtFormat = "kitti-poses";
inline constexpr const char* kLoopinfGtFormat = "loopinf";

// `name` when it is "auto" or a registered format; InvalidArgument naming the
// value and every format otherwise.
GtFormat parse_gt_format(const std::string& name);
// "auto" and every registered format, in registration order (the choices of
// --gt-format).
std::vector<std::string> gt_format_names();

struct GtOptions {
  GtFormat format = kAutoGtFormat;  // "auto": detect_gt_format()
  // Expected frame count, [-1, 1e9]; -1 takes it from the file (pairs: max id
  // + 1, mat: N, kitti-poses: poses, loopinf: lines). A file that disagrees
  // with a given count is a FormatError naming both.
  std::int64_t frames = -1;
  // kitti-poses: a loop when camera centres are closer than this, metres, (0, 1e6].
  double poses_distance = 10.0;
  // kitti-poses: ... and more than this many frames apart, [0, 1e9].
  std::int64_t poses_min_gap = 100;
  // mat: the variable to read; empty: the heuristic of read_mat().
  std::string mat_variable;

  void check() const;  // InvalidArgument naming the field and value
};

// Tells the format of a file by its content. A format registered from outside
// whose `detect` says so comes first (in registration order); then the
// built-in ones: a MAT header ("MATLAB 5.0
// MAT-file" / "MATLAB 7.3 MAT-file") -> mat; every data line with the same
// count of 12 or 13 numbers -> kitti-poses; two integers per line where line k
// starts with k and either a -1 appears or the fields are tab-separated ->
// loopinf; two non-negative integers per line -> pairs. A binary file without
// a MAT header but named *.mat is taken as mat (MAT v4 has no header).
// IoError when the file cannot be read; FormatError naming the file and the
// first line that fits no format otherwise.
GtFormat detect_gt_format(const std::string& path);

// Reads `path` in options.format (detected when "auto"). Throws as the readers do.
GroundTruth load_groundtruth(const std::string& path, const GtOptions& options = {});

// A ground-truth format (docs/design.md, "Add a dataset layout or a
// ground-truth format"): how a file lists the loops.
struct GtFormatType {
  const char* name;     // what --gt-format and GtOptions::format say
  const char* summary;  // one line, for help texts
  // The loops of `path` (options.frames: the expected frame count, -1: the
  // file's); FormatError / IoError naming the file.
  GroundTruth (*open)(const std::string& path, const GtOptions& options);
  // Whether "auto" reads `path` in this format; nullptr: only by name. The
  // built-in formats are told apart by detect_gt_format() itself.
  bool (*detect)(const std::string& path) = nullptr;
};

// Every registered format, in registration order: the built-in ones first.
std::vector<GtFormatType> gt_format_types();
// Registers another format, usable by name from then on (GtOptions::format,
// --gt-format, a sweep dataset's gt-format); call it before reading files
// with it. InvalidArgument for a missing name, summary or open function, the
// name "auto" or one already registered. Thread-safe.
void register_gt_format(const GtFormatType& format);

// Reads a MATLAB loop matrix with matio. The variable is `variable` when given;
// otherwise the first square 2-D numeric, logical or sparse variable whose name
// contains "gt" or "truth" (any case), else the first square one. Any numeric
// class, logical and sparse; lower-, upper-triangular or full (symmetric)
// matrices alike: every GT(r, c) = 1, r != c, is the loop {r, c}; the
// diagonal is ignored; entries hold 0 or 1 (any other value is refused). A compressed dense matrix in a v5 file (every published
// one) is streamed through zlib, never held whole; other layouts are read whole
// by matio (N^2 x the element size). FormatError naming the file for a
// truncated or corrupt file, no suitable variable, a non-square or complex
// matrix, an entry other than 0 or 1 (NaN, -1, 0.5, 7), or N != frames (when frames >= 0); IoError when unreadable.
GroundTruth read_mat(const std::string& path, std::int64_t frames = -1,
                     const std::string& variable = "");

// Camera centre in metres: the translation column of a KITTI 3x4 pose.
struct Pose {
  double x = 0, y = 0, z = 0;
};

// Reads KITTI poses: 12 numbers per line (official, row-major [R | t]) or 13
// (a timestamp first); every line must have the same count. Blank lines and
// '#' comments are skipped. FormatError naming file:line for a wrong column
// count, a non-number or a non-finite value; IoError when unreadable.
std::vector<Pose> read_kitti_poses(const std::string& path);

// Loop ground truth from camera centres: frames i > j are a loop when
// i - j > min_gap and |c_i - c_j| < distance (Euclidean, 3-D). A hash grid of
// cell `distance` keeps it near-linear (KITTI-00, 4541 frames: ~10 ms).
// InvalidArgument for distance not in (0, 1e6] or min_gap < 0.
GroundTruth groundtruth_from_poses(const std::vector<Pose>& poses, double distance,
                                   std::int64_t min_gap);

// Reads the LSGDDN authors' loopinf format: line k (0-based, blank lines
// skipped) is "k<TAB>j", j the loop frame of k or -1 for none; j may be later
// than k. frames = -1 takes the line count. FormatError naming file:line for a
// malformed line, an id out of order, or j outside [0, frames); FormatError
// naming both counts when the file has another number of lines than frames.
GroundTruth read_loopinf(const std::string& path, std::int64_t frames = -1);

struct GtStats {
  std::int64_t frames = 0;
  std::int64_t pairs = 0;            // distinct unordered loop pairs
  std::int64_t positives = 0;        // queries q with a match m < q
  std::int64_t frames_in_loops = 0;  // frames in at least one pair, either side
  std::int64_t gap_min = 0;          // |q - m| over all pairs, frames; 0 when no pairs
  double gap_median = 0;             // mean of the two middle gaps when even
  std::int64_t gap_max = 0;
  std::int64_t min_gap = 0;           // the temporal window of the next two
  std::int64_t window_pairs = 0;      // pairs with q - m > min_gap
  std::int64_t window_positives = 0;  // queries with a match m < q - min_gap (strict protocol)
};

// Statistics of a ground truth; min_gap >= 0 is the window of the window_* fields.
GtStats gt_stats(const GroundTruth& gt, std::int64_t min_gap = 0);

}  // namespace lsgd::eval
