#include "lsgd/io/files.h"
#include "lsgd/eval/detections.h"
#include "lsgd/eval/results_csv.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "internal/check.h"
#include "internal/numbers.h"
#include "lsgd/io/sequence.h"
#include "lsgd/error.h"

namespace lsgd::eval {
namespace {

using internal::concat;

std::string trim(const std::string& s) {
  const char* kSpace = " \t\r\n";
  const std::size_t b = s.find_first_not_of(kSpace);
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(kSpace) - b + 1);
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Splits one record: commas (quotes honoured) when it has any, else white space.
std::vector<std::string> split_fields(const std::string& record) {
  std::vector<std::string> fields;
  if (record.find(',') == std::string::npos && record.find('"') == std::string::npos) {
    std::size_t i = 0;
    while ((i = record.find_first_not_of(" \t\r", i)) != std::string::npos) {
      const std::size_t end = std::min(record.find_first_of(" \t\r", i), record.size());
      fields.push_back(record.substr(i, end - i));
      i = end;
    }
    return fields;
  }
  for (std::string& field : csv_fields(record)) fields.push_back(trim(field));
  return fields;
}

std::optional<std::int64_t> parse_int(const std::string& s) {
  std::int64_t v = 0;
  if (!internal::parses_as(s, v)) return std::nullopt;
  return v;
}

std::optional<double> parse_double(const std::string& s) {
  double v = 0;
  if (!internal::parses_as(s, v)) return std::nullopt;
  return v;
}

// A score field: a finite number within kMaxDetectionScore of 0.
double score_of(const std::string& where, const char* column, const std::string& text) {
  const auto v = parse_double(text);
  if (!v || !std::isfinite(*v)) {
    throw FormatError(concat(where, ": ", column, " '", internal::shown_value(text), "' is not a finite number"));
  }
  if (std::abs(*v) > kMaxDetectionScore) {
    throw FormatError(concat(where, ": ", column, " ", internal::shown_value(text), " is beyond the +-", kMaxDetectionScore,
                             " lsgd reads (the report draws scores to scale)"));
  }
  return *v;
}

// Which field holds what; -1: absent.
// `loop`: lsgd run's loop_frame (the loop it declared, -1 for none); other
// systems' files have none and every reported match counts as declared.
// `ranked_*`: lsgd run's ranking (Result::ranking); the ranking is then read
// from them, not from the match.
// `rank`: top-k files (lsgd match): a query's rows are its candidates, rank 1
// its reported match.
struct Columns {
  int query = 0, match = 1, score = 2, ms = -1, loop = -1;
  int ranked_frame = -1, ranked_score = -1, ranked_confirmed = -1;
  int rank = -1;
  int needed() const {
    return std::max({query, match, score, ms, loop, ranked_frame, ranked_score, ranked_confirmed, rank}) + 1;
  }
};

int find_column(const std::vector<std::string>& header, std::initializer_list<const char*> names) {
  for (const char* name : names) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it != header.end()) return static_cast<int>(it - header.begin());
  }
  return -1;
}

// Columns named by a header line; lsgd run's header is recognised by candidate_frame.
Columns columns_from_header(std::vector<std::string> header) {
  for (auto& h : header) h = lower(h);
  Columns c;
  if (find_column(header, {"candidate_frame"}) >= 0) {
    c.query = find_column(header, {"frame"});
    c.match = find_column(header, {"candidate_frame"});
    c.score = find_column(header, {"score"});
    c.ms = find_column(header, {"ms"});
    c.loop = find_column(header, {"loop_frame"});
    c.ranked_frame = find_column(header, {"ranked_frame"});
    c.ranked_score = find_column(header, {"ranked_score"});
    c.ranked_confirmed = find_column(header, {"ranked_confirmed"});
    if (c.ranked_frame < 0 || c.ranked_score < 0 || c.ranked_confirmed < 0) {
      c.ranked_frame = c.ranked_score = c.ranked_confirmed = -1;  // all three, or none
    }
  } else {
    const int q = find_column(header, {"query", "frame"});
    const int m = find_column(header, {"match"});
    const int s = find_column(header, {"score"});
    if (q >= 0) c.query = q;
    if (m >= 0) c.match = m;
    if (s >= 0) c.score = s;
    c.rank = find_column(header, {"rank"});
  }
  return c;
}

