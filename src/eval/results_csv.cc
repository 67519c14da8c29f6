#include "lsgd/eval/results_csv.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <system_error>

#include "lsgd/error.h"
#include "lsgd/io/files.h"
#include "lsgd/options.h"

namespace lsgd::eval {

using io::throw_cannot_write;

std::string match_csv(const std::vector<TopMatch>& matches) {
  std::ostringstream out;
  out << "query,match,score,similarity,rank\n";
  for (const TopMatch& m : matches) {
    out << m.query << ',' << m.match << ',' << std::setprecision(9) << m.score << ',' << m.similarity
        << ',' << m.rank << '\n';
  }
  return out.str();
}

std::string csv_field(const std::string& text) {
  // A lone CR ends a line for every reader of text here (io::read_line): quoted too.
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::vector<std::string> csv_fields(const std::string& record) {
  std::vector<std::string> fields;
  std::string field;
  bool quoted = false;
  for (std::size_t i = 0; i < record.size(); ++i) {
    const char c = record[i];
    if (quoted && c == '"' && i + 1 < record.size() && record[i + 1] == '"') {
      field += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      fields.push_back(std::move(field));
      field.clear();
    } else {
      field += c;
    }
  }
  fields.push_back(std::move(field));
  return fields;
}

namespace {

// The headers of the CSV's versions, oldest first; a run resumes in the
// columns of the header its CSV has (CsvWriter::Trim::version).
constexpr const char* kCsvHeaders[] = {
    "frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers",
    "frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers,ranked_frame,ranked_score,"
    "ranked_confirmed",
    "frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers,ranked_frame,ranked_score,"
    "ranked_confirmed,status",
    "frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers,ranked_frame,ranked_score,"
    "ranked_confirmed,status,stamp",
};
constexpr int kRankingVersion = 1;  // the first with the ranking's columns
constexpr int kStatusVersion = 2;   // ... with the status
constexpr int kStampVersion = 3;    // ... with the frame's time stamp

// The image of a row (its second field, unquoted: csv_field()).
std::string row_image(const std::string& row) {
  const std::vector<std::string> fields = csv_fields(row);
  return fields.size() > 1 ? fields[1] : std::string();
}

}  // namespace

CsvWriter::CsvWriter(const std::string& path, Mode mode, int version)
    : path_(path), version_(mode == kCreate ? kCsvNewest : version), out_(&std::cout) {
  if (version_ < 0 || version_ > kCsvNewest) {
    throw InvalidArgument("CsvWriter: version " + std::to_string(version) + " of the CSV does not exist");
  }
  if (!path.empty()) {
    lock_ = io::OutputLock(path, "CSV");  // before the file is truncated
    file_ = std::make_unique<std::ofstream>(
        path, mode == kAppend ? std::ios::out | std::ios::app : std::ios::out | std::ios::trunc);
    if (!*file_) throw_cannot_write(path);
    out_ = file_.get();
  }
  if (mode == kCreate) *out_ << kCsvHeaders[kCsvNewest] << "\n" << std::flush;
  if (!*out_) throw IoError("error while writing " + (path.empty() ? "the CSV rows to standard output" : "'" + path + "'"));
}

void CsvWriter::write(const Result& r, const std::string& image) {
  *out_ << r.frame << ',' << csv_field(image) << ',' << (r.loop ? r.best.frame : -1) << ',' << r.best.frame
        << ',' << std::setprecision(9) << (r.best.frame >= 0 ? r.best.score : 0.0) << ','
        << std::setprecision(4) << r.timings.total_ms << ',' << std::setprecision(6)
        << (r.best.frame >= 0 ? r.evidence.appearance : 0.0) << ',' << r.evidence.inliers;
  if (version_ >= kRankingVersion) {
    const bool ranked = r.ranking.best.frame >= 0;
    *out_ << ',' << r.ranking.best.frame << ',' << std::setprecision(9)
          << (ranked ? r.ranking.best.score : 0.0) << ',' << (ranked && r.ranking.confirmed ? 1 : 0);
  }
  if (version_ >= kStatusVersion) *out_ << ',' << to_string(r.status);
  if (version_ >= kStampVersion) {  // empty when the frame has none; else the shortest exact text
    *out_ << ',';
    if (std::isfinite(r.stamp)) *out_ << shortest_text(r.stamp);
  }
  errno = 0;
  *out_ << '\n' << std::flush;
  if (!*out_) {
    // The system's reason when the stream kept it (a full disk, a file size limit).
    const int error = errno;
    const std::string why = error == ENOSPC || error == EFBIG || error == EIO ? std::strerror(error)
                                                                             : "is the disk full?";
    throw IoError("error while writing the row of frame " + std::to_string(r.frame) + " to " +
                  (path_.empty() ? std::string("standard output") : "'" + path_ + "' (" + why + ")"));
  }
  loops_ += r.loop ? 1 : 0;
}

CsvWriter::Trim CsvWriter::trim(const std::string& path, std::int64_t last_frame,
                                const RowCheck& check) {
  const io::OutputLock lock(path, "CSV");  // no other writer cuts or adds rows meanwhile
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot read '" + path + "'");
  std::string line;
  const bool read = static_cast<bool>(std::getline(in, line));
  Trim trim;
  trim.version = -1;
  for (int v = 0; read && v <= kCsvNewest; ++v) {
    if (line == kCsvHeaders[v]) trim.version = v;
  }
  if (trim.version < 0) {
    throw FormatError("'" + path + "' is not a CSV of lsgd run (its first line is not '" +
                      kCsvHeaders[kCsvNewest] + "'); pass another --output");
  }
  std::int64_t keep = static_cast<std::int64_t>(line.size()) + 1;  // bytes kept
  bool cutting = false;
  std::string last_kept;               // the last row kept
  std::int64_t first_cut = -1;         // the first complete row cut: its frame
  std::string first_cut_row;
  while (std::getline(in, line)) {
    bool complete = !in.eof();  // the line ended with '\n'
    // A quoted image name may hold a newline (csv_field): the row goes on
    // while its quotes are open.
    std::string more;
    while (complete && std::count(line.begin(), line.end(), '"') % 2 != 0 && std::getline(in, more)) {
      line += '\n' + more;
      complete = !in.eof();
    }
    std::int64_t frame = -1;
    const auto comma = line.find(',');
    try {
      if (comma != std::string::npos) frame = std::stoll(line.substr(0, comma));
    } catch (const std::exception&) {
      frame = -1;
    }
    if (!cutting && complete && frame >= 0 && frame <= last_frame) {
      keep += static_cast<std::int64_t>(line.size()) + 1;
      trim.last_row = frame;
      if (check) last_kept = line;
      continue;
    }
    cutting = true;
    if (!complete) {
      trim.partial = true;
    } else if (frame >= 0) {
      if (++trim.dropped == 1 && check) {
        first_cut = frame;
        first_cut_row = line;
      }
    } else {
      ++trim.other;  // not a row of lsgd run (a line added to the file)
    }
  }
  if (check && trim.last_row >= 0) check(trim.last_row, row_image(last_kept));
  if (check && first_cut >= 0) check(first_cut, row_image(first_cut_row));
  if (trim.dropped > 0 || trim.other > 0 || trim.partial) {
    in.close();
    std::error_code ec;
    std::filesystem::resize_file(path, static_cast<std::uintmax_t>(keep), ec);
    if (ec) throw IoError("cannot cut the rows after frame " + std::to_string(last_frame) +
                          " from '" + path + "': " + ec.message());
  }
  return trim;
}

}  // namespace lsgd::eval
