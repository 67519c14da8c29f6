// Loop ground truth: which pairs of frames show the same place.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "lsgd/limits.h"

namespace lsgd::eval {

// kMaxFrames (lsgd/limits.h) bounds every frame id and count read from a
// file: beyond it is a FormatError naming the file, not an allocation the
// size of the id.
class GroundTruth {
 public:
  // A ground truth over `frames` frames (ids 0 .. frames-1) with no loop yet.
  // Memory grows with the pairs added, not with `frames`. Throws
  // InvalidArgument for frames < 0 or > kMaxFrames.
  explicit GroundTruth(std::int64_t frames = 0);

  // Marks frames a and b as the same place (order does not matter; a == b is
  // ignored). Throws InvalidArgument for ids outside [0, frames).
  void add(std::int64_t a, std::int64_t b);

  std::int64_t frames() const { return frames_; }
  // Number of distinct unordered pairs.
  std::int64_t pairs() const { return pairs_; }
  // True when a and b (either order) are a ground-truth loop.
  bool is_loop(std::int64_t a, std::int64_t b) const;
  // Earlier frames m < q that show the same place as q, ascending.
  const std::vector<std::int64_t>& matches(std::int64_t q) const;
  // The frames q that have at least one earlier match, ascending.
  std::vector<std::int64_t> queries() const;
  // True when q has a match m < q - min_gap (q counts as a positive query).
  bool has_loop(std::int64_t q, std::int64_t min_gap) const;

 private:
  std::int64_t frames_ = 0;
  std::map<std::int64_t, std::vector<std::int64_t>> matches_;  // per query with matches, sorted
  std::int64_t pairs_ = 0;
};

// Reads the pairs text format: one "q m" pair of 0-based frame ids per line;
// blank lines and lines starting with '#' are ignored. Throws IoError when the
// file cannot be opened and FormatError naming the file and line for a
// malformed line or an id outside [0, frames). A file that starts with the
// header write_pairs() writes must agree with it: another frame count than
// `frames`, or another number of pairs than it holds (a file cut short at a
// line's end read as a smaller ground truth, scoring true loops false), is a
// FormatError naming the file and both counts.
GroundTruth read_pairs(const std::string& path, std::int64_t frames);

// Writes the pairs text format ("q m" with q > m, sorted) after a header
// line "# lsgd pairs: frames=N pairs=M; ..." that read_pairs() checks.
void write_pairs(const GroundTruth& gt, const std::string& path);

// The counts of write_pairs()'s header when `line` is one (-1 otherwise).
struct PairsHeader {
  std::int64_t frames = -1;
  std::int64_t pairs = -1;
};
PairsHeader pairs_header(const std::string& line);

}  // namespace lsgd::eval
