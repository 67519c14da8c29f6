#include "lsgd/io/files.h"
#include "lsgd/eval/groundtruth.h"

#include <algorithm>
#include <charconv>
#include <cstring>
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

namespace {

constexpr const char* kPairsHeader = "# lsgd pairs: ";

// The number after `key` ("frames=") in `line`, or -1.
std::int64_t header_count(const std::string& line, const char* key) {
  const std::size_t at = line.find(key);
  if (at == std::string::npos) return -1;
  const char* begin = line.data() + at + std::strlen(key);
  std::int64_t value = -1;
  const auto [end, ec] = std::from_chars(begin, line.data() + line.size(), value);
  return ec == std::errc() && end != begin && value >= 0 ? value : -1;
}

}  // namespace

PairsHeader pairs_header(const std::string& line) {
  PairsHeader header;
  if (line.rfind(kPairsHeader, 0) != 0) return header;
  // Up to the first ';': the comment after it is free text.
  const std::string counts = line.substr(0, line.find(';'));
  header.frames = header_count(counts, " frames=");
  header.pairs = header_count(counts, " pairs=");
  return header;
}

GroundTruth read_pairs(const std::string& path, std::int64_t frames) {
  io::check_input_file(path, "ground-truth file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(concat("cannot open ground-truth file '", path, "'"));
  io::skip_utf8_bom(in);
  GroundTruth gt(frames);
  std::string line;
  PairsHeader header;
  for (std::int64_t number = 1; io::read_line(in, line, path, number); ++number) {
    if (number == 1) {
      header = pairs_header(line);
      if (header.frames >= 0 && header.frames != frames) {
        throw FormatError(concat(path, ":1: the header says frames=", header.frames, " but the sequence has ",
                                 frames, " frames (does the ground truth belong to this sequence?)"));
      }
    }
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
  if (header.pairs >= 0 && header.pairs != gt.pairs()) {
    throw FormatError(concat(path, ": holds ", gt.pairs(), " pairs but its header says pairs=", header.pairs,
                             ": cut short or edited? (lsgd wrote the header with the file; write the file "
                             "again, or delete the header line to take the pairs as they are)"));
  }
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
