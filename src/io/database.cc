#include "lsgd/io/database.h"

#include <errno.h>
#include <fcntl.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <type_traits>

#include "internal/check.h"
#include "lsgd/error.h"
#include "io/wal_check.h"
#include "lsgd/io/config.h"
#include "lsgd/limits.h"
#include "lsgd/version.h"


namespace lsgd::io {
namespace {

using internal::concat;

constexpr std::int64_t kNull = std::numeric_limits<std::int64_t>::min();  // NULL in checksums
// Appends between checkpoints (Impl::checkpoint): the most frames that live
// only in the write-ahead log.
constexpr std::int64_t kCheckpointFrames = 32;

template <typename... Parts>
[[noreturn]] void format_error(const std::string& path, const Parts&... parts) {
  throw FormatError(concat("database ", path, ": ", parts...));
}

template <typename... Parts>
[[noreturn]] void io_error(const std::string& path, const Parts&... parts) {
  throw IoError(concat("database ", path, ": ", parts...));
}

// ---- little-endian blobs (memcpy on little-endian hosts)

constexpr bool kLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

template <typename T>
void encode_le(const T* values, std::size_t n, std::vector<std::uint8_t>& out) {
  static_assert(std::is_unsigned_v<T>);
  const std::size_t start = out.size();
  out.resize(start + n * sizeof(T));
  std::uint8_t* dst = out.data() + start;
  if constexpr (kLittleEndian) {
    if (n > 0) std::memcpy(dst, values, n * sizeof(T));
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t b = 0; b < sizeof(T); ++b)
        dst[i * sizeof(T) + b] = (values[i] >> (8 * b)) & 0xFF;
    }
  }
}

template <typename T>
void decode_le(const std::uint8_t* src, std::size_t n, T* values) {
  static_assert(std::is_unsigned_v<T>);
  if constexpr (kLittleEndian) {
    if (n > 0) std::memcpy(values, src, n * sizeof(T));
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      T v = 0;
      for (std::size_t b = 0; b < sizeof(T); ++b)
        v |= static_cast<T>(src[i * sizeof(T) + b]) << (8 * b);
      values[i] = v;
    }
  }
}

// ---- checksums (zlib's CRC-32; python3 -c "import zlib" recomputes them)

std::uint32_t crc_bytes(std::uint32_t crc, const void* data, std::size_t n) {
  const auto* p = static_cast<const Bytef*>(data);
  while (n > 0) {  // crc32() takes a uInt length
    const auto chunk = static_cast<uInt>(std::min<std::size_t>(n, 1u << 30));
    crc = static_cast<std::uint32_t>(crc32(crc, p, chunk));
    p += chunk;
    n -= chunk;
  }
  return crc;
}

// CRC-32 of n bytes on their own.
std::uint32_t crc_of(const void* data, std::size_t n) {
  return crc_bytes(static_cast<std::uint32_t>(crc32(0, Z_NULL, 0)), data, n);
}

std::uint32_t crc_int(std::uint32_t crc, std::int64_t v) {
  std::uint8_t b[8];
  for (int i = 0; i < 8; ++i)
    b[i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * i));
  return crc_bytes(crc, b, 8);
}

// A blob: its length as an int64 (-1 for NULL), then its bytes.
std::uint32_t crc_blob(std::uint32_t crc, const void* data, std::int64_t n) {
  crc = crc_int(crc, n);
  return n > 0 ? crc_bytes(crc, data, static_cast<std::size_t>(n)) : crc;
}

struct RowBytes {
  std::int64_t id = 0, session = 0, node = kNull, place = kNull;
  // The decision's state after the frame (format 2); loop_inliers NULL: a row
  // written by format 1, whose checksum does not cover them.
  std::int64_t loop = kNull;
  bool has_loop_inliers = false;
  double loop_inliers = 0;
  // The caller's frame id (format 3); NULL in rows of older formats, whose
  // checksum does not cover it (their frame id is their row id).
  std::int64_t frame = kNull;
  const void* name = nullptr;
  std::int64_t name_size = 0;
  const void* hist = nullptr;
  std::int64_t hist_size = 0;
  const void* pixels = nullptr;
  std::int64_t pixels_size = 0;
  const void* features = nullptr;
  std::int64_t features_size = -1;  // -1: NULL
  // The components' per-frame state (format 4, Detector::frame_state());
  // -1: NULL (rows of older formats, whose checksum does not cover it).
  const void* state = nullptr;
  std::int64_t state_size = -1;
};

// CRC-32 of a frame row: id, session, node, place as int64 little-endian
// (NULL = INT64_MIN), then (rows with loop_inliers, format 2) loop as int64
// and loop_inliers' IEEE-754 bits as int64, then (rows with a frame id,
// format 3) frame as int64, then name, histogram, pixels, features as blobs,
// then (rows with a state, format 4) state as a blob.
std::uint32_t row_checksum(const RowBytes& r) {
  std::uint32_t crc = static_cast<std::uint32_t>(crc32(0, Z_NULL, 0));
  crc = crc_int(crc, r.id);
  crc = crc_int(crc, r.session);
  crc = crc_int(crc, r.node);
  crc = crc_int(crc, r.place);
  if (r.has_loop_inliers) {
    std::int64_t bits = 0;
    std::memcpy(&bits, &r.loop_inliers, sizeof bits);
    crc = crc_int(crc, r.loop);
    crc = crc_int(crc, bits);
  }
  if (r.frame != kNull) crc = crc_int(crc, r.frame);
  crc = crc_blob(crc, r.name, r.name_size);
  crc = crc_blob(crc, r.hist, r.hist_size);
  crc = crc_blob(crc, r.pixels, r.pixels_size);
  crc = crc_blob(crc, r.features, r.features_size);
  if (r.state_size >= 0) crc = crc_blob(crc, r.state, r.state_size);
  return crc;
}

// CRC-32 of "key=value\n" for every meta key but "checksum", keys in order.
std::uint32_t meta_checksum(const std::map<std::string, std::string>& meta) {
  std::string text;
  for (const auto& [key, value] : meta) {
    if (key != "checksum") text += key + "=" + value + "\n";
  }
  return crc_of(text.data(), text.size());
}

// ---- SQLite helpers

class Statement {
 public:
  Statement() = default;
  Statement(sqlite3* db, const std::string& path, const char* sql) {
    if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK) {
      const std::string message = sqlite3_errmsg(db);
      sqlite3_finalize(stmt_);
      stmt_ = nullptr;
      format_error(path, "cannot read (", message, ") in: ", sql);
    }
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(Statement&& o) noexcept : stmt_(o.stmt_) { o.stmt_ = nullptr; }
  Statement& operator=(Statement&& o) noexcept {
    std::swap(stmt_, o.stmt_);
    return *this;
  }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  sqlite3_stmt* get() const { return stmt_; }

 private:
  sqlite3_stmt* stmt_ = nullptr;
};

// Runs statements that return no rows; any failure is an IoError (writing).
void exec_write(sqlite3* db, const std::string& path, const char* sql) {
  char* error = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &error) != SQLITE_OK) {
    const std::string message = error ? error : sqlite3_errmsg(db);
    sqlite3_free(error);
    io_error(path, "cannot write (", message, ")");
  }
}

// Steps a reading statement: true for a row, false when done; an error is a FormatError.
bool step_read(sqlite3* db, sqlite3_stmt* stmt, const std::string& path) {
  const int rc = sqlite3_step(stmt);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  const int primary = rc & 0xFF;
  if (primary == SQLITE_BUSY || primary == SQLITE_LOCKED || primary == SQLITE_CANTOPEN ||
      primary == SQLITE_PERM || primary == SQLITE_NOMEM) {
    io_error(path, "cannot read (", sqlite3_errmsg(db), ")");
  }
  format_error(path, "damaged or not an lsgd database (SQLite: ", sqlite3_errmsg(db), ")");
}

