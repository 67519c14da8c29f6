// Reading and checking a database's header when it is opened (Database::Impl::
// load_header): the file's structure, our tables, meta and the frames' ids,
// each step refusing what it finds damaged with a FormatError.
#include <sqlite3.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>

#include "io/database_internal.h"
#include "lsgd/io/config.h"
#include "lsgd/limits.h"
#include "lsgd/version.h"

namespace lsgd::io {

void Database::Impl::load_header() {
  // 1. SQLite's own structural check: catches truncation and damaged pages.
  check_integrity();
  check_file_size();
  // 2. Our tables.
  check_tables();
  // 3. Meta, the format version first: a newer format may change the rest.
  std::map<std::string, int> types = read_meta();
  read_format(types);
  check_meta(types);
  read_options();
  read_frame_size();
  // 4. Frames: columns present, ids dense.
  count_frames();
  read_session_first_ids();
  read_last_frame();
}

void Database::Impl::check_integrity() const {
  Statement check(db, path, "PRAGMA quick_check");
  if (step_read(db, check.get(), path)) {
    std::string verdict = column_text(check.get(), 0);
    if (verdict != "ok") {
      // Its first problem on one line (it may list a hundred pages).
      for (char& c : verdict) c = c == '\n' ? ' ' : c;
      if (verdict.size() > 200) verdict = concat(verdict.substr(0, 200), "...");
      // A log that does not belong to this file (a backup restored beside
      // a newer log) damages it as it is replayed: say what to do.
      const std::string hint =
          file_size(path + "-wal") > 0
              ? concat(". If the file was restored from a backup beside a newer write-ahead log, "
                       "move '", path, "-wal' (and '", path, "-shm') away and open it again")
              : std::string();
      format_error(path, "damaged (SQLite quick_check: ", verdict, ")", hint);
    }
  }
}

// A file cut at a page boundary, or cut inside its last page's unused tail,
// may pass quick_check (SQLite reads missing bytes as zeros): the size must
// be the page count times the page size. Pages still in a write-ahead log
// (a writer is active or crashed) are not in the file yet: skipped then.
void Database::Impl::check_file_size() const {
  if (file_size(path + "-wal") != 0) return;
  Statement size(db, path,
                 "SELECT page_size * page_count, page_size FROM pragma_page_size, "
                 "pragma_page_count");
  step_read(db, size.get(), path);
  const std::int64_t expected = sqlite3_column_int64(size.get(), 0);
  const std::int64_t page = sqlite3_column_int64(size.get(), 1);
  const std::int64_t actual = file_size(path);
  if (actual != 0 && (actual < expected || actual % std::max<std::int64_t>(page, 1) != 0)) {
    format_error(path, "truncated or damaged: ", actual, " bytes, but its header counts ",
                 expected / std::max<std::int64_t>(page, 1), " pages of ", page, " bytes");
  }
}

void Database::Impl::check_tables() const {
  Statement tables(db, path,
                   "SELECT count(*) FROM sqlite_schema WHERE type = 'table' AND "
                   "name IN ('meta', 'frames')");
  if (!step_read(db, tables.get(), path) || sqlite3_column_int(tables.get(), 0) != 2) {
    format_error(path, "not an lsgd database (no meta and frames tables)");
  }
}

std::map<std::string, int> Database::Impl::read_meta() {
  std::map<std::string, int> types;
  Statement rows(db, path, "SELECT key, value FROM meta");
  while (step_read(db, rows.get(), path)) {
    const std::string key = column_text(rows.get(), 0);
    types[key] = sqlite3_column_type(rows.get(), 1);
    meta[key] = column_text(rows.get(), 1);
  }
  return types;
}

void Database::Impl::read_format(std::map<std::string, int>& types) {
  const auto version = meta.find("format_version");
  if (version == meta.end()) format_error(path, "not an lsgd database (no format_version in meta)");
  if (types["format_version"] != SQLITE_INTEGER) {
    format_error(path, "format_version '", version->second, "' is not an integer");
  }
  const long long stored_format = std::stoll(version->second);
  if (stored_format > kDatabaseFormatVersion) {
    format_error(path, "format version ", stored_format, " is newer than this lsgd (", lsgd::version(),
                 ") reads (", kDatabaseFormatVersion, "): use a newer lsgd");
  }
  if (stored_format < 1) format_error(path, "unknown format version ", stored_format);
  format = static_cast<int>(stored_format);
}

// Every key present, the integer ones stored as integers, the checksum right.
void Database::Impl::check_meta(std::map<std::string, int>& types) {
  for (const char* key :
       {"library_version", "options", "width", "height", "grid_rows", "grid_cols", "checksum"}) {
    if (meta.find(key) == meta.end()) format_error(path, "meta has no ", key);
  }
  for (const auto& key : kIntegerMeta) {
    if (types[key] != SQLITE_INTEGER) {
      format_error(path, "meta ", key, " '", meta[key], "' is not an integer");
    }
  }
  const std::uint32_t checksum = meta_checksum(meta);
  if (std::to_string(checksum) != meta["checksum"]) {
    format_error(path, "meta checksum ", meta["checksum"], " does not match its content (",
                 checksum, "): the file was modified or damaged");
  }
}

void Database::Impl::read_options() {
  try {
    // A key missing from a stored file did not exist when it was written: it
    // takes the value that reproduces that version's behaviour, not today's
    // default (verification.temporal.long_frames came with default 48).
    DetectorOptions before;
    before.verification.temporal_options.long_frames = 0;
    before.verification.geometric_options.max_side = 0;  // came with format 2
    before.segmentation.working_side = 0;  // frames were segmented at their own size
    options = parse_config(meta["options"], "database " + path + " meta options", before);
    // Format 1 decision thresholds were raw similarities: this version's
    // decision (in sigma) replaces them.
    if (format < 2) options.decision = DecisionOptions{};
  } catch (const InvalidArgument& e) {
    throw FormatError(e.what());
  }
}

// The frame size and grid, which the segmentation's options must give.
void Database::Impl::read_frame_size() {
  const auto integer = [&](const char* key, long long lo, long long hi) {
    const long long v = std::stoll(meta[key]);
    if (v < lo || v > hi) format_error(path, "meta ", key, " = ", v, " is out of range");
    return static_cast<int>(v);
  };
  width = integer("width", 0, kMaxImageSide);
  height = integer("height", 0, kMaxImageSide);
  grid.rows = integer("grid_rows", 0, kMaxImageSide);
  grid.cols = integer("grid_cols", 0, kMaxImageSide);
  const bool sized = width > 0 && height > 0;
  if ((width > 0) != (height > 0) ||
      (sized && grid != frame_grid(width, height, options.segmentation)) ||
      (!sized && (grid.rows != 0 || grid.cols != 0))) {
    format_error(path, "meta frame size ", width, "x", height, " and grid ", grid.rows, "x",
                 grid.cols, " do not match segmentation.superpixel_size ",
                 options.segmentation.superpixel_size);
  }
}

void Database::Impl::count_frames() {
  { Statement columns(db, path, select_frames(format, " LIMIT 0").c_str()); }
  Statement count(db, path, "SELECT count(*), min(id), max(id) FROM frames");
  step_read(db, count.get(), path);
  frames = sqlite3_column_int64(count.get(), 0);
  if (frames > 0 && (sqlite3_column_int64(count.get(), 1) != 0 ||
                     sqlite3_column_int64(count.get(), 2) != frames - 1)) {
    format_error(path, "frame ids are not 0 .. ", frames - 1, " (", frames, " rows, ids ",
                 sqlite3_column_int64(count.get(), 1), " .. ",
                 sqlite3_column_int64(count.get(), 2), ")");
  }
  const bool sized = width > 0 && height > 0;
  if (frames > 0 && !sized) format_error(path, frames, " frames but no frame size in meta");
}

void Database::Impl::read_session_first_ids() {
  const auto first = meta.find("session_first_ids");
  if (first == meta.end()) return;
  // "session=first_id" pairs separated by spaces.
  std::istringstream in(first->second);
  std::string pair;
  while (in >> pair) {
    long long s = -1, f = -1;
    char end = 0;
    if (std::sscanf(pair.c_str(), "%lld=%lld%c", &s, &f, &end) != 2 || s < 0 || f < 0 ||
        s > kMaxSession || f > kMaxFrameId) {
      format_error(path, "meta session_first_ids '", first->second, "' is not session=first_id pairs");
    }
    session_first[s] = f;
  }
}

// The last row's session and id, and every session with frames.
void Database::Impl::read_last_frame() {
  if (frames == 0) return;
  Statement last(db, path,
                 concat("SELECT session, ", frame_column(format),
                        " FROM frames ORDER BY id DESC LIMIT 1")
                     .c_str());
  step_read(db, last.get(), path);
  last_session = sqlite3_column_int64(last.get(), 0);
  last_frame = sqlite3_column_int64(last.get(), 1);
  Statement distinct(db, path, "SELECT DISTINCT session FROM frames");
  while (step_read(db, distinct.get(), path)) {
    sessions.insert(sqlite3_column_int64(distinct.get(), 0));
  }
}

}  // namespace lsgd::io
