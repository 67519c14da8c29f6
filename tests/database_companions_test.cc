// The files SQLite keeps beside a database (docs/reliability.md, issue 35).
// A log of another database is refused. A database on a read-only file
// system is readable where SQLite cannot create its FILE-shm, exactly, and
// a log that would need one is refused saying what to do. The read-only file system is
// a bind mount of the test's folder in a mount namespace of a child process;
// where the machine allows none (no CAP_SYS_ADMIN), the test is skipped.
#include <errno.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sched.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <exception>
#include <fstream>
#include <functional>
#include <iterator>
#include <filesystem>
#include <string>
#include <vector>

#include "detector_util.h"
#include "lsgd/error.h"
#include "lsgd/io/database.h"
#include "test_util.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using test::frame;

constexpr int kSkip = 77;

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A folder of its own with a database of `frames` frames, closed (every
// frame in the file) or, with `log`, copied while its writer runs (frames in
// FILE-wal).
std::string database_in_folder(const std::string& name, int frames, bool log, int first = 0) {
  const std::string folder = std::string(LSGD_TEST_TMP) + "/read_only_" + name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  const std::string path = folder + "/map ?#%.db";  // URI-special characters
  DetectorOptions o;
  o.search.min_gap = 2;
  o.verification.geometric_options.max_features = 32;
  const std::string live = std::string(LSGD_TEST_TMP) + "/read_only_" + name + "_live.db";
  for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(live + suffix);
  {
    Database db = Database::create(log ? live : path, o);
    Detector d(o);
    for (int i = 0; i < frames; ++i) db.append(d, d.process(frame(first + i)), 0, "f" + std::to_string(i));
    if (log) {
      fs::copy_file(live, path);
      fs::copy_file(live + "-wal", path + "-wal");
    }
  }
  return path;
}

// Runs `check` in a child whose mount namespace has `folder` read-only; its
// exit code (kSkip: no namespace here).
int in_read_only_folder(const std::string& folder, const std::function<int()>& check) {
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::unshare(CLONE_NEWNS) != 0) ::_exit(kSkip);
    if (::mount("none", "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) ::_exit(kSkip);
    if (::mount(folder.c_str(), folder.c_str(), nullptr, MS_BIND, nullptr) != 0) ::_exit(kSkip);
    if (::mount(nullptr, folder.c_str(), nullptr, MS_REMOUNT | MS_BIND | MS_RDONLY, nullptr) != 0) {
      ::_exit(kSkip);
    }
    const int fd = ::open((folder + "/probe").c_str(), O_CREAT | O_WRONLY, 0600);
    if (fd >= 0 || errno != EROFS) ::_exit(kSkip);
    int code = 0;
    try {
      code = check();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s\n", e.what());
      code = 3;
    }
    std::fflush(nullptr);
    ::_exit(code);
  }
  int status = 0;
  if (pid < 0 || ::waitpid(pid, &status, 0) != pid || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

// A process out of file descriptors (ulimit -n) gets the reason, not
// SQLite's bare "unable to open database file": opening and creating, in a
// child whose soft limit is its lowest free descriptor.
TEST(DatabaseLimits, OutOfFileDescriptorsIsSaidSo) {
  const std::string path = database_in_folder("fd_limit", 3, false);
  const std::string created = fs::path(path).parent_path().string() + "/new.db";
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int probe = ::open("/dev/null", O_RDONLY);
    if (probe < 0) ::_exit(kSkip);
    ::close(probe);
    struct rlimit limit{};
    if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) ::_exit(kSkip);
    const struct rlimit before = limit;
    limit.rlim_cur = static_cast<rlim_t>(probe);
    if (::setrlimit(RLIMIT_NOFILE, &limit) != 0) ::_exit(kSkip);
    // The errors are kept and read once the limit is back: with no descriptor
    // left, UBSan cannot check the exception's vptr (it reads /proc/self/maps).
    std::exception_ptr opened, created_error;
    int code = 0;
    try {
      Database::open(path, Database::Mode::kReadOnly);
      code |= 1;
    } catch (...) {
      opened = std::current_exception();
    }
    try {
      Database::create(created, DetectorOptions{});
      code |= 4;
    } catch (...) {
      created_error = std::current_exception();
    }
    if (::setrlimit(RLIMIT_NOFILE, &before) != 0) ::_exit(kSkip);
    const auto said = [](const std::exception_ptr& error, const std::string& file) {
      try {
        if (error) std::rethrow_exception(error);
      } catch (const IoError& e) {
        const std::string m = e.what();
        if (m.find(file) != std::string::npos && m.find("Too many open files") != std::string::npos) return true;
        std::fprintf(stderr, "%s\n", m.c_str());
      } catch (...) {
      }
      return false;
    };
    if (!(code & 1) && !said(opened, path)) code |= 2;
    if (!(code & 4) && !said(created_error, created)) code |= 8;
    std::fflush(nullptr);
    ::_exit(code);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  if (WEXITSTATUS(status) == kSkip) GTEST_SKIP() << "cannot lower RLIMIT_NOFILE here";
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1/4: no error, 2/8: the message lacks the file or the reason";
  EXPECT_FALSE(fs::exists(created));
}

// SQLite refuses an absolute path over 504 bytes (its journal's name would
// pass 512) with a bare "unable to open database file" and a stale errno;
// lsgd names the length instead, and 504 bytes still open.
// A umask that leaves the owner no write permission: the new database is
// refused as such and nothing is left (it was created, then refused as "is
// read-only ... make it writable to append to it").
TEST(DatabaseLimits, AUmaskWithoutWritePermissionIsSaidSo) {
  const std::string folder = std::string(LSGD_TEST_TMP) + "/umask";
  fs::remove_all(folder);
  fs::create_directories(folder);
  const std::string path = folder + "/new.db";
  const mode_t before = ::umask(0777);
  const std::string e = test::message_of<IoError>([&] { Database::create(path, DetectorOptions{}); });
  ::umask(before);
  EXPECT_NE(e.find("database " + path + ": cannot create it: the new file's permissions (0000)"), std::string::npos)
      << e;
  EXPECT_NE(e.find("the umask (0777)"), std::string::npos) << e;
  EXPECT_TRUE(fs::is_empty(folder)) << "nothing is left";
  EXPECT_NO_THROW(Database::create(path, DetectorOptions{}));  // the usual umask
}

TEST(DatabaseLimits, APathBeyondSqlitesLimitIsSaidSo) {
  const std::string short_path = database_in_folder("long_path", 2, false);
  std::string folder = fs::path(short_path).parent_path().string();
  while (folder.size() < 600) folder += "/" + std::string(100, 'd');
  fs::create_directories(folder);
  const std::string created = folder + "/new.db";
  const std::string e1 = test::message_of<IoError>([&] { Database::create(created, DetectorOptions{}); });
  EXPECT_NE(e1.find(created), std::string::npos) << e1;
  EXPECT_NE(e1.find("absolute path is"), std::string::npos) << e1;
  EXPECT_FALSE(fs::exists(created));
  const std::string moved = folder + "/moved.db";
  fs::rename(short_path, moved);
  const std::string e2 = test::message_of<IoError>([&] { Database::open(moved, Database::Mode::kReadOnly); });
  EXPECT_NE(e2.find("SQLite opens paths of at most 504 bytes"), std::string::npos) << e2;
  // Just under the limit both work.
  std::string near_folder = fs::absolute(fs::path(short_path).parent_path()).string();
  while (504 - near_folder.size() > 200) near_folder += "/" + std::string(150, 'n');
  fs::create_directories(near_folder);
  const auto named = [&](std::size_t bytes) {
    return near_folder + "/" + std::string(bytes - near_folder.size() - 1 - 3, 'n') + ".db";
  };
  fs::rename(moved, named(505));
  const std::string e3 = test::message_of<IoError>([&] { Database::open(named(505), Database::Mode::kReadOnly); });
  EXPECT_NE(e3.find("is 505 bytes long"), std::string::npos) << e3;
  fs::rename(named(505), named(504));
  EXPECT_EQ(Database::open(named(504), Database::Mode::kReadOnly).frames(), 2);
}

TEST(DatabaseReadOnly, AReadOnlyFileSystemIsReadExactly) {
  const std::string path = database_in_folder("closed", 12, false);
  const std::string folder = fs::path(path).parent_path().string();
  ASSERT_FALSE(fs::exists(path + "-shm"));  // a closed writer leaves none
  const int code = in_read_only_folder(folder, [&] {
    const Database db = Database::open(path, Database::Mode::kReadOnly);
    if (db.frames() != 12) return 1;
    db.verify();
    Detector d(db.options());
    db.restore(d);
    if (d.size() != 12) return 2;
    return fs::exists(path + "-shm") ? 4 : 0;  // nothing written beside it
  });
  if (code == kSkip) GTEST_SKIP() << "no mount namespace on this machine (needs CAP_SYS_ADMIN)";
  EXPECT_EQ(code, 0);
  // A writer still gets the file system's own refusal, naming the file.
  const int writer = in_read_only_folder(folder, [&] {
    try {
      Database db = Database::open(path, Database::Mode::kReadWrite);
    } catch (const IoError& e) {
      return std::string(e.what()).find(path) != std::string::npos ? 0 : 5;
    }
    return 6;
  });
  EXPECT_EQ(writer, 0);
}

TEST(DatabaseReadOnly, ALogThatNeedsItsIndexIsRefusedSayingWhatToDo) {
  const std::string path = database_in_folder("log", 40, true);  // frames 32 .. 39 in the log
  const std::string folder = fs::path(path).parent_path().string();
  const int code = in_read_only_folder(folder, [&] {
    try {
      const Database db = Database::open(path, Database::Mode::kReadOnly);
    } catch (const IoError& e) {
      const std::string m = e.what();
      const bool says = m.find(path + "-wal") != std::string::npos &&
                        m.find("copy the database and its -wal to a writable folder") != std::string::npos;
      if (!says) std::fprintf(stderr, "%s\n", m.c_str());
      return says ? 0 : 7;
    }
    return 8;
  });
  if (code == kSkip) GTEST_SKIP() << "no mount namespace on this machine (needs CAP_SYS_ADMIN)";
  EXPECT_EQ(code, 0);
  // Writable again, the log is read: every frame.
  const Database db = Database::open(path, Database::Mode::kReadOnly);
  EXPECT_EQ(db.frames(), 40);
}

// Two databases of the same options: A's file (32 frames checkpointed) and
// B's log (its frames 32 .. 39, other images) beside it would replay without
// damage, mixing B's frames into A; refused by the database ids, readers
// and writers alike, nothing changed. Moved away, A opens as it was.
TEST(DatabaseLog, AnotherDatabasesLogIsRefusedSayingToMoveItAway) {
  const std::string a = database_in_folder("a", 40, true);
  const std::string b = database_in_folder("b", 40, true, 100);
  fs::remove(a + "-wal");
  fs::copy_file(b + "-wal", a + "-wal");
  const std::string before = read_bytes(a);
  for (const auto mode : {Database::Mode::kReadOnly, Database::Mode::kReadWrite}) {
    const std::string m = test::message_of<IoError>([&] { Database::open(a, mode); });
    EXPECT_NE(m.find("'" + a + "-wal' is the write-ahead log of another database"), std::string::npos) << m;
    EXPECT_NE(m.find("move '" + a + "-wal' and '" + a + "-shm' away"), std::string::npos) << m;
  }
  EXPECT_EQ(read_bytes(a), before);
  // B's own log is B's.
  EXPECT_EQ(Database::open(b, Database::Mode::kReadOnly).frames(), 40);
  // Through a symbolic link too: SQLite resolves the link and keeps the log
  // beside the target, so the checks look there (they looked for LINK-wal,
  // found none, and a writer through the link took in B's frames).
  const std::string link = fs::path(a).parent_path().string() + "/link.db";
  fs::create_symlink(a, link);
  for (const auto mode : {Database::Mode::kReadOnly, Database::Mode::kReadWrite}) {
    const std::string m = test::message_of<IoError>([&] { Database::open(link, mode); });
    EXPECT_NE(m.find("'" + fs::canonical(a).string() + "-wal' is the write-ahead log of another database"),
              std::string::npos) << m;
  }
  EXPECT_EQ(read_bytes(a), before);
  fs::rename(a + "-wal", a + "-wal.b");
  fs::remove(a + "-shm");
  EXPECT_EQ(Database::open(a, Database::Mode::kReadOnly).frames(), 32);
  EXPECT_EQ(Database::open(link, Database::Mode::kReadOnly).frames(), 32);
  // A link is no name to create a database at, and a link to nothing names itself.
  EXPECT_NE(test::message_of<IoError>([&] { Database::create(link, DetectorOptions{}); }).find("symbolic link"),
            std::string::npos);
  const std::string dangling = fs::path(a).parent_path().string() + "/dangling.db";
  fs::create_symlink(fs::path(a).parent_path() / "nothing.db", dangling);
  for (const auto& attempt : std::vector<std::function<void()>>{
           [&] { Database::create(dangling, DetectorOptions{}); }, [&] { Database::open(dangling); }}) {
    const std::string m = test::message_of<IoError>(attempt);
    EXPECT_NE(m.find("symbolic link to a file that cannot be reached"), std::string::npos) << m;
  }
  EXPECT_FALSE(fs::exists(fs::path(a).parent_path() / "nothing.db"));
}

// Another program's SQLite database in WAL mode, with a log not yet in its
// file: refused, and left byte for byte as it was (SQLite's checkpoint when
// the connection closed moved the log into the file and deleted it).
TEST(DatabaseNames, AnotherProgramsDatabaseIsLeftAsItWasFound) {
  const std::string folder = std::string(LSGD_TEST_TMP) + "/other_program_" + std::to_string(::getpid());
  fs::remove_all(folder);
  fs::create_directories(folder);
  const std::string live = folder + "/live.db", path = folder + "/app.db";
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(live.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "PRAGMA journal_mode=WAL; PRAGMA wal_autocheckpoint=0; CREATE TABLE t(a);",
                         nullptr, nullptr, nullptr), SQLITE_OK);
  for (int i = 0; i < 20; ++i) {
    ASSERT_EQ(sqlite3_exec(db, "INSERT INTO t VALUES (1)", nullptr, nullptr, nullptr), SQLITE_OK);
  }
  fs::copy_file(live, path);
  fs::copy_file(live + "-wal", path + "-wal");
  sqlite3_close(db);
  const std::string before = read_bytes(path) + "|" + read_bytes(path + "-wal");
  for (const auto mode : {Database::Mode::kReadWrite, Database::Mode::kReadOnly}) {
    const std::string m = test::message_of<FormatError>([&] { Database::open(path, mode); });
    EXPECT_NE(m.find("not an lsgd database"), std::string::npos) << m;
    EXPECT_EQ(read_bytes(path) + "|" + read_bytes(path + "-wal"), before);
  }
  fs::remove_all(folder);
}

// Names SQLite would read as something else: ":memory:" (a private database
// in memory) and "file:..." (a URI) given as relative paths are files like
// any other (lsgd created the file, then SQLite opened another database).
TEST(DatabaseNames, NamesSqliteWouldInterpretAreFiles) {
  const fs::path folder = fs::path(LSGD_TEST_TMP) / ("sqlite_names_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  const fs::path was = fs::current_path();
  fs::current_path(folder);
  DetectorOptions o;
  o.search.min_gap = 2;
  o.verification.geometric_options.max_features = 32;
  for (const std::string name : {":memory:", "file:a.db", "file:b.db?mode=memory"}) {
    SCOPED_TRACE(name);
    {
      Database db = Database::create(name, o);
      Detector d(o);
      for (int i = 0; i < 3; ++i) db.append(d, d.process(frame(i)), 0);
    }
    EXPECT_TRUE(fs::is_regular_file(folder / name));
    EXPECT_EQ(Database::open(name, Database::Mode::kReadOnly).frames(), 3);
    EXPECT_EQ(Database::open(name).frames(), 3);
  }
  EXPECT_FALSE(fs::exists(folder / "a.db"));
  fs::current_path(was);
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lsgd::io
