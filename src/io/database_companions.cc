// The files SQLite keeps beside a database. A database on a read-only file
// system or in a folder this user cannot write (a map shipped on read-only
// media, a container's read-only volume): SQLite reads a WAL database through its shared index, FILE-shm, which it
// creates beside the file; where that cannot be created, the file is read
// as immutable (SQLite's `immutable=1`: no locks, no -shm), which is exact
// as long as nothing is in the log and nobody writes.
#include <errno.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <sqlite3.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <random>
#include <string>
#include <utility>

#include "internal/numbers.h"
#include "io/database_internal.h"
#include "lsgd/io/files.h"

#include <memory>

namespace lsgd::io {

// SQLite keeps a database's write-ahead log and its index beside the name it
// was opened by (FILE-wal, FILE-shm; FILE-journal in rollback mode) and
// trusts whatever it finds there.
// Refuses a companion (FILE-wal, FILE-shm, FILE-journal) that is not a
// regular file (a folder, a FIFO, a link elsewhere), naming it.
void check_companions(const std::string& path) {
  constexpr std::pair<const char*, const char*> kCompanions[] = {
      {"-wal", "write-ahead log"}, {"-shm", "shared index of the log"}, {"-journal", "rollback journal"}};
  for (const auto& [suffix, what] : kCompanions) {
    const std::string companion = path + suffix;
    struct stat st;
    if (::lstat(companion.c_str(), &st) != 0) continue;
    if (S_ISREG(st.st_mode)) continue;
    const char* kind = S_ISDIR(st.st_mode)    ? "a directory"
                       : S_ISLNK(st.st_mode)  ? "a symbolic link"
                       : S_ISFIFO(st.st_mode) ? "a FIFO"
                                              : "not a regular file";
    io_error(path, "'", companion, "' is ", kind, ", where SQLite keeps the database's ", what,
             ": move it away (nothing was changed)");
  }
}

void check_rollback_journal(const std::string& path, bool creating, int fd) {
  const std::string journal = path + "-journal";
  struct stat st;
  if (::stat(journal.c_str(), &st) != 0 || st.st_size == 0) return;
  if (creating) {
    io_error(path, "'", journal, "' is the rollback journal of a database that was deleted at "
             "this path (", st.st_size, " bytes): SQLite would roll its pages back into the new "
             "database. Move '", journal, "' away, or give another path (nothing was created)");
  }
  // The header's write and read versions (bytes 18, 19): 2 in WAL mode.
  // Read through the Database's own descriptor: opening and closing another
  // would drop the POSIX locks this process's connections hold on the file.
  unsigned char header[20] = {};
  if (fd < 0) return;
  const bool read = ::pread(fd, header, sizeof header, 0) == static_cast<ssize_t>(sizeof header);
  if (!read || header[18] != 2 || header[19] != 2) return;
  io_error(path, "'", journal, "' (", st.st_size, " bytes) is a rollback journal, which a database "
           "in WAL mode never has: it was left by another database at this path, and SQLite "
           "would roll its pages back into this one. Nothing was changed; move '", journal,
           "' away to open the database");
}

bool companions_cannot_be_created(const std::string& path) {
  struct statvfs fs {};
  if (::statvfs(path.c_str(), &fs) == 0 && (fs.f_flag & ST_RDONLY) != 0) return true;
  return ::access(folder_of(path).c_str(), W_OK) != 0 && errno != ENOENT;
}

std::string immutable_uri(const std::string& path) {
  std::string absolute = path;
  if (path.empty() || path[0] != '/') {
    if (char* cwd = ::getcwd(nullptr, 0)) {
      absolute = std::string(cwd) + "/" + path;
      std::free(cwd);
    }
  }
  // file:///a/b for /a/b (an empty authority, so that //a/b stays a path);
  // a relative path (no working folder) as file:a/b. Every byte but the
  // unreserved ones and '/' is percent-encoded ('?', '#' and '%' must be).
  std::string uri = absolute[0] == '/' ? "file://" : "file:";
  static const char kHex[] = "0123456789ABCDEF";
  for (const unsigned char c : absolute) {
    if (std::isalnum(c) || c == '/' || c == '.' || c == '-' || c == '_' || c == '~') {
      uri += static_cast<char>(c);
    } else {
      uri += '%';
      uri += kHex[c >> 4];
      uri += kHex[c & 15];
    }
  }
  return uri + "?immutable=1";
}

std::string sqlite_file_name(const std::string& path) {
  return !path.empty() && path[0] != '/' ? "./" + path : path;
}

std::string database_file(const std::string& path, bool creating) {
  struct stat st;
  if (::lstat(path.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return path;
  char* target = ::realpath(path.c_str(), nullptr);
  if (target == nullptr) {
    const int error = errno;
    io_error(path, "is a symbolic link to a file that cannot be reached (", std::strerror(error),
             "): give the database's own file", creating ? " (nothing was created)" : "");
  }
  const std::string file(target);
  std::free(target);
  if (creating) {
    io_error(path, "already exists (a symbolic link to '", file, "')");
  }
  return file;
}

std::string new_database_id() {
  std::random_device random;
  static const char kHex[] = "0123456789abcdef";
  std::string id;
  for (int i = 0; i < 8; ++i) {
    const unsigned v = random();
    for (int k = 0; k < 4; ++k) id += kHex[(v >> (4 * k)) & 15];
  }
  return id;
}

namespace {

// meta's `key` as `name` reads it (a path, or an immutable URI: the file
// alone, without its log); none for a file written before the key.
std::optional<std::string> read_meta(const std::string& path, const std::string& name, bool uri,
                                     const char* key) {
  sqlite3* db = nullptr;
  const int flags = SQLITE_OPEN_READONLY | (uri ? SQLITE_OPEN_URI : 0);
  const std::unique_ptr<sqlite3, int (*)(sqlite3*)> owner(
      sqlite3_open_v2((uri ? name : sqlite_file_name(name)).c_str(), &db, flags, nullptr) == SQLITE_OK ? db : (sqlite3_close(db), nullptr),
      sqlite3_close);
  if (!owner) io_error(path, "cannot open (", uri ? "the file alone" : "with its log", ")");
  sqlite3_busy_timeout(db, 5000);
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db, "SELECT value FROM meta WHERE key = ?", -1, &raw, nullptr) != SQLITE_OK) {
    sqlite3_finalize(raw);
    return std::nullopt;  // damage: the open's own checks name it
  }
  const std::unique_ptr<sqlite3_stmt, int (*)(sqlite3_stmt*)> stmt(raw, sqlite3_finalize);
  sqlite3_bind_text(stmt.get(), 1, key, -1, SQLITE_STATIC);
  if (sqlite3_step(stmt.get()) != SQLITE_ROW) return std::nullopt;
  const unsigned char* text = sqlite3_column_text(stmt.get(), 0);
  return text ? std::optional<std::string>(reinterpret_cast<const char*>(text)) : std::nullopt;
}

// meta's checkpoint count as `name` reads it; -1 for none.
std::int64_t read_checkpoints(const std::string& path, const std::string& name, bool uri) {
  const std::optional<std::string> text = read_meta(path, name, uri, "checkpoints");
  std::int64_t count = -1;
  if (!text || !internal::parses_as(*text, count)) return -1;
  return count;
}

}  // namespace

void check_log_belongs(const std::string& path) {
  const std::optional<std::string> own = read_meta(path, immutable_uri(path), true, "database_id");
  if (!own) return;  // written before database ids: nothing to compare
  const std::optional<std::string> logged = read_meta(path, path, false, "database_id");
  if (logged && *logged != *own) {
    io_error(path, "'", path, "-wal' is the write-ahead log of another database (", *logged,
             "; this file is ", *own, "): SQLite would replay that database's frames into this "
             "one. Nothing was changed; move '", path, "-wal' and '", path, "-shm' away to open "
             "the file as of its last checkpoint");
  }
  // The log began after the file's last checkpoint, or later: one that began
  // before it (FILE-wal copied before FILE) would replay its old pages over
  // the file's newer frames.
  const std::int64_t file = read_checkpoints(path, immutable_uri(path), true);
  const std::int64_t log = read_checkpoints(path, path, false);
  if (file >= 0 && log >= 0 && log < file) {
    io_error(path, "'", path, "-wal' is older than the file: it was written after checkpoint ",
             log, " of this database, and the file holds checkpoint ", file, " (the log copied "
             "before the file?): SQLite would replay its old pages over newer frames. Nothing was "
             "changed; move '", path, "-wal' and '", path, "-shm' away to open the file as of its "
             "last checkpoint, or copy the file and its log together again");
  }
}

}  // namespace lsgd::io
