#include "lsgd/io/database.h"
#include "lsgd/io/files.h"

#include "io/database_internal.h"
#include "internal/file_mode.h"


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
#include <exception>
#include <fstream>
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


Database::Database(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Database::~Database() = default;
Database::Database(Database&& other) noexcept = default;
Database& Database::operator=(Database&& other) noexcept = default;

void Database::close() {
  if (impl_) impl_->close_file(true);
}

void Database::Impl::close_file(bool report) {
  std::exception_ptr error;
  if (db && writable && opened) {
    opened = false;
    try {
      checkpoint("closed");
      check_same_file();
    } catch (...) {
      error = std::current_exception();
    }
  }
  insert = Statement();
  if (db) sqlite3_close_v2(db);
  db = nullptr;
  release_file();  // after SQLite's connection
  if (report && error) std::rethrow_exception(error);
}

namespace {

// The file at `path` before anything opens it: it exists, is a regular file
// with regular companions (its rollback journal is checked once it is
// open), has one name when written, and this user may read (and write) it.
void check_file(const std::string& path, bool writable) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) {
    io_error(path, errno == ENOENT ? "does not exist" : "cannot be opened",
             errno == ENOENT ? "" : concat(" (", std::strerror(errno), ")"));
  }
  if (!S_ISREG(st.st_mode)) io_error(path, "is not a regular file");
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
  if (writable && !internal::mode_allows_writing(st.st_mode)) {
    io_error(path, "is read-only (no write permission at all): open it for reading, or make it "
             "writable to append to it");
  }
}

}  // namespace

Database Database::open(const std::string& given, Mode mode) {
  const bool writable = mode == Mode::kReadWrite;
  if (given.empty()) throw InvalidArgument("the database path is empty: give a file name");
  const std::string path = database_file(given, false);
  check_path_length(path, path);
  check_file(path, writable);
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->writable = writable;
  // One writer at a time: a second one would interleave its frames with ours.
  // The writer holds an exclusive flock on its descriptor of the file while
  // open (flock locks are separate from SQLite's POSIX locks). The descriptor
  // comes from the process's table of open database files
  // (database_locks.cc), which closes it only with the file's last Database
  // here: closing any descriptor of the file drops the process's SQLite
  // locks on it. The header is read through it too.
  impl->open_file();
  check_rollback_journal(path, false, impl->lock_fd);
  const bool writer_active = impl->lock();
  const wal::WalCheck log = impl->check_log(writer_active);
  impl->open_sqlite(writer_active);
  impl->load_header();
  // An lsgd database: closing it empties and removes its log as before.
  sqlite3_db_config(impl->db, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 0, nullptr);
  impl->note_last_writer(writer_active, log);
  if (writable && impl->format < kDatabaseFormatVersion) impl->upgrade();
  if (writable) impl->start_writing();
  return Database(std::move(impl));
}