std::string column_text(sqlite3_stmt* stmt, int column) {
  const auto* text = sqlite3_column_text(stmt, column);
  return text ? std::string(reinterpret_cast<const char*>(text),
                            static_cast<std::size_t>(sqlite3_column_bytes(stmt, column)))
              : std::string();
}

std::int64_t file_size(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 ? static_cast<std::int64_t>(st.st_size) : 0;
}


const char* kSchema =
    "CREATE TABLE meta(key TEXT PRIMARY KEY, value NOT NULL);"
    "CREATE TABLE frames("
    "id INTEGER PRIMARY KEY, session INTEGER NOT NULL, name TEXT NOT NULL,"
    "histogram BLOB NOT NULL, pixels BLOB NOT NULL, node INTEGER, place INTEGER,"
    "features BLOB, crc32 INTEGER NOT NULL, loop INTEGER, loop_inliers REAL, frame INTEGER,"
    "state BLOB);";
// Format 5's table of saved search indexes (made with the schema, and by the
// upgrade of older files).
const char* kIndexesTable =
    "CREATE TABLE IF NOT EXISTS indexes(mode TEXT NOT NULL, part INTEGER NOT NULL,"
    "frames INTEGER NOT NULL, data BLOB NOT NULL, crc32 INTEGER NOT NULL, PRIMARY KEY(mode, part));";

// Columns a format lacks read as NULL: loop state before 2, frame ids before
// 3, the components' state before 4.
std::string select_frames(int format, const char* tail = " ORDER BY id") {
  return concat("SELECT id, session, name, histogram, pixels, node, place, features, crc32, ",
                format < 2 ? "NULL, NULL" : "loop, loop_inliers", ", ",
                format < 3 ? "NULL" : "frame", ", ", format < 4 ? "NULL" : "state", " FROM frames",
                tail);
}

// The caller's id of a row: its frame column, or its row id in older formats.
std::string frame_column(int format) { return format < 3 ? "id" : "coalesce(frame, id)"; }

const char* kInsertFrame =
    "INSERT INTO frames(id, session, name, histogram, pixels, node, crc32, frame, state) "
    "VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)";

// Older formats -> 4, inside the caller's transaction.
const char* kUpgradeV1 =
    "ALTER TABLE frames ADD COLUMN loop INTEGER; ALTER TABLE frames ADD COLUMN loop_inliers REAL;";
const char* kUpgradeV2 = "ALTER TABLE frames ADD COLUMN frame INTEGER;";
const char* kUpgradeV3 = "ALTER TABLE frames ADD COLUMN state BLOB;";

// A saved index is stored in parts of at most this many bytes (SQLite's
// largest blob is 1e9 bytes; a graph of 10^6 frames is about 1.4 GB).
constexpr std::size_t kIndexPartBytes = std::size_t{64} << 20;

// Appends the little-endian record of `component` (version 1) to `records`.
// Rows of formats 1 to 3 keep the built-in components' state in columns of
// their own; restore() reads them as these records, whose version-1 layouts
// are those columns' (state.h, and each component's save_frame()).
void legacy_record(std::vector<StateRecord>& records, const char* component,
                   std::vector<std::uint8_t> bytes) {
  records.push_back({component, 1, std::move(bytes)});
}

const std::vector<std::string> kIntegerMeta = {"format_version", "width",     "height",
                                               "grid_rows",      "grid_cols", "checksum"};

}  // namespace

namespace {
// The databases open for writing in this process, by file identity.
std::mutex& writers_mutex() {
  static std::mutex m;
  return m;
}
// The process that registered each (a child made by fork() inherits the
// table but is another process).
std::map<std::pair<dev_t, ino_t>, pid_t>& writers() {
  static std::map<std::pair<dev_t, ino_t>, pid_t> open;
  return open;
}
}  // namespace

struct Database::Impl {
  std::string path;
  sqlite3* db = nullptr;
  bool writable = false;
  std::map<std::string, std::string> meta;  // text of every value
  DetectorOptions options;
  int width = 0;
  int height = 0;
  GridSize grid{0, 0};
  std::int64_t frames = 0;
  std::int64_t last_session = -1;
  std::int64_t last_frame = -1;     // the caller's id of the last row
  std::set<std::int64_t> sessions;  // sessions with frames
  // Meta session_first_ids (written by forget()): the first id of sessions
  // whose frames before them were forgotten (SessionFrames::first_id).
  std::map<std::int64_t, std::int64_t> session_first;
  int format = kDatabaseFormatVersion;
  int lock_fd = -1;                 // holds the writer's lock (flock) while open
  std::int64_t since_checkpoint = 0;
  std::string note;                 // what open() found about the last writer
  bool opened = false;              // open() completed: the destructor may checkpoint
  std::string checked_yaml;  // options YAML already found compatible
  Statement insert;
  // Scratch of append(), reused between frames.
  std::vector<std::uint8_t> hist_bytes, pixel_bytes;

  std::pair<dev_t, ino_t> writer_key{0, 0};  // registered in writers() while open for writing
  bool registered = false;

  ~Impl() {
    if (registered) {
      const std::lock_guard<std::mutex> lock(writers_mutex());
      const auto open = writers().find(writer_key);
      if (open != writers().end() && open->second == ::getpid()) writers().erase(open);
    }
    if (db && writable && opened) {
      try {
        checkpoint("closed");
      } catch (...) {
        // The frames stay committed in the write-ahead log; the next open replays it.
      }
    }
    insert = Statement();
    if (db) sqlite3_close_v2(db);
    if (lock_fd >= 0) ::close(lock_fd);  // after SQLite's own descriptors (POSIX locks)
  }

  // Records in meta that the writer is `state` ("open" or "closed") with
  // `frames` frames, then moves every committed frame from the write-ahead
  // log into the file and empties the log: afterwards the file alone holds
  // them, and damage to the log cannot lose them (docs/reliability.md).
  void checkpoint(const char* state);
  std::int64_t read_index(const std::string& mode, std::int64_t stored,
                          std::vector<std::uint8_t>& out) const;

  void check_writable() const {
    if (!writable) internal::throw_invalid("database ", path, " was opened read-only");
  }

  // Writes every meta row with a fresh checksum (inside the caller's transaction).
  void write_meta() {
    meta["checksum"] = std::to_string(meta_checksum(meta));
    sqlite3_stmt* raw = nullptr;
    if (sqlite3_prepare_v2(db, "INSERT OR REPLACE INTO meta(key, value) VALUES(?1, ?2)", -1, &raw,
                           nullptr) != SQLITE_OK) {
      sqlite3_finalize(raw);
      io_error(path, "cannot write meta (", sqlite3_errmsg(db), ")");
    }
    const std::unique_ptr<sqlite3_stmt, int (*)(sqlite3_stmt*)> stmt(raw, sqlite3_finalize);
    for (const auto& [key, value] : meta) {
      sqlite3_bind_text(stmt.get(), 1, key.c_str(), -1, SQLITE_TRANSIENT);
      if (std::find(kIntegerMeta.begin(), kIntegerMeta.end(), key) != kIntegerMeta.end()) {
        sqlite3_bind_int64(stmt.get(), 2, std::stoll(value));
      } else {
        sqlite3_bind_text(stmt.get(), 2, value.c_str(), -1, SQLITE_TRANSIENT);
      }
      if (sqlite3_step(stmt.get()) != SQLITE_DONE) {
        io_error(path, "cannot write meta key ", key, " (", sqlite3_errmsg(db), ")");
      }
      sqlite3_reset(stmt.get());
    }
  }

  void load_header();
  // `frame`: the detector's id of the frame; `caller_id`: the caller's.
  void insert_frame(const Detector& detector, std::int64_t frame, std::int64_t session,
                    const std::string& name, std::int64_t caller_id);
  // InvalidArgument unless frames may be appended to `session`.
  void check_session(std::int64_t session) const;
};