// Reads records one at a time; a quoted field may continue on the next line.
class RecordReader {
 public:
  explicit RecordReader(const std::string& path)
      : path_(path), in_((io::check_input_file(path, "detections file"), path)) {
    if (!in_) throw IoError(concat("cannot read detections file '", path, "'"));
    io::skip_utf8_bom(in_);
  }
  // Next non-blank, non-comment record; false at the end. line() is where it starts.
  bool next(std::string& record) {
    std::string text;
    while (read_line(text)) {
      start_ = number_;
      if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);  // UTF-8 BOM
      const std::string t = trim(text);
      if (t.empty() || t[0] == '#') continue;
      record = text;
      while (std::count(record.begin(), record.end(), '"') % 2 != 0) {
        std::string more;
        if (!read_line(more)) {
          throw FormatError(concat(path_, ":", start_, ": a quoted field is never closed"));
        }
        record += '\n' + more;
      }
      return true;
    }
    if (in_.bad()) throw IoError(concat("error while reading '", path_, "'"));
    return false;
  }
  std::int64_t line() const { return start_; }

 private:
  bool read_line(std::string& text) {
    if (!io::read_line(in_, text, path_, number_ + 1)) return false;
    ++number_;
    return true;
  }
  std::string path_;
  std::ifstream in_;
  std::int64_t number_ = 0;
  std::int64_t start_ = 0;
};

struct Row {
  std::int64_t line = 0;
  std::int64_t query = 0;
  std::int64_t match = -1;
  double score = 0;
  double ms = 0;
  bool declared = false;
  std::optional<Ranking> ranking;  // lsgd run's ranking columns
  std::int64_t rank = 1;           // a top-k file's rank (1: the reported match)
};

Row parse_row(const std::vector<std::string>& f, const Columns& c, const std::string& where) {
  if (static_cast<int>(f.size()) < c.needed()) {
    throw FormatError(concat(where, ": expected at least ", c.needed(),
                             " fields (query, match, score), got ", f.size()));
  }
  Row row;
  const auto query = parse_int(f[static_cast<std::size_t>(c.query)]);
  if (!query || *query < 0) {
    throw FormatError(concat(where, ": query '", f[static_cast<std::size_t>(c.query)],
                             "' is not a frame id (an integer >= 0)"));
  }
  const auto match = parse_int(f[static_cast<std::size_t>(c.match)]);
  if (!match || *match < -1) {
    throw FormatError(concat(where, ": match '", f[static_cast<std::size_t>(c.match)],
                             "' is not a frame id or -1 (no loop)"));
  }
  if (*query >= kMaxFrames || *match >= kMaxFrames) {
    throw FormatError(concat(where, ": frame id ", std::max(*query, *match),
                             " is implausibly large (at most ", kMaxFrames,
                             " frames are supported)"));
  }
  row.query = *query;
  row.match = *match;
  const std::string& score = f[static_cast<std::size_t>(c.score)];
  if (row.match >= 0) row.score = score_of(where, "score", score);
  row.declared = row.match >= 0;
  if (c.loop >= 0) {
    const auto loop = parse_int(f[static_cast<std::size_t>(c.loop)]);
    if (!loop || (*loop != -1 && *loop != row.match)) {
      throw FormatError(concat(where, ": loop_frame '", f[static_cast<std::size_t>(c.loop)],
                               "' is neither -1 nor the candidate_frame"));
    }
    row.declared = *loop >= 0;
  }
  if (c.ms >= 0) {
    const auto ms = parse_double(f[static_cast<std::size_t>(c.ms)]);
    if (!ms || !std::isfinite(*ms) || *ms < 0) {
      throw FormatError(concat(where, ": ms '", f[static_cast<std::size_t>(c.ms)],
                               "' is not a time in milliseconds"));
    }
    row.ms = *ms;
  }
  if (c.rank >= 0) {
    const auto rank = parse_int(f[static_cast<std::size_t>(c.rank)]);
    if (!rank || *rank < 1 || *rank > 1000000) {
      throw FormatError(concat(where, ": rank '", f[static_cast<std::size_t>(c.rank)],
                               "' is not a rank (1 for the reported match, 2, 3, ...)"));
    }
    row.rank = *rank;
    if (row.match < 0 && row.rank > 1) {
      throw FormatError(concat(where, ": rank ", row.rank, " has no match (only rank 1 may be -1)"));
    }
  }
  if (c.ranked_frame >= 0) {
    const std::string& frame = f[static_cast<std::size_t>(c.ranked_frame)];
    const std::string& ranked_score = f[static_cast<std::size_t>(c.ranked_score)];
    const std::string& confirmed = f[static_cast<std::size_t>(c.ranked_confirmed)];
    const auto j = parse_int(frame);
    if (!j || *j < -1 || *j >= kMaxFrames) {
      throw FormatError(concat(where, ": ranked_frame '", frame, "' is not a frame id or -1"));
    }
    const double v = score_of(where, "ranked_score", ranked_score);
    if (confirmed != "0" && confirmed != "1") {
      throw FormatError(concat(where, ": ranked_confirmed '", confirmed, "' is neither 0 nor 1"));
    }
    row.ranking = Ranking{Candidate{*j, v}, confirmed == "1"};
  }
  return row;
}

