#include "lsgd/io/files.h"
#include "lsgd/eval/groundtruth.h"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "internal/check.h"
#include "lsgd/limits.h"
#include "lsgd/error.h"
#include "lsgd/io/sequence.h"

namespace lsgd::eval {

using internal::concat;

GroundTruth::GroundTruth(std::int64_t frames) : frames_(frames) {
  if (frames < 0 || frames > kMaxFrames) {
    internal::throw_invalid("ground truth frames = ", frames, ": must be in [0, ", kMaxFrames, "]");
  }
}

void GroundTruth::add(std::int64_t a, std::int64_t b) {
  const std::int64_t n = frames();
  if (a < 0 || a >= n || b < 0 || b >= n) {
    internal::throw_invalid("ground-truth pair (", a, ", ", b, ") is outside the ", n, " frames");
  }
  if (a == b) return;
  const std::int64_t q = std::max(a, b), m = std::min(a, b);
  auto& list = matches_[q];
  auto it = std::lower_bound(list.begin(), list.end(), m);
  if (it != list.end() && *it == m) return;
  if (pairs_ >= kMaxGroundTruthPairs) {
    internal::throw_invalid("the ground truth has more than ", kMaxGroundTruthPairs,
                            " pairs, the most lsgd holds (nearly every frame a loop of every other: "
                            "a poses ground truth needs a shorter distance)");
  }
  list.insert(it, m);
  ++pairs_;
}

bool GroundTruth::is_loop(std::int64_t a, std::int64_t b) const {
  const std::int64_t q = std::max(a, b), m = std::min(a, b);
  if (m < 0 || q >= frames() || q == m) return false;
  const auto it = matches_.find(q);
  return it != matches_.end() && std::binary_search(it->second.begin(), it->second.end(), m);
}

const std::vector<std::int64_t>& GroundTruth::matches(std::int64_t q) const {
  if (q < 0 || q >= frames()) {
    internal::throw_invalid("frame ", q, " is outside the ground truth's ", frames(), " frames");
  }
  static const std::vector<std::int64_t> kNone;
  const auto it = matches_.find(q);
  return it == matches_.end() ? kNone : it->second;
}

std::vector<std::int64_t> GroundTruth::queries() const {
  std::vector<std::int64_t> out;
  out.reserve(matches_.size());
  for (const auto& [q, list] : matches_) out.push_back(q);
  return out;
}

bool GroundTruth::has_loop(std::int64_t q, std::int64_t min_gap) const {
  const auto& list = matches(q);
  return !list.empty() && list.front() < q - min_gap;
}

GroundTruth read_pairs(const std::string& path, std::int64_t frames) {
  io::check_input_file(path, "ground-truth file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(concat("cannot open ground-truth file '", path, "'"));
  io::skip_utf8_bom(in);
  GroundTruth gt(frames);
  std::string line;
  for (std::int64_t number = 1; io::read_line(in, line, path, number); ++number) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    long long q = 0, m = 0;
    std::string rest;
    if (!(fields >> q >> m) || (fields >> rest)) {
      throw FormatError(concat(path, ":", number, ": expected two frame ids 'q m', got '", line,
                               "'"));
    }
    if (q < 0 || m < 0 || q >= frames || m >= frames) {
      throw FormatError(concat(path, ":", number, ": pair (", q, ", ", m,
                               ") is outside the sequence's ", frames,
                               " frames (does the ground truth belong to this sequence?)"));
    }
    gt.add(q, m);
  }
  if (in.bad()) throw IoError(concat("error while reading '", path, "'"));
  return gt;
}

void write_pairs(const GroundTruth& gt, const std::string& path) {
  std::ostringstream out;
  out << "# lsgd pairs: frames=" << gt.frames() << " pairs=" << gt.pairs()
      << "; one line per loop: q m (0-based, q > m)\n";
  for (const std::int64_t q : gt.queries()) {
    for (std::int64_t m : gt.matches(q)) out << q << ' ' << m << '\n';
  }
  io::write_output_file(path, out.str(), "ground-truth file");
}

}  // namespace lsgd::eval