bool Database::Impl::lock() {
  if (!writable) {
    // Refused: a writer is active; its log is in flux: SQLite reads it
    // consistently, we cannot.
    return ::flock(lock_fd, LOCK_SH | LOCK_NB) != 0;
  }
  register_writer();
  // A reader holds a shared lock for a moment (lock() to check_log()): wait up to 2 s.
  int tries = 0;
  while (::flock(lock_fd, LOCK_EX | LOCK_NB) != 0) {
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
  return false;
}

// Before SQLite replays the log, which it would do silently up to any damage.
wal::WalCheck Database::Impl::check_log(bool writer_active) const {
  const wal::WalCheck log = writer_active ? wal::WalCheck{} : wal::check_wal(path + "-wal");
  if (!writable && !writer_active) ::flock(lock_fd, LOCK_UN);
  if (!log.damage.empty()) {
    format_error(path, log.damage,
                 ". Nothing was changed; to open the database as of its last checkpoint, losing "
                 "what the log holds, move '",
                 path, "-wal' away");
  }
  if (!writer_active && log.committed_frames > 0) check_log_belongs(path);
  return log;
}

void Database::Impl::open_sqlite(bool writer_active) {
  // A reader where FILE-shm cannot be created (database_companions.cc): the
  // file as immutable when its log holds nothing; else say what to do.
  bool immutable = false;
  if (!writable && !writer_active && companions_cannot_be_created(path)) {
    if (file_size(path + "-wal") > 0) {
      io_error(path, "cannot be read where it is: its write-ahead log '", path, "-wal' holds "
               "frames not yet in the file, and SQLite cannot create '", path, "-shm' to read "
               "them (a read-only file system or folder); copy the database and its -wal to a "
               "writable folder, or open it for writing once where it was written");
    }
    immutable = true;
  }
  const int flags = writable ? SQLITE_OPEN_READWRITE
                             : SQLITE_OPEN_READONLY | (immutable ? SQLITE_OPEN_URI : 0);
  const std::string name = immutable ? immutable_uri(path) : sqlite_file_name(path);
  if (sqlite3_open_v2(name.c_str(), &db, flags, nullptr) != SQLITE_OK) {
    io_error(path, "cannot open (", sqlite_message(db), ")");
  }
  sqlite3_extended_result_codes(db, 1);
  sqlite3_busy_timeout(db, 5000);
  // No checkpoint when the connection closes until the file is known to be
  // an lsgd database (Database::open): a file refused on the way (another
  // program's SQLite database, a damaged header) is left as it was found.
  // SQLite's checkpoint on close moved another program's log into its file
  // and deleted it before the refusal.
  sqlite3_db_config(db, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, nullptr);
}

void Database::Impl::note_last_writer(bool writer_active, const wal::WalCheck& log) {
  const auto writer = meta.find("writer");
  if (writer == meta.end() || writer->second != "open") return;
  const auto at = meta.find("checkpoint_frames");
  const std::string checkpointed = at == meta.end() ? "?" : at->second;
  if (!writable) {
    note = writer_active
               ? concat("a writer has it open (", frames, " frames readable)")
               : concat("its last writer was stopped before closing it (", frames,
                        " frames readable, ", checkpointed,
                        " of them checkpointed into the file)");
  } else if (log.committed_frames > 0) {
    note = concat("the last writer was stopped before closing it; its write-ahead log held ",
                  log.committed_frames, " pages of committed transactions, replayed: ",
                  frames, " frames");
  } else {
    note = concat("the last writer was stopped before closing it and left no write-ahead "
                  "log: the ",
                  frames, " frames of its last checkpoint are here; frames it committed "
                  "after that checkpoint, if any, are lost");
  }
}

// Upgrade in place, atomically: the columns and the new meta or nothing.
void Database::Impl::upgrade() {
  exec_write(db, path, "BEGIN IMMEDIATE");
  try {
    if (format < 2) exec_write(db, path, kUpgradeV1);
    if (format < 3) exec_write(db, path, kUpgradeV2);
    if (format < 4) exec_write(db, path, kUpgradeV3);
    exec_write(db, path, kIndexesTable);
    meta["format_version"] = std::to_string(kDatabaseFormatVersion);
    meta["options"] = to_yaml(options);
    write_meta();
    exec_write(db, path, "COMMIT");
  } catch (...) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    meta["format_version"] = std::to_string(format);
    throw;
  }
  format = kDatabaseFormatVersion;
}

void Database::Impl::start_writing() {
  // WAL: an append writes its pages once, sequentially, to the log; FULL:
  // the log is synced at every commit, so a committed frame survives a
  // power loss too. SQLite's own checkpoints are replaced by ours, which
  // empty the log (docs/reliability.md, "Persistence").
  exec_write(db, path,
             "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL; PRAGMA wal_autocheckpoint=0;");
  insert = Statement(db, path, kInsertFrame);
  if (meta.find("database_id") == meta.end()) meta["database_id"] = new_database_id();
  checkpoint("open");
  opened = true;
}

namespace {

// SQLite names its companions FILE-journal, -wal and -shm: the file's name
// must leave room for the longest.
constexpr std::size_t kCompanionSuffix = 8;  // "-journal"

// What must hold before a database is created at `path`; nothing is created.
void check_new_database_path(const std::string& path) {
  if (path.empty()) throw InvalidArgument("the database path is empty: give a file name");
  database_file(path, true);  // a symbolic link is refused
  struct stat st;
  if (::stat(path.c_str(), &st) == 0) io_error(path, "already exists");
  check_companions(path);
  check_rollback_journal(path, true);
  // A log left by a database deleted at this path (its writer killed, the
  // file removed): SQLite would replay its frames into the new database.
  if (::stat((path + "-wal").c_str(), &st) == 0 && st.st_size > 0) {
    io_error(path, "'", path, "-wal' is the write-ahead log of a database that was deleted at "
             "this path (", st.st_size, " bytes): SQLite would replay it into the new database. "
             "Move '", path, "-wal' and '", path, "-shm' away, or give another path "
             "(nothing was created)");
  }
  const std::size_t name = name_length(path);
  if (const std::size_t limit = name_limit(path); name + kCompanionSuffix > limit) {
    io_error(path, "its name is ", name, " bytes; SQLite's companion NAME-journal would be ",
             name + kCompanionSuffix, ", over the folder's limit of ", limit,
             " bytes a name: give a name of at most ", limit - kCompanionSuffix,
             " bytes (nothing was created)");
  }
}

void remove_with_companions(const std::string& file) {
  for (const char* suffix : {"", "-journal", "-wal", "-shm"}) ::unlink((file + suffix).c_str());
}

// The process's umask, as /proc/self/status tells it ("" when it does not:
// umask() itself would change it for every thread while read).
std::string umask_text() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("Umask:", 0) == 0) {
      const std::size_t at = line.find_first_not_of(" \t", 6);
      return at == std::string::npos ? "" : line.substr(at);
    }
  }
  return "";
}