void Database::Impl::load_header() {
  // 1. SQLite's own structural check: catches truncation and damaged pages.
  {
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
  if (file_size(path + "-wal") == 0) {
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
  // 2. Our tables.
  {
    Statement tables(db, path,
                     "SELECT count(*) FROM sqlite_schema WHERE type = 'table' AND "
                     "name IN ('meta', 'frames')");
    if (!step_read(db, tables.get(), path) || sqlite3_column_int(tables.get(), 0) != 2) {
      format_error(path, "not an lsgd database (no meta and frames tables)");
    }
  }
  // 3. Meta, the format version first: a newer format may change the rest.
  std::map<std::string, int> types;
  {
    Statement rows(db, path, "SELECT key, value FROM meta");
    while (step_read(db, rows.get(), path)) {
      const std::string key = column_text(rows.get(), 0);
      types[key] = sqlite3_column_type(rows.get(), 1);
      meta[key] = column_text(rows.get(), 1);
    }
  }
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
  try {
    // A key missing from a stored file did not exist when it was written: it
    // takes the value that reproduces that version's behaviour, not today's
    // default (verification.temporal.long_frames came with default 48).
    DetectorOptions before;
    before.verification.temporal_options.long_frames = 0;
    before.verification.geometric_options.max_side = 0;  // came with format 2
    options = parse_config(meta["options"], "database " + path + " meta options", before);
    // Format 1 decision thresholds were raw similarities: this version's
    // decision (in sigma) replaces them.
    if (format < 2) options.decision = DecisionOptions{};
  } catch (const InvalidArgument& e) {
    throw FormatError(e.what());
  }
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
      (sized && grid != grid_size(width, height, options.segmentation.superpixel_size)) ||
      (!sized && (grid.rows != 0 || grid.cols != 0))) {
    format_error(path, "meta frame size ", width, "x", height, " and grid ", grid.rows, "x",
                 grid.cols, " do not match segmentation.superpixel_size ",
                 options.segmentation.superpixel_size);
  }
  // 4. Frames: columns present, ids dense.
  { Statement columns(db, path, select_frames(format, " LIMIT 0").c_str()); }
  {
    Statement count(db, path, "SELECT count(*), min(id), max(id) FROM frames");
    step_read(db, count.get(), path);
    frames = sqlite3_column_int64(count.get(), 0);
    if (frames > 0 && (sqlite3_column_int64(count.get(), 1) != 0 ||
                       sqlite3_column_int64(count.get(), 2) != frames - 1)) {
      format_error(path, "frame ids are not 0 .. ", frames - 1, " (", frames, " rows, ids ",
                   sqlite3_column_int64(count.get(), 1), " .. ",
                   sqlite3_column_int64(count.get(), 2), ")");
    }
    if (frames > 0 && !sized) format_error(path, frames, " frames but no frame size in meta");
  }
  if (const auto first = meta.find("session_first_ids"); first != meta.end()) {
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
  if (frames > 0) {
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
}

void Database::Impl::checkpoint(const char* state) {
  exec_write(db, path, "BEGIN IMMEDIATE");
  try {
    const std::map<std::string, std::string> saved = meta;
    meta["writer"] = state;
    meta["checkpoint_frames"] = std::to_string(frames);
    try {
      write_meta();
    } catch (...) {
      meta = saved;
      throw;
    }
    exec_write(db, path, "COMMIT");
  } catch (...) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
  // TRUNCATE waits (busy timeout) for readers of the log; if one still holds
  // it, the frames stay in the log until the next checkpoint.
  int log = -1, moved = -1;
  const int rc = sqlite3_wal_checkpoint_v2(db, nullptr, SQLITE_CHECKPOINT_TRUNCATE, &log, &moved);
  if (rc != SQLITE_OK && (rc & 0xFF) != SQLITE_BUSY) {
    io_error(path, "cannot checkpoint its write-ahead log (", sqlite3_errmsg(db), ")");
  }
  since_checkpoint = 0;
}

Database::Database(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Database::~Database() = default;
Database::Database(Database&& other) noexcept = default;
Database& Database::operator=(Database&& other) noexcept = default;

namespace {

// SQLite keeps a database's write-ahead log and its index beside the name it
// was opened by (FILE-wal, FILE-shm) and trusts whatever it finds there.
// Refuses a companion that is not a regular file (a folder, a FIFO, a link
// elsewhere), naming it.
void check_companions(const std::string& path) {
  for (const char* suffix : {"-wal", "-shm"}) {
    const std::string companion = path + suffix;
    struct stat st;
    if (::lstat(companion.c_str(), &st) != 0) continue;
    if (S_ISREG(st.st_mode)) continue;
    const char* kind = S_ISDIR(st.st_mode)    ? "a directory"
                       : S_ISLNK(st.st_mode)  ? "a symbolic link"
                       : S_ISFIFO(st.st_mode) ? "a FIFO"
                                              : "not a regular file";
    io_error(path, "'", companion, "' is ", kind, ", where SQLite keeps the database's ",
             suffix[1] == 'w' ? "write-ahead log" : "shared index of the log",
             ": move it away (nothing was changed)");
  }
}

}  // namespace

Database Database::open(const std::string& path, Mode mode) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) {
    io_error(path, errno == ENOENT ? "does not exist" : "cannot be opened",
             errno == ENOENT ? "" : concat(" (", std::strerror(errno), ")"));
  }
  if (!S_ISREG(st.st_mode)) io_error(path, "is not a regular file");
  const bool writable = mode == Mode::kReadWrite;
  check_companions(path);
  // Each name of a file has a log of its own: a writer through one name
  // would leave a log that a later open through the other replays over newer
  // frames (SQLite, "How To Corrupt An SQLite Database File", 2.6).
  if (writable && st.st_nlink > 1) {
    io_error(path, "has ", st.st_nlink, " hard links: SQLite keeps the log beside the name a "
             "database is opened by, so a writer through one name can have its frames undone "
             "through another; copy the file instead of linking it (reading it is fine)");
  }
  if (::access(path.c_str(), writable ? R_OK | W_OK : R_OK) != 0) {
    io_error(path, "cannot be ", writable ? "read and written" : "read", " (",
             std::strerror(errno), ")");
  }
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->writable = writable;
  // One writer at a time: a second one would interleave its frames with ours.
  // The writer holds an exclusive flock on the file while open (flock locks
  // are separate from SQLite's POSIX locks; the descriptor is closed only
  // after SQLite's, which closing it would otherwise release).
  impl->lock_fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (impl->lock_fd < 0) io_error(path, "cannot be opened (", std::strerror(errno), ")");
  bool writer_active = false;
  if (writable) {
    // A writer in this very process holds the lock already: say so, rather
    // than the "another process" of the flock below.
    struct stat id {};
    if (::fstat(impl->lock_fd, &id) == 0) {
      const std::lock_guard<std::mutex> lock(writers_mutex());
      const std::pair<dev_t, ino_t> key{id.st_dev, id.st_ino};
      const auto open = writers().find(key);
      if (open != writers().end() && open->second == ::getpid()) {
        io_error(path, "is already open for writing in this process (close that Database first: "
                       "C++ destroys it, Python's db.close() or a `with` block closes it)");
      }
      writers()[key] = ::getpid();
      impl->writer_key = key;
      impl->registered = true;
    }
    // A reader holds a shared lock for a moment (below): wait up to 2 s.
    int tries = 0;
    while (::flock(impl->lock_fd, LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      if (error != EWOULDBLOCK) {
        io_error(path, "cannot be locked for writing (", std::strerror(error), ")");
      }
      if (++tries == 200) {
        io_error(path, "another process is writing to it (one writer at a time: wait for it to "
                       "finish, or give this run another database)");
      }
      ::usleep(10'000);
    }
  } else if (::flock(impl->lock_fd, LOCK_SH | LOCK_NB) != 0) {
    writer_active = true;  // its log is in flux: SQLite reads it consistently, we cannot
  }
  // Before SQLite replays the log, which it would do silently up to any damage.
  const wal::WalCheck log = writer_active ? wal::WalCheck{} : wal::check_wal(path + "-wal");
  if (!writable && !writer_active) ::flock(impl->lock_fd, LOCK_UN);
  if (!log.damage.empty()) {
    format_error(path, log.damage,
                 ". Nothing was changed; to open the database as of its last checkpoint, losing "
                 "what the log holds, move '",
                 path, "-wal' away");
  }
  const int flags = writable ? SQLITE_OPEN_READWRITE : SQLITE_OPEN_READONLY;
  if (sqlite3_open_v2(path.c_str(), &impl->db, flags, nullptr) != SQLITE_OK) {
    io_error(path, "cannot open (", impl->db ? sqlite3_errmsg(impl->db) : "out of memory", ")");
  }
  sqlite3_extended_result_codes(impl->db, 1);
  sqlite3_busy_timeout(impl->db, 5000);
  impl->load_header();
  Impl& m = *impl;
  const auto writer = m.meta.find("writer");
  if (writer != m.meta.end() && writer->second == "open") {
    const auto at = m.meta.find("checkpoint_frames");
    const std::string checkpointed = at == m.meta.end() ? "?" : at->second;
    if (!writable) {
      m.note = writer_active
                   ? concat("a writer has it open (", m.frames, " frames readable)")
                   : concat("its last writer was stopped before closing it (", m.frames,
                            " frames readable, ", checkpointed,
                            " of them checkpointed into the file)");
    } else if (log.committed_frames > 0) {
      m.note = concat("the last writer was stopped before closing it; its write-ahead log held ",
                      log.committed_frames, " pages of committed transactions, replayed: ",
                      m.frames, " frames");
    } else {
      m.note = concat("the last writer was stopped before closing it and left no write-ahead "
                      "log: the ",
                      m.frames, " frames of its last checkpoint are here; frames it committed "
                      "after that checkpoint, if any, are lost");
    }
  }
  if (writable && m.format < kDatabaseFormatVersion) {
    // Upgrade in place, atomically: the columns and the new meta or nothing.
    exec_write(m.db, path, "BEGIN IMMEDIATE");
    try {
      if (m.format < 2) exec_write(m.db, path, kUpgradeV1);
      if (m.format < 3) exec_write(m.db, path, kUpgradeV2);
      if (m.format < 4) exec_write(m.db, path, kUpgradeV3);
      exec_write(m.db, path, kIndexesTable);
      m.meta["format_version"] = std::to_string(kDatabaseFormatVersion);
      m.meta["options"] = to_yaml(m.options);
      m.write_meta();
      exec_write(m.db, path, "COMMIT");
    } catch (...) {
      sqlite3_exec(m.db, "ROLLBACK", nullptr, nullptr, nullptr);
      m.meta["format_version"] = std::to_string(m.format);
      throw;
    }
    m.format = kDatabaseFormatVersion;
  }
  if (writable) {
    // WAL: an append writes its pages once, sequentially, to the log; FULL:
    // the log is synced at every commit, so a committed frame survives a
    // power loss too. SQLite's own checkpoints are replaced by ours, which
    // empty the log (docs/reliability.md, "Persistence").
    exec_write(m.db, path,
               "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL; PRAGMA wal_autocheckpoint=0;");
    Statement insert(m.db, path, kInsertFrame);
    m.insert = std::move(insert);
    m.checkpoint("open");
    m.opened = true;
  }
  return Database(std::move(impl));
}

Database Database::create(const std::string& path, const DetectorOptions& options) {
  options.check();
  struct stat st;
  if (::stat(path.c_str(), &st) == 0) io_error(path, "already exists");
  check_companions(path);
  // A log left by a database deleted at this path (its writer killed, the
  // file removed): SQLite would replay its frames into the new database.
  if (::stat((path + "-wal").c_str(), &st) == 0 && st.st_size > 0) {
    io_error(path, "'", path, "-wal' is the write-ahead log of a database that was deleted at "
             "this path (", st.st_size, " bytes): SQLite would replay it into the new database. "
             "Move '", path, "-wal' and '", path, "-shm' away, or give another path "
             "(nothing was created)");
  }
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  for (const char* suffix : {"", "-journal", "-wal", "-shm"}) ::unlink((tmp + suffix).c_str());
  {
    Impl impl;  // closes the temporary database on every path
    impl.path = path;
    if (sqlite3_open_v2(tmp.c_str(), &impl.db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                        nullptr) != SQLITE_OK) {
      const std::string message = impl.db ? sqlite3_errmsg(impl.db) : "out of memory";
      io_error(path, "cannot create ", tmp, " (", message, ")");
    }
    try {
      exec_write(impl.db, path, "PRAGMA synchronous=FULL; BEGIN;");
      exec_write(impl.db, path, kSchema);
      exec_write(impl.db, path, kIndexesTable);
      impl.meta = {{"format_version", std::to_string(kDatabaseFormatVersion)},
                   {"library_version", lsgd::version()},
                   {"options", to_yaml(options)},
                   {"width", "0"},
                   {"height", "0"},
                   {"grid_rows", "0"},
                   {"grid_cols", "0"}};
      impl.write_meta();
      exec_write(impl.db, path, "COMMIT; PRAGMA journal_mode=WAL;");
    } catch (...) {
      sqlite3_close_v2(impl.db);
      impl.db = nullptr;
      for (const char* suffix : {"", "-journal", "-wal", "-shm"}) ::unlink((tmp + suffix).c_str());
      throw;
    }
    if (sqlite3_close(impl.db) != SQLITE_OK) io_error(path, "cannot close ", tmp);
    impl.db = nullptr;
  }
  // link() fails when path exists (no silent overwrite); fall back to rename()
  // on file systems without hard links.
  if (::link(tmp.c_str(), path.c_str()) != 0) {
    const int error = errno;
    if (error == EEXIST || ::stat(path.c_str(), &st) == 0) {
      ::unlink(tmp.c_str());
      io_error(path, "already exists");
    }
    if (::rename(tmp.c_str(), path.c_str()) != 0) {
      const int rename_error = errno;
      ::unlink(tmp.c_str());
      io_error(path, "cannot create (", std::strerror(error), "; ", std::strerror(rename_error),
               ")");
    }
  } else {
    ::unlink(tmp.c_str());
  }
  // Make the new name durable.
  const auto slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "."
                          : slash == 0               ? "/"
                                                     : path.substr(0, slash);
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
  return open(path, Mode::kReadWrite);
}

const std::string& Database::path() const { return impl_->path; }
const DetectorOptions& Database::options() const { return impl_->options; }
std::int64_t Database::frames() const { return impl_->frames; }
std::int64_t Database::last_session() const { return impl_->last_session; }
std::int64_t Database::last_frame() const { return impl_->last_frame; }
const std::string& Database::note() const { return impl_->note; }

std::vector<std::int64_t> Database::frame_ids() const {
  const Impl& m = *impl_;
  std::vector<std::int64_t> ids;
  ids.reserve(static_cast<std::size_t>(m.frames));
  Statement stmt(m.db, m.path,
                 concat("SELECT ", frame_column(m.format), " FROM frames ORDER BY id").c_str());
  while (step_read(m.db, stmt.get(), m.path) &&
         static_cast<std::int64_t>(ids.size()) < m.frames) {
    ids.push_back(sqlite3_column_int64(stmt.get(), 0));
  }
  return ids;
}

SessionFrames Database::session_frames(std::int64_t session) const {
  const Impl& m = *impl_;
  SessionFrames out;
  out.session = session;
  const std::string column = frame_column(m.format);
  {
    // The first id of the session: one past the frame stored just before it.
    Statement before(m.db, m.path,
                     concat("SELECT ", column, " FROM frames WHERE id < (SELECT min(id) FROM "
                            "frames WHERE session = ?1) ORDER BY id DESC LIMIT 1")
                         .c_str());
    sqlite3_bind_int64(before.get(), 1, session);
    if (step_read(m.db, before.get(), m.path)) {
      out.first_id = sqlite3_column_int64(before.get(), 0) + 1;
    }
    // Frames before it were forgotten: the first id it had.
    if (const auto kept = m.session_first.find(session); kept != m.session_first.end()) {
      out.first_id = kept->second;
    }
  }
  Statement rows(m.db, m.path,
                 concat("SELECT ", column, ", name FROM frames WHERE session = ?1 AND id < ?2 "
                        "ORDER BY id")
                     .c_str());
  sqlite3_bind_int64(rows.get(), 1, session);
  sqlite3_bind_int64(rows.get(), 2, m.frames);
  while (step_read(m.db, rows.get(), m.path)) {
    out.frames.push_back({sqlite3_column_int64(rows.get(), 0), column_text(rows.get(), 1)});
  }
  return out;
}

void Database::verify() const {
  Detector scratch(impl_->options);
  restore(scratch);
}

DatabaseInfo Database::info() const {
  const Impl& m = *impl_;
  exec_write(m.db, m.path, "BEGIN");  // one snapshot, even beside a writer
  struct EndRead {
    sqlite3* db;
    ~EndRead() { sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr); }
  } end_read{m.db};
  DatabaseInfo info;
  info.path = m.path;
  info.format_version = std::stoi(m.meta.at("format_version"));
  info.library_version = m.meta.at("library_version");
  info.options_yaml = m.meta.at("options");
  info.width = m.width;
  info.height = m.height;
  info.grid = m.grid;
  info.note = m.note;
  {
    Statement stmt(m.db, m.path, "SELECT count(*) FROM frames");
    step_read(m.db, stmt.get(), m.path);
    info.frames = sqlite3_column_int64(stmt.get(), 0);
  }
  {
    // Sessions in the order their frames were stored, with their id ranges.
    const std::string column = frame_column(m.format);
    Statement stmt(m.db, m.path,
                   concat("SELECT session, count(*), min(", column, "), max(", column,
                          ") FROM frames GROUP BY session ORDER BY min(id)")
                       .c_str());
    while (step_read(m.db, stmt.get(), m.path)) {
      info.sessions.push_back({sqlite3_column_int64(stmt.get(), 0),
                               sqlite3_column_int64(stmt.get(), 1),
                               sqlite3_column_int64(stmt.get(), 2),
                               sqlite3_column_int64(stmt.get(), 3)});
    }
  }
  {
    Statement stmt(m.db, m.path, "SELECT max(node) FROM frames");
    if (step_read(m.db, stmt.get(), m.path) &&
        sqlite3_column_type(stmt.get(), 0) == SQLITE_INTEGER) {
      info.nodes = sqlite3_column_int64(stmt.get(), 0) + 1;
    }
  }
  if (m.format >= 5) {
    Statement stmt(m.db, m.path,
                   "SELECT max(frames), sum(length(data)) FROM indexes WHERE mode = ?1");
    const std::string& mode = m.options.search.mode;
    sqlite3_bind_text(stmt.get(), 1, mode.c_str(), static_cast<int>(mode.size()), SQLITE_TRANSIENT);
    if (step_read(m.db, stmt.get(), m.path) && sqlite3_column_type(stmt.get(), 0) == SQLITE_INTEGER) {
      info.index_frames = sqlite3_column_int64(stmt.get(), 0);
      info.index_bytes = sqlite3_column_int64(stmt.get(), 1);
    }
  }
  info.bytes = file_size(m.path) + file_size(m.path + "-wal");
  return info;
}

void Database::check_compatible(const DetectorOptions& options) const {
  const DetectorOptions& stored = impl_->options;
  // Every option but the resumable ones (decision.*), where it matters for
  // the stored options (search.nodes.* only in nodes mode, ...).
  for (const OptionField<DetectorOptions>& f : DetectorOptions::fields()) {
    if (f.resumable || (f.applies && !f.applies(stored))) continue;
    const std::string value = f.text(stored);
    const std::string given = f.text(options);
    const std::string& key = f.name;
    if (given != value) {
      internal::throw_invalid("database ", impl_->path, ": option ", key, " = ", given,
                              " differs from the stored ", value,
                              " (only decision.* may change when resuming)");
    }
  }
}

void Database::restore(Detector& detector, IndexUse index) const {
  Impl& m = *impl_;
  if (detector.size() != 0) {
    internal::throw_invalid("database ", m.path, ": restore needs a new detector, this one holds ",
                            detector.size(), " frames");
  }
  check_compatible(detector.options());
  if (m.frames == 0) return;
  const DetectorOptions& o = detector.options();
  const bool nodes_mode = detector.search().has_groups();  // dynamic nodes
  const auto cells = static_cast<std::size_t>(m.grid.cells());

  // Compact storage keeps cells * kCompactBins bytes per frame and no pixel
  // counts (an empty pixels blob); exact storage 16-bit bins and counts.
  const bool compact = o.descriptor.storage == HistogramStorage::kCompact;
  const std::size_t hist_bytes =
      compact ? cells * kCompactBins * sizeof(CompactBin) : cells * kBins * sizeof(Bin);
  const std::size_t pixel_bytes = compact ? 0 : cells * sizeof(Count);
  Descriptor descriptor;
  descriptor.grid = m.grid;
  descriptor.storage = o.descriptor.storage;
  if (compact) {
    descriptor.cell_pixels = static_cast<double>(m.width) * m.height / static_cast<double>(cells);
  }
  // The descriptor's memory is committed when the first row shows a blob of
  // its size, so the meta's frame size alone never makes an allocation.
  const auto allocate = [&] {
    if (compact) {
      descriptor.compact.resize(cells * kCompactBins);
    } else {
      descriptor.hist.resize(cells * kBins);
      descriptor.pixels.resize(cells);
    }
  };
  std::vector<std::uint8_t> state;
  std::int64_t nodes = 0;  // dynamic nodes so far (the node column)

  // One read transaction: the rows and their count are one snapshot, even
  // while another process appends (a reader beside the writer).
  exec_write(m.db, m.path, "BEGIN");
  struct EndRead {
    sqlite3* db;
    ~EndRead() { sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr); }
  } end_read{m.db};
  Statement stmt(m.db, m.path, select_frames(m.format).c_str());
  std::int64_t id = 0;
  std::int64_t last_frame = -1;
  for (; step_read(m.db, stmt.get(), m.path); ++id) {
    sqlite3_stmt* s = stmt.get();
    const auto bad = [&](const auto&... parts) {
      format_error(m.path, "frame ", id, ": ", parts...);
    };
    const auto type = [&](int column) { return sqlite3_column_type(s, column); };
    if (type(0) != SQLITE_INTEGER || sqlite3_column_int64(s, 0) != id) bad("id is not ", id);
    if (type(1) != SQLITE_INTEGER || sqlite3_column_int64(s, 1) < 0)
      bad("session is not an integer >= 0");
    if (type(2) != SQLITE_TEXT) bad("name is not text");
    if (type(3) != SQLITE_BLOB || type(4) != SQLITE_BLOB) bad("histogram or pixels is not a blob");
    if (type(8) != SQLITE_INTEGER) bad("crc32 is not an integer");
    RowBytes row;
    row.id = id;
    row.session = sqlite3_column_int64(s, 1);
    row.hist = sqlite3_column_blob(s, 3);
    row.hist_size = sqlite3_column_bytes(s, 3);
    row.pixels = sqlite3_column_blob(s, 4);
    row.pixels_size = sqlite3_column_bytes(s, 4);
    if (row.hist_size != static_cast<std::int64_t>(hist_bytes)) {
      bad("histogram blob has ", row.hist_size, " bytes, expected ", hist_bytes, " (", m.grid.rows,
          "x", m.grid.cols, " cells of ",
          compact ? "128 8-bit bins, descriptor.storage compact"
                  : "256 16-bit bins, descriptor.storage exact",
          ")");
    }
    if (row.pixels_size != static_cast<std::int64_t>(pixel_bytes)) {
      bad("pixels blob has ", row.pixels_size, " bytes, expected ", pixel_bytes);
    }
    if (id == 0) allocate();
    // The node column: the dynamic node of the frame, kept beside its state
    // for db info and inspection.
    if (nodes_mode) {
      if (type(5) != SQLITE_INTEGER) bad("node is not an integer (search mode nodes)");
      row.node = sqlite3_column_int64(s, 5);
      if (row.node < 0 || row.node > nodes) {
        bad("node ", row.node, " does not exist yet (", nodes, " nodes before this frame)");
      }
      if (row.node == nodes) ++nodes;
    } else if (type(5) != SQLITE_NULL) {
      bad("has a node but the search mode is ", o.search.mode);
    }
    if (type(6) == SQLITE_INTEGER) {
      row.place = sqlite3_column_int64(s, 6);
    } else if (type(6) != SQLITE_NULL) {
      bad("place is not an integer");
    }
    if (type(7) == SQLITE_BLOB) {
      row.features = sqlite3_column_blob(s, 7);
      row.features_size = sqlite3_column_bytes(s, 7);
    } else if (type(7) != SQLITE_NULL) {
      bad("features is not a blob");
    }
    if (type(10) == SQLITE_FLOAT || type(10) == SQLITE_INTEGER) {
      if (type(9) != SQLITE_INTEGER) bad("loop is not an integer");
      row.loop = sqlite3_column_int64(s, 9);
      row.has_loop_inliers = true;
      row.loop_inliers = sqlite3_column_double(s, 10);
    } else if (type(10) != SQLITE_NULL || type(9) != SQLITE_NULL) {
      bad("loop_inliers is not a number");
    }
    if (type(11) == SQLITE_INTEGER) {
      row.frame = sqlite3_column_int64(s, 11);
      if (row.frame <= last_frame || row.frame > kMaxFrameId) {
        bad("frame id ", row.frame, " is not above the previous frame's ", last_frame,
            " and at most ", kMaxFrameId);
      }
    } else if (type(11) != SQLITE_NULL) {
      bad("frame is not an integer");
    } else if (id <= last_frame) {
      bad("has no frame id, and its row id ", id, " is not above the previous frame's ",
          last_frame);
    }
    if (type(12) == SQLITE_BLOB) {
      if (row.place != kNull || row.features_size >= 0 || row.has_loop_inliers) {
        bad("has both a state and the place, features or loop columns of older formats");
      }
      row.state = sqlite3_column_blob(s, 12);
      row.state_size = sqlite3_column_bytes(s, 12);
    } else if (type(12) != SQLITE_NULL) {
      bad("state is not a blob");
    }
    last_frame = row.frame == kNull ? id : row.frame;
    const std::string name = column_text(s, 2);  // after the blobs: text conversion is not needed
    row.name = name.data();
    row.name_size = static_cast<std::int64_t>(name.size());
    const std::uint32_t crc = row_checksum(row);
    if (static_cast<std::int64_t>(crc) != sqlite3_column_int64(s, 8)) {
      bad("checksum ", sqlite3_column_int64(s, 8), " does not match the row (", crc,
          "): the file was modified or damaged");
    }

    if (compact) {
      std::memcpy(descriptor.compact.data(), row.hist, hist_bytes);
    } else {
      decode_le(static_cast<const std::uint8_t*>(row.hist), cells * kBins, descriptor.hist.data());
      decode_le(static_cast<const std::uint8_t*>(row.pixels), cells, descriptor.pixels.data());
    }
    if (row.state_size >= 0) {
      const auto* bytes = static_cast<const std::uint8_t*>(row.state);
      state.assign(bytes, bytes + row.state_size);
    } else {
      // A row of format 1 to 3: its columns as the components' records.
      std::vector<StateRecord> records;
      const auto i64 = [](std::int64_t v) {
        StateWriter w;
        w.put_i64(v);
        return w.bytes();
      };
      if (nodes_mode) legacy_record(records, detector.search().name(), i64(row.node));
      if (row.place != kNull) legacy_record(records, kTemporalStage, i64(row.place));
      if (row.features_size >= 0) {
        const auto* bytes = static_cast<const std::uint8_t*>(row.features);
        legacy_record(records, kGeometricStage, {bytes, bytes + row.features_size});
      }
      if (row.has_loop_inliers) {
        StateWriter w;
        w.put_i64(row.loop);
        w.put_f64(row.loop_inliers);
        legacy_record(records, "decision", w.bytes());
      }
      state = encode_records(records);
    }
    try {
      detector.restore_frame(m.width, m.height, descriptor, state, last_frame);
    } catch (const InvalidArgument& e) {
      bad(e.what());
    }
    if (nodes_mode && detector.search().group_of(id) != row.node) {
      bad("node column ", row.node, " differs from the node in its state, ",
          detector.search().group_of(id));
    }
  }
  if (id != m.frames) {
    if (m.writable) {  // we hold the writer's lock: nothing else appends
      format_error(m.path, "read ", id, " frames but the database held ", m.frames, " at open");
    }
    m.frames = id;  // a writer appended since open: this snapshot holds more
    m.last_frame = last_frame;
  }
  if (index == IndexUse::kSaved) {
    std::vector<std::uint8_t> bytes;
    if (m.read_index(detector.search().name(), id, bytes) > 0) {
      try {
        detector.restore_index(bytes.data(), bytes.size());
      } catch (const InvalidArgument& e) {
        format_error(m.path, "the saved index of search mode ", detector.search().name(), ": ",
                     e.what(), " (restore with IndexUse::kRebuild, lsgd run --rebuild-index, to "
                     "ignore it)");
      }
    }
  }
}

// The saved index of `mode` as one blob (its parts in order, each checked
// against its checksum); returns the frames it covers, 0 when there is none.
std::int64_t Database::Impl::read_index(const std::string& mode, std::int64_t stored,
                                        std::vector<std::uint8_t>& out) const {
  out.clear();
  if (format < 5) return 0;
  {
    // One allocation for the whole blob (a graph of 10^6 frames is ~1.4 GB).
    Statement size(db, path, "SELECT sum(length(data)) FROM indexes WHERE mode = ?1");
    sqlite3_bind_text(size.get(), 1, mode.c_str(), static_cast<int>(mode.size()), SQLITE_TRANSIENT);
    if (step_read(db, size.get(), path) && sqlite3_column_type(size.get(), 0) == SQLITE_INTEGER) {
      out.reserve(static_cast<std::size_t>(std::max<sqlite3_int64>(0, sqlite3_column_int64(size.get(), 0))));
    }
  }
  Statement stmt(db, path, "SELECT part, frames, data, crc32 FROM indexes WHERE mode = ?1 ORDER BY part");
  sqlite3_bind_text(stmt.get(), 1, mode.c_str(), static_cast<int>(mode.size()), SQLITE_TRANSIENT);
  std::int64_t covered = -1, part = 0;
  while (step_read(db, stmt.get(), path)) {
    sqlite3_stmt* s = stmt.get();
    const auto bad = [&](const auto&... parts) {
      format_error(path, "the saved index of search mode ", mode, ", part ", part, ": ", parts...,
                   " (restore with IndexUse::kRebuild, lsgd run --rebuild-index, to ignore it)");
    };
    if (sqlite3_column_type(s, 0) != SQLITE_INTEGER || sqlite3_column_int64(s, 0) != part) {
      bad("parts are not numbered 0, 1, 2, ...");
    }
    if (sqlite3_column_type(s, 1) != SQLITE_INTEGER) bad("frames is not an integer");
    const std::int64_t f = sqlite3_column_int64(s, 1);
    if (f < 1 || f > stored || (covered >= 0 && f != covered)) {
      bad("covers ", f, " frames (", stored, " stored", covered >= 0 ? concat(", part 0 says ", covered) : "",
          ")");
    }
    covered = f;
    if (sqlite3_column_type(s, 2) != SQLITE_BLOB || sqlite3_column_type(s, 3) != SQLITE_INTEGER) {
      bad("data is not a blob or crc32 not an integer");
    }
    const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(s, 2));
    const auto size = static_cast<std::size_t>(sqlite3_column_bytes(s, 2));
    const std::uint32_t crc = crc_of(data, size);
    if (static_cast<std::int64_t>(crc) != sqlite3_column_int64(s, 3)) {
      bad("checksum ", sqlite3_column_int64(s, 3), " does not match its data (", crc,
          "): the file was modified or damaged");
    }
    out.insert(out.end(), data, data + size);
    ++part;
  }
  return covered < 0 ? 0 : covered;
}


void Database::Impl::insert_frame(const Detector& detector, std::int64_t frame,
                                  std::int64_t session, const std::string& name,
                                  std::int64_t caller_id) {
  const DescriptorView view = detector.store().view(frame);
  const auto cells = static_cast<std::size_t>(view.cells);
  hist_bytes.clear();
  pixel_bytes.clear();
  if (view.storage() == HistogramStorage::kCompact) {
    hist_bytes.assign(view.compact, view.compact + cells * kCompactBins);
  } else {
    encode_le(view.hist, cells * kBins, hist_bytes);
    encode_le(view.pixels, cells, pixel_bytes);
  }
  const std::vector<std::uint8_t> state = detector.frame_state(frame);
  RowBytes row;
  row.id = frame;
  row.session = session;
  if (detector.search().has_groups()) row.node = detector.search().group_of(frame);
  row.frame = caller_id;
  row.name = name.data();
  row.name_size = static_cast<std::int64_t>(name.size());
  row.hist = hist_bytes.data();
  row.hist_size = static_cast<std::int64_t>(hist_bytes.size());
  row.pixels = pixel_bytes.data();
  row.pixels_size = static_cast<std::int64_t>(pixel_bytes.size());
  row.state = state.data();
  row.state_size = static_cast<std::int64_t>(state.size());
  sqlite3_stmt* s = insert.get();
  sqlite3_reset(s);
  sqlite3_clear_bindings(s);
  sqlite3_bind_int64(s, 1, frame);
  sqlite3_bind_int64(s, 2, session);
  sqlite3_bind_text(s, 3, name.c_str(), static_cast<int>(name.size()), SQLITE_STATIC);
  sqlite3_bind_blob(s, 4, hist_bytes.data(), static_cast<int>(hist_bytes.size()), SQLITE_STATIC);
  if (pixel_bytes.empty()) {  // compact storage: an empty blob, not NULL
    sqlite3_bind_zeroblob(s, 5, 0);
  } else {
    sqlite3_bind_blob(s, 5, pixel_bytes.data(), static_cast<int>(pixel_bytes.size()),
                      SQLITE_STATIC);
  }
  if (row.node != kNull) sqlite3_bind_int64(s, 6, row.node);
  sqlite3_bind_int64(s, 7, row_checksum(row));
  sqlite3_bind_int64(s, 8, caller_id);
  sqlite3_bind_blob(s, 9, state.data(), static_cast<int>(state.size()), SQLITE_STATIC);
  const int rc = sqlite3_step(s);
  sqlite3_reset(s);
  if (rc != SQLITE_DONE)
    io_error(path, "cannot write frame ", frame, " (", sqlite3_errmsg(db), ")");
}

namespace {

// Runs `write` in one IMMEDIATE transaction; rolls back if it throws.
template <typename F>
void transaction(sqlite3* db, const std::string& path, F&& write) {
  exec_write(db, path, "BEGIN IMMEDIATE");
  try {
    write();
    exec_write(db, path, "COMMIT");
  } catch (...) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

}  // namespace

void Database::Impl::check_session(std::int64_t session) const {
  if (session < 0 || session > kMaxSession) {
    internal::throw_invalid("database ", path, ": session ", session, " is outside [0, ",
                            kMaxSession, "]");
  }
  if (session != last_session && sessions.count(session) != 0) {
    internal::throw_invalid("database ", path, ": session ", session,
                            " has frames before session ", last_session,
                            "'s: a session's frames stay together, so only the last session "
                            "can be continued; choose a new session id");
  }
}

void Database::append(const Detector& detector, const Result& /*result*/, std::int64_t session,
                      const std::string& name, std::int64_t frame) {
  Impl& m = *impl_;
  m.check_writable();
  m.check_session(session);
  if (detector.size() != m.frames + 1) {
    internal::throw_invalid("database ", m.path, ": append from a detector holding ",
                            detector.size(), " frames, but the database holds ", m.frames,
                            " (append each frame right after process())");
  }
  // The frame's id is the detector's (Detector::process(frame, id)): a
  // different one would be refused when the frame is restored.
  const std::int64_t own = detector.id_of(detector.size() - 1);
  if (frame < -1) {
    internal::throw_invalid("database ", m.path, ": frame id ", frame, " is negative (-1: the "
                            "detector's id of its last frame)");
  }
  if (frame >= 0 && frame != own) {
    internal::throw_invalid("database ", m.path, ": frame id ", frame, " is not the detector's id ", own,
                            " of its last frame (give the id to Detector::process)");
  }
  frame = own;
  if (frame <= m.last_frame || frame > kMaxFrameId) {
    internal::throw_invalid("database ", m.path, ": frame id ", frame, " must be above the last ",
                            "stored id ", m.last_frame, " and at most ", kMaxFrameId);
  }
  const std::string yaml = to_yaml(detector.options());
  if (yaml != m.checked_yaml) {
    check_compatible(detector.options());
    m.checked_yaml = yaml;
  }
  const std::int64_t dense = m.frames;  // the detector's id of its last frame
  transaction(m.db, m.path, [&] {
    std::map<std::string, std::string> saved = m.meta;
    if (m.frames == 0) {
      m.meta["width"] = std::to_string(detector.width());
      m.meta["height"] = std::to_string(detector.height());
      m.meta["grid_rows"] = std::to_string(detector.store().grid().rows);
      m.meta["grid_cols"] = std::to_string(detector.store().grid().cols);
      try {
        m.write_meta();
      } catch (...) {
        m.meta = saved;
        throw;
      }
    }
    try {
      m.insert_frame(detector, dense, session, name, frame);
    } catch (...) {
      m.meta = saved;
      throw;
    }
  });
  if (m.frames == 0) {
    m.width = detector.width();
    m.height = detector.height();
    m.grid = detector.store().grid();
  }
  ++m.frames;
  m.last_session = session;
  m.last_frame = frame;
  m.sessions.insert(session);
  if (++m.since_checkpoint >= kCheckpointFrames) m.checkpoint("open");
}

void Database::append_all(const Detector& detector, std::int64_t session) {
  Impl& m = *impl_;
  m.check_writable();
  m.check_session(session);
  if (detector.size() < m.frames) {
    internal::throw_invalid("database ", m.path, ": the detector holds ", detector.size(),
                            " frames, fewer than the ", m.frames, " stored");
  }
  if (detector.size() == m.frames) return;
  check_compatible(detector.options());
  const std::int64_t first = m.frames;
  if (detector.id_of(first) <= m.last_frame) {
    internal::throw_invalid("database ", m.path, ": the detector's frame ", first, " has id ",
                            detector.id_of(first), ", not above the last stored id ", m.last_frame);
  }
  transaction(m.db, m.path, [&] {
    const std::map<std::string, std::string> saved = m.meta;
    try {
      if (first == 0) {
        m.meta["width"] = std::to_string(detector.width());
        m.meta["height"] = std::to_string(detector.height());
        m.meta["grid_rows"] = std::to_string(detector.store().grid().rows);
        m.meta["grid_cols"] = std::to_string(detector.store().grid().cols);
        m.write_meta();
      }
      for (std::int64_t f = first; f < detector.size(); ++f) {
        m.insert_frame(detector, f, session, "", detector.id_of(f));
      }
    } catch (...) {
      m.meta = saved;
      throw;
    }
  });
  if (first == 0) {
    m.width = detector.width();
    m.height = detector.height();
    m.grid = detector.store().grid();
  }
  m.last_frame = detector.id_of(detector.size() - 1);
  m.frames = detector.size();
  m.last_session = session;
  m.sessions.insert(session);
  m.checkpoint("open");
}

std::int64_t Database::forget(std::int64_t first_id, std::int64_t last_id) {
  Impl& m = *impl_;
  m.check_writable();
  if (first_id > last_id) {
    internal::throw_invalid("database ", m.path, ": forget: the first id ", first_id,
                            " is above the last ", last_id);
  }
  struct Row {
    std::int64_t session;
    std::string name;
    std::int64_t id;
  };
  std::vector<Row> rows;
  {
    Statement stmt(m.db, m.path,
                   concat("SELECT session, name, ", frame_column(m.format), " FROM frames ORDER BY id")
                       .c_str());
    while (step_read(m.db, stmt.get(), m.path)) {
      rows.push_back({sqlite3_column_int64(stmt.get(), 0), column_text(stmt.get(), 1),
                      sqlite3_column_int64(stmt.get(), 2)});
    }
  }
  const auto from = std::find_if(rows.begin(), rows.end(), [&](const Row& r) { return r.id >= first_id; });
  const auto to = std::find_if(from, rows.end(), [&](const Row& r) { return r.id > last_id; });
  const std::int64_t forgotten = to - from;
  if (forgotten == 0) return 0;
  const auto dense = static_cast<std::int64_t>(from - rows.begin());  // the first forgotten frame
  // The first id of every session as lsgd run numbered it, before any of
  // its earlier frames are gone.
  std::map<std::int64_t, std::int64_t> first_ids;
  for (const std::int64_t s : m.sessions) first_ids[s] = session_frames(s).first_id;
  // The kept frames' state: what the detector keeps when it forgets them.
  Detector detector(m.options);
  restore(detector, IndexUse::kRebuild);
  if (detector.forget(first_id, last_id) != forgotten) {
    format_error(m.path, "the rows' ids do not match their frames' state");
  }
  rows.erase(from, to);
  std::set<std::int64_t> sessions;
  for (const Row& r : rows) sessions.insert(r.session);
  // Those the frames before them no longer give.
  std::map<std::int64_t, std::int64_t> session_first;
  std::string kept_first;
  for (const auto& [session, id] : first_ids) {
    if (sessions.count(session) == 0) continue;
    const std::int64_t s = session;  // (C++17 lambdas cannot capture a structured binding)
    const auto at = std::find_if(rows.begin(), rows.end(), [s](const Row& r) { return r.session == s; });
    const std::int64_t before = at == rows.begin() ? 0 : std::prev(at)->id + 1;
    if (before == id) continue;
    session_first[session] = id;
    kept_first += concat(kept_first.empty() ? "" : " ", session, "=", id);
  }
  transaction(m.db, m.path, [&] {
    const std::map<std::string, std::string> saved = m.meta;
    try {
      Statement drop(m.db, m.path, "DELETE FROM frames WHERE id >= ?1");
      sqlite3_bind_int64(drop.get(), 1, dense);
      if (sqlite3_step(drop.get()) != SQLITE_DONE) io_error(m.path, "cannot write (", sqlite3_errmsg(m.db), ")");
      // The saved graph numbers the forgotten frames: the next resume builds it again.
      exec_write(m.db, m.path, "DELETE FROM indexes");
      for (std::int64_t f = dense; f < detector.size(); ++f) {
        const Row& r = rows[static_cast<std::size_t>(f)];
        m.insert_frame(detector, f, r.session, r.name, r.id);
      }
      if (kept_first.empty()) {
        m.meta.erase("session_first_ids");
        exec_write(m.db, m.path, "DELETE FROM meta WHERE key = 'session_first_ids'");
      } else {
        m.meta["session_first_ids"] = kept_first;
      }
      if (rows.empty()) {  // the next frame sets the size again
        for (const char* key : {"width", "height", "grid_rows", "grid_cols"}) m.meta[key] = "0";
      }
      m.write_meta();
    } catch (...) {
      m.meta = saved;
      throw;
    }
  });
  m.frames = detector.size();
  m.sessions = sessions;
  m.last_session = rows.empty() ? -1 : rows.back().session;
  m.last_frame = rows.empty() ? -1 : rows.back().id;
  m.session_first = std::move(session_first);
  if (rows.empty()) m.width = m.height = 0, m.grid = GridSize{0, 0};
  m.checkpoint("open");
  // The freed pages go back to the file system.
  exec_write(m.db, m.path, "VACUUM");
  m.checkpoint("open");
  return forgotten;
}

std::int64_t Database::forget_session(std::int64_t session) {
  Impl& m = *impl_;
  m.check_writable();
  if (m.sessions.count(session) == 0) {
    std::string known;
    for (const std::int64_t s : m.sessions) known += concat(known.empty() ? "" : ", ", s);
    internal::throw_invalid("database ", m.path, ": session ", session, " has no frames (sessions: ",
                            known.empty() ? "none" : known, ")");
  }
  const SessionFrames frames = session_frames(session);
  // A session's frames are consecutive: the range of its ids holds no other.
  return forget(frames.frames.front().frame, frames.frames.back().frame);
}

std::int64_t Database::save_index(const Detector& detector) {
  Impl& m = *impl_;
  m.check_writable();
  if (detector.size() != m.frames) {
    internal::throw_invalid("database ", m.path, ": save_index needs the detector of the stored ",
                            m.frames, " frames; this one holds ", detector.size());
  }
  check_compatible(detector.options());
  std::vector<std::uint8_t> bytes;
  const std::int64_t covered = detector.save_index(bytes);
  const std::string mode = detector.search().name();
  transaction(m.db, m.path, [&] {
    Statement drop(m.db, m.path, "DELETE FROM indexes WHERE mode = ?1");
    sqlite3_bind_text(drop.get(), 1, mode.c_str(), static_cast<int>(mode.size()), SQLITE_TRANSIENT);
    if (sqlite3_step(drop.get()) != SQLITE_DONE) io_error(m.path, "cannot write (", sqlite3_errmsg(m.db), ")");
    Statement insert(m.db, m.path,
                     "INSERT INTO indexes(mode, part, frames, data, crc32) VALUES(?1, ?2, ?3, ?4, ?5)");
    std::int64_t part = 0;
    for (std::size_t at = 0; at < bytes.size(); at += kIndexPartBytes, ++part) {
      const std::size_t n = std::min(kIndexPartBytes, bytes.size() - at);
      sqlite3_stmt* s = insert.get();
      sqlite3_reset(s);
      sqlite3_bind_text(s, 1, mode.c_str(), static_cast<int>(mode.size()), SQLITE_TRANSIENT);
      sqlite3_bind_int64(s, 2, part);
      sqlite3_bind_int64(s, 3, covered);
      sqlite3_bind_blob(s, 4, bytes.data() + at, static_cast<int>(n), SQLITE_STATIC);
      sqlite3_bind_int64(s, 5, crc_of(bytes.data() + at, n));
      if (sqlite3_step(s) != SQLITE_DONE) io_error(m.path, "cannot write (", sqlite3_errmsg(m.db), ")");
    }
  });
  m.checkpoint("open");
  return covered;
}

}  // namespace lsgd::io