// Reads the file's rows; a header, when there is one, sets `columns`.
std::vector<Row> read_rows(const std::string& path, Columns& columns) {
  RecordReader reader(path);
  std::vector<Row> rows;
  std::string record;
  for (bool first = true; reader.next(record); first = false) {
    const std::vector<std::string> fields = split_fields(record);
    if (first && !parse_int(fields.front())) {  // a header: the first field is no frame id
      columns = columns_from_header(fields);
      if (columns.query < 0 || columns.match < 0 || columns.score < 0) {
        throw FormatError(concat(path, ":", reader.line(),
                                 ": lsgd run header without frame, candidate_frame or score"));
      }
      continue;
    }
    Row row = parse_row(fields, columns, concat(path, ":", reader.line()));
    row.line = reader.line();
    rows.push_back(row);
  }
  if (rows.empty()) throw FormatError(concat("detections file '", path, "' has no row"));
  return rows;
}

// The sequence length: `frames` when given (>= 0), else one past the last query.
std::int64_t frame_count(const std::vector<Row>& rows, std::int64_t frames) {
  if (frames >= 0) return frames;
  frames = 0;
  for (const Row& r : rows) frames = std::max(frames, r.query + 1);
  return frames;
}

// One query's rows of a top-k file: (rank, (candidate, line)).
using Ranks = std::vector<std::pair<std::int64_t, std::pair<Candidate, std::int64_t>>>;

// Throws unless the row's frame ids lie in [0, frames).
void check_row_frames(const Row& r, std::int64_t frames, const std::string& where) {
  if (r.query >= frames) {
    throw FormatError(concat(where, ": query ", r.query, " is outside the ", frames,
                             " frames (does the file belong to this sequence and subsampling?)"));
  }
  if (r.match >= frames) {
    throw FormatError(concat(where, ": match ", r.match, " is outside the ", frames, " frames"));
  }
  if (r.ranking && r.ranking->best.frame >= frames) {
    throw FormatError(concat(where, ": ranked_frame ", r.ranking->best.frame, " is outside the ",
                             frames, " frames"));
  }
}

// Notes a top-k row under its query; true for rank 1 (the reported match).
// A rank given twice is found once the query's ranks are sorted
// (set_ranked_candidates): a search here for each row was quadratic in a
// query's ranks (85,000 of them took 2.9 s).
bool note_rank(const Row& r, Ranks& ranks) {
  ranks.push_back({r.rank, {Candidate{r.match, r.score}, r.line}});
  return r.rank == 1;
}

// Notes a row of a one-row-per-query file; throws on a second row for its query.
void note_single(const Row& r, std::int64_t& seen, const std::string& where) {
  if (seen != 0) {
    throw FormatError(concat(where, ": query ", r.query, " already has a row on line ", seen,
                             " (one reported loop per query; top-k files have a rank column)"));
  }
  seen = r.line;
}

// Sets a query's record from its reported row.
void set_reported(const Row& r, FrameRecord& out) {
  out.timings.total_ms = r.ms;
  out.ranking = r.ranking;
  if (r.match >= 0) {
    out.reported = Candidate{r.match, r.score};
    out.candidates = {out.reported};
    out.loop = r.declared;
  }
}