// A new database its owner cannot write (a umask of 0200 or more) is refused
// as such, before it takes its name ("is read-only ... make it writable to
// append to it" named a file the run was creating).
void check_new_file_writable(const std::string& tmp, const std::string& path) {
  struct stat st {};
  if (::stat(tmp.c_str(), &st) != 0 || (st.st_mode & S_IWUSR) != 0) return;
  remove_with_companions(tmp);
  const std::string mask = umask_text();
  char mode[8];
  std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
  io_error(path, "cannot create it: the new file's permissions (", mode,
           ") do not let its owner write it; the umask", mask.empty() ? "" : " (" + mask + ")",
           " removes the write permission (umask 022, say) (nothing was created)");
}

// The finished temporary database takes its name: link() fails when `path`
// exists (no silent overwrite); rename() on file systems without hard links.
// The new name is made durable.
void publish_database(const std::string& tmp, const std::string& path) {
  struct stat st;
  if (::link(tmp.c_str(), path.c_str()) != 0) {
    const int error = errno;
    if (error == EEXIST || ::stat(path.c_str(), &st) == 0) {
      // It did not exist when this creation began (check_new_database_path):
      // another process created it meanwhile (two `lsgd run --database` at
      // one new path). Nothing of this one is kept; the other's is whole.
      ::unlink(tmp.c_str());
      io_error(path, "was created by another process while this one created it (two runs given "
               "one new database?): nothing was stored here, the other's database is untouched; "
               "run again to resume it once the other has finished");
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
  const int fd = ::open(folder_of(path).c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

Database Database::create(const std::string& path, const DetectorOptions& options) {
  options.check();
  check_new_database_path(path);
  const std::string tmp = temporary_beside(path, kCompanionSuffix);
  check_path_length(path, tmp);
  remove_with_companions(tmp);
  {  // a new, empty database written whole at tmp; on failure nothing is left there
    Impl impl;  // closes the temporary database on every path
    impl.path = path;
    if (sqlite3_open_v2(sqlite_file_name(tmp).c_str(), &impl.db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                        nullptr) != SQLITE_OK) {
      const std::string message = sqlite_message(impl.db);
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
                   {"grid_cols", "0"},
                   {"database_id", new_database_id()}};
      impl.write_meta();
      exec_write(impl.db, path, "COMMIT; PRAGMA journal_mode=WAL;");
    } catch (...) {
      sqlite3_close_v2(impl.db);
      impl.db = nullptr;
      remove_with_companions(tmp);
      throw;
    }
    if (sqlite3_close(impl.db) != SQLITE_OK) io_error(path, "cannot close ", tmp);
    impl.db = nullptr;
  }
  check_new_file_writable(tmp, path);
  publish_database(tmp, path);
  // A database that cannot be opened once created (no file descriptor left,
  // an I/O error) holds nothing yet: removed, so that it does not pin these
  // options for the next run at this path.
  try {
    return open(path, Mode::kReadWrite);
  } catch (...) {
    remove_with_companions(path);
    throw;
  }
}

const std::string& Database::path() const { return impl_->path; }
const DetectorOptions& Database::options() const { return impl_->options; }
std::int64_t Database::frames() const { return impl_->frames; }
std::int64_t Database::last_session() const { return impl_->last_session; }
std::int64_t Database::last_frame() const { return impl_->last_frame; }
const std::string& Database::note() const { return impl_->note; }

std::vector<std::int64_t> Database::frame_ids() const {
  const Impl& m = *impl_;
  m.check_open();
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
  m.check_open();
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
  m.check_open();
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

}  // namespace lsgd::io
