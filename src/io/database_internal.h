// Internals of the place database shared by its source files (database.cc:
// opening and creating; database_header.cc: reading the header;
// database_restore.cc: restoring a detector; database_write.cc: appending,
// forgetting, saving an index): the file format's blobs and checksums, SQLite
// helpers and Database::Impl.
// Not installed; included by src/io/database*.cc only.
#pragma once

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
#include <filesystem>
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
#include "lsgd/io/database.h"

namespace lsgd::io {
namespace db {


using internal::concat;

inline constexpr std::int64_t kNull = std::numeric_limits<std::int64_t>::min();  // NULL in checksums
// Appends between checkpoints (Impl::checkpoint): the most frames that live
// only in the write-ahead log.
inline constexpr std::int64_t kCheckpointFrames = 32;

template <typename... Parts>
[[noreturn]] void format_error(const std::string& path, const Parts&... parts) {
  throw FormatError(concat("database ", path, ": ", parts...));
}

template <typename... Parts>
[[noreturn]] void io_error(const std::string& path, const Parts&... parts) {
  throw IoError(concat("database ", path, ": ", parts...));
}

// SQLite's message for the last error on `db`, with the system's reason when
// a system call failed ("unable to open database file" says nothing of a
// process out of file descriptors, a full disk or a permission).
inline std::string sqlite_message(sqlite3* db) {
  if (!db) return "out of memory";
  std::string message = sqlite3_errmsg(db);
  // Only for a failure of the file itself: the errno of the last system call
  // SQLite made may be stale (a probe for a log that is not there) otherwise.
  const int primary = sqlite3_extended_errcode(db) & 0xFF;
  const bool file_failed = primary == SQLITE_CANTOPEN || primary == SQLITE_IOERR ||
                           primary == SQLITE_FULL || primary == SQLITE_PERM ||
                           primary == SQLITE_READONLY;
  const int err = file_failed ? sqlite3_system_errno(db) : 0;
  if (err != 0) {
    message += concat(": ", std::strerror(err));
    if (err == EMFILE || err == ENFILE) {
      message += err == EMFILE ? " (this process's limit on open files, ulimit -n, is reached)"
                               : " (the system's limit on open files is reached)";
    }
  }
  return message;
}

// SQLite opens a database by its absolute path and refuses one whose
// journal name ("-journal", 8 more bytes) would pass its 512-byte limit
// (SQLITE_MAX_PATHNAME), with a bare "unable to open database file" and a
// stale errno. `name` is the file SQLite is given for `path`.
inline constexpr std::size_t kSqliteMaxPathBytes = 512 - 8;
inline void check_path_length(const std::string& path, const std::string& name) {
  // An empty name is SQLite's private temporary database, never a file.
  if (path.empty()) throw InvalidArgument("the database path is empty: give a file name");
  std::error_code ec;
  const std::string full = std::filesystem::absolute(name, ec).string();
  const std::size_t length = ec ? name.size() : full.size();
  if (length > kSqliteMaxPathBytes) {
    io_error(path, "its absolute path is ", length, " bytes long, and SQLite opens paths of at "
             "most ", kSqliteMaxPathBytes, " bytes: give a shorter path (a symbolic link to the "
             "folder will do)");
  }
}

// ---- little-endian blobs (memcpy on little-endian hosts)

inline constexpr bool kLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

template <typename T>
inline void encode_le(const T* values, std::size_t n, std::vector<std::uint8_t>& out) {
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
inline void decode_le(const std::uint8_t* src, std::size_t n, T* values) {
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

inline std::uint32_t crc_bytes(std::uint32_t crc, const void* data, std::size_t n) {
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
inline std::uint32_t crc_of(const void* data, std::size_t n) {
  return crc_bytes(static_cast<std::uint32_t>(crc32(0, Z_NULL, 0)), data, n);
}

inline std::uint32_t crc_int(std::uint32_t crc, std::int64_t v) {
  std::uint8_t b[8];
  for (int i = 0; i < 8; ++i)
    b[i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * i));
  return crc_bytes(crc, b, 8);
}

// A blob: its length as an int64 (-1 for NULL), then its bytes.
inline std::uint32_t crc_blob(std::uint32_t crc, const void* data, std::int64_t n) {
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
inline std::uint32_t row_checksum(const RowBytes& r) {
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
inline std::uint32_t meta_checksum(const std::map<std::string, std::string>& meta) {
  std::string text;
  for (const auto& [key, value] : meta) {
    if (key != "checksum") text += key + "=" + value + "\n";
  }
  return crc_of(text.data(), text.size());
}

// ---- SQLite helpers

// A result code that says the file could not be reached (locked, not
// openable, no permission, no memory), not that it is damaged.
inline bool is_io_condition(int rc) {
  const int primary = rc & 0xFF;
  return primary == SQLITE_BUSY || primary == SQLITE_LOCKED || primary == SQLITE_CANTOPEN ||
         primary == SQLITE_PERM || primary == SQLITE_NOMEM;
}

class Statement {
 public:
  Statement() = default;
  Statement(sqlite3* db, const std::string& path, const char* sql) {
    if (const int rc = sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr); rc != SQLITE_OK) {
      const std::string message = sqlite_message(db);
      sqlite3_finalize(stmt_);
      stmt_ = nullptr;
      if (is_io_condition(rc)) io_error(path, "cannot read (", message, ") in: ", sql);
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
inline void exec_write(sqlite3* db, const std::string& path, const char* sql) {
  char* error = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &error) != SQLITE_OK) {
    const std::string message = error ? error : sqlite_message(db);
    sqlite3_free(error);
    io_error(path, "cannot write (", message, ")");
  }
}

// Steps a reading statement: true for a row, false when done; an error is a FormatError.
inline bool step_read(sqlite3* db, sqlite3_stmt* stmt, const std::string& path) {
  const int rc = sqlite3_step(stmt);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  if (is_io_condition(rc)) io_error(path, "cannot read (", sqlite_message(db), ")");
  format_error(path, "damaged or not an lsgd database (SQLite: ", sqlite_message(db), ")");
}

inline std::string column_text(sqlite3_stmt* stmt, int column) {
  const auto* text = sqlite3_column_text(stmt, column);
  return text ? std::string(reinterpret_cast<const char*>(text),
                            static_cast<std::size_t>(sqlite3_column_bytes(stmt, column)))
              : std::string();
}

inline std::int64_t file_size(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 ? static_cast<std::int64_t>(st.st_size) : 0;
}


inline constexpr const char* kSchema =
    "CREATE TABLE meta(key TEXT PRIMARY KEY, value NOT NULL);"
    "CREATE TABLE frames("
    "id INTEGER PRIMARY KEY, session INTEGER NOT NULL, name TEXT NOT NULL,"
    "histogram BLOB NOT NULL, pixels BLOB NOT NULL, node INTEGER, place INTEGER,"
    "features BLOB, crc32 INTEGER NOT NULL, loop INTEGER, loop_inliers REAL, frame INTEGER,"
    "state BLOB);";
// Format 5's table of saved search indexes (made with the schema, and by the
// upgrade of older files).
inline constexpr const char* kIndexesTable =
    "CREATE TABLE IF NOT EXISTS indexes(mode TEXT NOT NULL, part INTEGER NOT NULL,"
    "frames INTEGER NOT NULL, data BLOB NOT NULL, crc32 INTEGER NOT NULL, PRIMARY KEY(mode, part));";

// Columns a format lacks read as NULL: loop state before 2, frame ids before
// 3, the components' state before 4.
inline std::string select_frames(int format, const char* tail = " ORDER BY id") {
  return concat("SELECT id, session, name, histogram, pixels, node, place, features, crc32, ",
                format < 2 ? "NULL, NULL" : "loop, loop_inliers", ", ",
                format < 3 ? "NULL" : "frame", ", ", format < 4 ? "NULL" : "state", " FROM frames",
                tail);
}

// The caller's id of a row: its frame column, or its row id in older formats.
inline std::string frame_column(int format) { return format < 3 ? "id" : "coalesce(frame, id)"; }

inline constexpr const char* kInsertFrame =
    "INSERT INTO frames(id, session, name, histogram, pixels, node, crc32, frame, state) "
    "VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)";

// Older formats -> 4, inside the caller's transaction.
inline constexpr const char* kUpgradeV1 =
    "ALTER TABLE frames ADD COLUMN loop INTEGER; ALTER TABLE frames ADD COLUMN loop_inliers REAL;";
inline constexpr const char* kUpgradeV2 = "ALTER TABLE frames ADD COLUMN frame INTEGER;";
inline constexpr const char* kUpgradeV3 = "ALTER TABLE frames ADD COLUMN state BLOB;";

// A saved index is stored in parts of at most this many bytes (SQLite's
// largest blob is 1e9 bytes; a graph of 10^6 frames is about 1.4 GB).
inline constexpr std::size_t kIndexPartBytes = std::size_t{64} << 20;

// Appends the little-endian record of `component` (version 1) to `records`.
// Rows of formats 1 to 3 keep the built-in components' state in columns of
// their own; restore() reads them as these records, whose version-1 layouts
// are those columns' (state.h, and each component's save_frame()).
inline void legacy_record(std::vector<StateRecord>& records, const char* component,
                   std::vector<std::uint8_t> bytes) {
  records.push_back({component, 1, std::move(bytes)});
}

inline const std::vector<std::string> kIntegerMeta = {"format_version", "width",     "height",
                                               "grid_rows",      "grid_cols", "checksum"};


// A stored frame's keys, as forget() keeps them (database_write.cc).
struct FrameKeys {
  std::int64_t session;
  std::string name;
  std::int64_t id;  // the caller's
};

}  // namespace db

using namespace db;  // the database files' own helpers

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
  // This Database's descriptor of the file: the writer's lock (flock) while
  // open, the header's reads. Taken and given back through the process's
  // table of open database files (database_locks.cc), never closed while
  // another Database of the file is open here: closing any descriptor of a
  // file drops every POSIX lock the process holds on it, SQLite's too.
  int lock_fd = -1;
  std::pair<dev_t, ino_t> file_key{0, 0};  // the file's identity (fstat of lock_fd)
  pid_t owner = 0;  // the process whose table holds lock_fd (0: none; fork() makes another)
  bool registered_writer = false;  // the table's writer of the file
  std::int64_t since_checkpoint = 0;
  // sqlite3_total_changes64 after the last checkpoint's own meta write (0: as
  // opened): a checkpoint with nothing written since counts no checkpoint.
  std::int64_t changes_at_checkpoint = 0;
  bool log_named = false;  // meta is in the log since the last checkpoint
  std::string note;                 // what open() found about the last writer
  bool opened = false;              // open() completed: the destructor may checkpoint
  std::string checked_yaml;  // options YAML already found compatible
  Statement insert;
  // Scratch of append(), reused between frames.
  std::vector<std::uint8_t> hist_bytes, pixel_bytes;

  ~Impl() { close_file(false); }

  // Closes the connection and gives the descriptor back (the destructor,
  // Database::close()). A writer checkpoints first (and checks that its
  // path still names its file): `report` throws what went wrong, once all
  // is closed; else the frames stay committed in the log for the next open.
  void close_file(bool report);
  void check_open() const {
    if (!db) internal::throw_invalid("database ", path, " is closed");
  }

  // The process's table of open database files (database_locks.cc).
  // Sets lock_fd to a descriptor of the file at `path` (one a closed
  // Database of the file left, or a new one) and counts this Database as a
  // user of the file.
  void open_file();
  // Gives lock_fd back (its flock released): closed with the file's other
  // spare descriptors when this is the file's last Database in the process,
  // else kept for the next one.
  void release_file() noexcept;
  // IoError when `path` no longer names the file this Database opened (it
  // was replaced, moved or deleted): the frames written went to a file that
  // path does not reach.
  void check_same_file() const;

  // Records in meta that the writer is `state` ("open" or "closed") with
  // `frames` frames, then moves every committed frame from the write-ahead
  // log into the file and empties the log: afterwards the file alone holds
  // them, and damage to the log cannot lose them (docs/reliability.md).
  void checkpoint(const char* state);
  std::int64_t read_index(const std::string& mode, std::int64_t stored,
                          std::vector<std::uint8_t>& out) const;
  // The steps of Database::restore() (database_restore.cc), inside its read
  // transaction. Every frame row into `detector`, each checked; returns the
  // rows read and the caller's id of the last (-1: none).
  std::pair<std::int64_t, std::int64_t> restore_frames(Detector& detector) const;
  // The saved index of the detector's search mode, covering `stored` frames,
  // into `detector`; none saved: nothing (the detector builds its own).
  void restore_index(Detector& detector, std::int64_t stored) const;

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
      io_error(path, "cannot write meta (", sqlite_message(db), ")");
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
        io_error(path, "cannot write meta key ", key, " (", sqlite_message(db), ")");
      }
      sqlite3_reset(stmt.get());
    }
  }