// Top-k files: each query's candidates in rank order; throws when rank 1 is missing.
void set_ranked_candidates(const std::string& path, std::vector<Ranks>& ranks_of,
                           std::vector<FrameRecord>& records) {
  for (std::size_t k = 0; k < ranks_of.size(); ++k) {
    auto& ranks = ranks_of[k];
    if (ranks.empty()) continue;
    // By rank, then by line: a rank given twice names both lines, the first as
    // where it was given already.
    std::sort(ranks.begin(), ranks.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first < b.first : a.second.second < b.second.second;
    });
    FrameRecord& out = records[k];
    for (std::size_t i = 1; i < ranks.size(); ++i) {
      if (ranks[i].first == ranks[i - 1].first) {
        throw FormatError(concat(path, ":", ranks[i].second.second, ": query ", out.frame, " already has rank ",
                                 ranks[i].first, " on line ", ranks[i - 1].second.second));
      }
    }
    if (ranks.front().first != 1) {
      throw FormatError(concat(path, ":", ranks.front().second.second, ": query ", out.frame,
                               " has ranks from ", ranks.front().first, " but no rank 1 (its reported match)"));
    }
    out.candidates.clear();
    for (const auto& rank : ranks) {
      if (rank.second.first.frame >= 0) out.candidates.push_back(rank.second.first);
    }
  }
}

}  // namespace

std::vector<FrameRecord> read_detections(const std::string& path, std::int64_t frames) {
  if (frames < -1 || frames > kMaxFrames) {
    internal::throw_invalid("read_detections: frames = ", frames, " must be in [-1, ", kMaxFrames,
                            "]");
  }
  Columns columns;
  const std::vector<Row> rows = read_rows(path, columns);
  frames = frame_count(rows, frames);
  // One record per query that has a row, so memory follows the file, not the
  // frame ids it names (a 12-byte file may name frame 9,999,999).
  std::vector<FrameRecord> records;
  std::vector<std::int64_t> line_of;  // per record: its row (one-row-per-query files)
  std::vector<Ranks> ranks_of;        // per record: its ranked rows (top-k files)
  std::unordered_map<std::int64_t, std::size_t> record_of_query;
  for (const Row& r : rows) {
    const std::string where = concat(path, ":", r.line);
    check_row_frames(r, frames, where);
    const auto [it, added] = record_of_query.try_emplace(r.query, records.size());
    if (added) {
      records.emplace_back().frame = r.query;
      line_of.push_back(0);
      if (columns.rank >= 0) ranks_of.emplace_back();
    }
    const std::size_t k = it->second;
    if (columns.rank >= 0) {
      // A top-k file: the query's candidates by rank, rank 1 reported.
      if (!note_rank(r, ranks_of[k])) continue;
    } else {
      note_single(r, line_of[k], where);
    }
    set_reported(r, records[k]);
  }
  set_ranked_candidates(path, ranks_of, records);
  std::sort(records.begin(), records.end(),
            [](const FrameRecord& a, const FrameRecord& b) { return a.frame < b.frame; });
  return records;
}

std::vector<std::string> detections_warnings(const std::vector<FrameRecord>& records,
                                             const GroundTruth& gt, std::int64_t min_gap,
                                             const std::string& name) {
  std::vector<std::string> warnings;
  std::int64_t revisits = 0, without_row = 0;
  std::size_t r = 0;
  for (std::int64_t q = 0; q < gt.frames(); ++q) {
    while (r < records.size() && records[r].frame < q) ++r;
    if (!gt.has_loop(q, min_gap)) continue;
    ++revisits;
    without_row += r < records.size() && records[r].frame == q ? 0 : 1;
  }
  if (without_row > 0) {
    warnings.push_back(concat(name, " has no row for ", without_row, " of the ", revisits,
                              " revisits the ground truth lists: they count as missed (score a CSV "
                              "of lsgd run --first, --last or --every with the same flags)"));
  }
  std::int64_t forward = 0, itself = 0;
  const FrameRecord* first = nullptr;
  for (const FrameRecord& record : records) {
    if (!record.loop || record.reported.frame < record.frame) continue;
    ++forward;
    itself += record.reported.frame == record.frame ? 1 : 0;
    if (!first) first = &record;
  }
  if (forward > 0) {
    warnings.push_back(concat(
        name, " reports ", forward, " match", forward == 1 ? "" : "es", " to the query itself or a "
        "later frame (", itself, " to itself; the first: query ", first->frame, " -> ",
        first->reported.frame, "): a loop closes on an earlier frame, and the strict protocol counts "
        "them as false loops (does the system store a frame before it queries it, or are the "
        "columns match,query?)"));
  }
  return warnings;
}

}  // namespace lsgd::eval