  // Runs `write` in one IMMEDIATE transaction; rolls back if it throws. The
  // first transaction of a log writes meta first, so that the log carries
  // the database's id (check_log_belongs).
  template <typename F>
  void transaction(F&& write) {
    exec_write(db, path, "BEGIN IMMEDIATE");
    try {
      if (!log_named) write_meta();
      write();
      exec_write(db, path, "COMMIT");
    } catch (...) {
      sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
      throw;
    }
    log_named = true;
  }

  // The steps of Database::open() after its checks of the file (database.cc).
  // Takes the lock: a writer's exclusive one (waiting for readers), a
  // reader's shared one; returns true when a writer holds it (a reader's only).
  bool lock();
  void register_writer();  // the table's writer of the file: one per file in this process
  // Checks the write-ahead log (wal_check.h) and that it belongs to the file;
  // returns what it holds.
  wal::WalCheck check_log(bool writer_active) const;
  void open_sqlite(bool writer_active);  // into `db`
  // `note`, when the last writer did not close the file.
  void note_last_writer(bool writer_active, const wal::WalCheck& log);
  void upgrade();        // an older format to this one (a writer only)
  void start_writing();  // journal mode, the insert statement, the first checkpoint

  // Reads and checks the header when the file is opened (database_header.cc),
  // in these steps.
  void load_header();
  void check_integrity() const;  // SQLite's quick_check
  void check_file_size() const;  // the pages the header counts are all there
  void check_tables() const;     // meta and frames
  // Every meta row into `meta`; returns each value's SQLite type.
  std::map<std::string, int> read_meta();
  void read_format(std::map<std::string, int>& types);  // format_version, into `format`
  void check_meta(std::map<std::string, int>& types);
  void read_options();     // meta options, into `options`
  void read_frame_size();  // width, height, grid
  void count_frames();     // the frames' columns, and their ids 0 .. frames - 1
  void read_session_first_ids();
  void read_last_frame();  // last_session, last_frame, sessions
  // `frame`: the detector's id of the frame; `caller_id`: the caller's.
  void insert_frame(const Detector& detector, std::int64_t frame, std::int64_t session,
                    const std::string& name, std::int64_t caller_id);
  // InvalidArgument unless frames may be appended to `session`.
  void check_session(std::int64_t session) const;
  std::int64_t check_append(const Detector& detector, const Result& result, const std::string& name,
                            std::int64_t frame) const;
  // The steps of Database::forget() (database_write.cc). Every row's keys,
  // in order.
  std::vector<FrameKeys> read_keys() const;
  // In one transaction: the rows from `dense` on replaced by the kept `rows`
  // from there, with their state in `detector`; the saved indexes dropped;
  // meta session_first_ids set to `first_ids` (empty: removed).
  void rewrite_from(std::int64_t dense, const Detector& detector,
                    const std::vector<FrameKeys>& rows, const std::string& first_ids);
};

// Refuses a companion of `path` (FILE-wal, FILE-shm, FILE-journal) that is
// not a regular file (a folder, a FIFO, a link elsewhere), naming it.
void check_companions(const std::string& path);
// Refuses a rollback journal (FILE-journal) with any bytes beside `path`
// when it cannot be the database's own, saying to move it away: SQLite
// would roll its pages back into the file. `creating`: no database is at
// `path` (a journal left by one deleted there); else one whose header says
// WAL mode (which never has a rollback journal; an old file in rollback
// mode keeps its own).
// `fd`: a descriptor of the database file whose header is read (pread: no
// descriptor of the file is opened and closed, which would drop the
// process's POSIX locks on it); -1 when creating.
void check_rollback_journal(const std::string& path, bool creating, int fd = -1);
// True when FILE-wal and FILE-shm cannot be created beside `path`: a
// read-only file system, or a folder this user cannot write.
bool companions_cannot_be_created(const std::string& path);
// SQLite's URI opening `path` as immutable (database_companions.cc).
std::string immutable_uri(const std::string& path);
// The name SQLite is given for `path`: a relative path as ./path, so that
// SQLite never reads ":memory:" (a private in-memory database) or
// "file:..." (a URI) into a file's name.
std::string sqlite_file_name(const std::string& path);
// The file a database at `path` is: the target of a symbolic link (SQLite
// resolves the link and keeps the log beside the target, so lsgd checks and
// opens the companions there too), else `path`. A link to nothing is an
// IoError naming both; `creating`: a link at all is refused (a database is
// created at its own name).
std::string database_file(const std::string& path, bool creating);
// A new database's meta database_id: 32 random hex digits. The writer
// writes meta in the first transaction of every log (database_write.cc), so a log
// carries the id of the database that wrote it.
std::string new_database_id();
// IoError, saying to move it away, when FILE-wal holds committed
// transactions of another database (its meta's database_id differs from
// the file's own); nothing to compare for files written before ids.
void check_log_belongs(const std::string& path);

}  // namespace lsgd::io
