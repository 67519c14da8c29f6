// The file a Database has open (src/io/database_locks.cc): a second Database
// of the file in the writer's process (a reader, a refused writer, one
// refused for a rollback journal) leaves the writer's SQLite locks in place,
// so another program's connection never takes itself for the last one and
// deletes the log under the writer; descriptors are reused, not piled up. A
// file replaced or deleted under its writer is said, not written blindly.
#include "lsgd/io/database.h"

#include <gtest/gtest.h>
#include <dirent.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/inotify.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>

#include "lsgd/error.h"
#include "database_test_support.h"
#include "test_util.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using database_test_support::options;
using database_test_support::run;
using database_test_support::temp_path;
using database_test_support::write_bytes;
using test::message_of;

// True when this process holds a POSIX (fcntl) lock on `path`, as another
// process sees it: F_GETLK from a child, whose exit status says.
bool posix_locked_here(const std::string& path) {
  const pid_t self = ::getpid();
  const pid_t child = ::fork();
  if (child == 0) {
    const int fd = ::open(path.c_str(), O_RDWR);
    struct flock probe {};
    probe.l_type = F_WRLCK;
    probe.l_whence = SEEK_SET;  // l_start 0, l_len 0: the whole file
    if (fd < 0 || ::fcntl(fd, F_GETLK, &probe) != 0) ::_exit(2);
    ::_exit(probe.l_type != F_UNLCK && probe.l_pid == self ? 0 : 1);
  }
  int status = -1;
  if (child < 0 || ::waitpid(child, &status, 0) != child || !WIFEXITED(status)) return false;
  EXPECT_NE(WEXITSTATUS(status), 2) << "the probe could not read the locks of " << path;
  return WEXITSTATUS(status) == 0;
}

std::int64_t open_descriptors() {
  std::int64_t n = 0;
  for (auto it = fs::directory_iterator("/proc/self/fd"); it != fs::directory_iterator(); ++it) ++n;
  return n;
}

// Exit status 0 when another process can open `path` for writing (the
// writer's flock is released).
bool writable_elsewhere(const std::string& path) {
  const pid_t child = ::fork();
  if (child == 0) {
    try {
      Database::open(path);
      ::_exit(0);
    } catch (const std::exception&) {
      ::_exit(1);
    }
  }
  int status = -1;
  return child > 0 && ::waitpid(child, &status, 0) == child && WIFEXITED(status) &&
         WEXITSTATUS(status) == 0;
}

TEST(DatabaseLocks, AnotherDatabaseOfTheFileLeavesTheWritersLocks) {
  const std::string path = temp_path("locks_kept");
  const DetectorOptions o = options(kExhaustiveSearch, "none");
  std::optional<Database> writer(Database::create(path, o));
  Detector d(o);
  run(d, 0, 3, &*writer);
  ASSERT_TRUE(posix_locked_here(path)) << "SQLite's lock on " << path;
  {
    const Database reader = Database::open(path, Database::Mode::kReadOnly);
    EXPECT_EQ(reader.frames(), 3);
  }
  EXPECT_TRUE(posix_locked_here(path)) << "after a reader of the file closed";
  EXPECT_THROW(Database::open(path), IoError);  // a second writer in this process
  EXPECT_TRUE(posix_locked_here(path)) << "after a refused second writer";
  // A reader refused for a rollback journal, whose header it read.
  write_bytes(path + "-journal", std::string(512, 'j'));
  const std::string refused = message_of<IoError>([&] { Database::open(path, Database::Mode::kReadOnly); });
  EXPECT_NE(refused.find("rollback journal"), std::string::npos) << refused;
  fs::remove(path + "-journal");
  EXPECT_TRUE(posix_locked_here(path)) << "after a reader refused for a rollback journal";
  // The descriptors closed Databases leave are reused, not piled up.
  const std::int64_t descriptors = open_descriptors();
  for (int i = 0; i < 5; ++i) EXPECT_EQ(Database::open(path, Database::Mode::kReadOnly).frames(), 3);
  EXPECT_EQ(open_descriptors(), descriptors);
  // The writer stays a writer: its frames go on, and another process cannot write.
  run(d, 3, 6, &*writer);
  EXPECT_FALSE(writable_elsewhere(path));
  // The last Database of the file gone: its descriptors are closed and its lock released.
  writer.reset();
  EXPECT_LT(open_descriptors(), descriptors);
  EXPECT_FALSE(posix_locked_here(path));
  EXPECT_TRUE(writable_elsewhere(path));
  EXPECT_EQ(Database::open(path, Database::Mode::kReadOnly).frames(), 6);
}

// Opening a file whose log holds a stopped writer's frames reads the log's
// meta through connections of its own (check_log_belongs) and closes them:
// SQLite's unix VFS keeps their descriptors open while another connection
// of the file in the process holds a lock, so a reader open meanwhile keeps
// its lock.
TEST(DatabaseLocks, ReadingAStoppedWritersLogLeavesAnotherReadersLock) {
  const std::string path = temp_path("locks_log");
  const DetectorOptions o = options(kExhaustiveSearch, "none");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // a writer stopped before closing: its frames in the log
    Database writer = Database::create(path, o);
    Detector d(o);
    run(d, 0, 5, &writer);
    ::_exit(0);
  }
  int status = -1;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  ASSERT_GT(fs::file_size(path + "-wal"), 0u);
  const Database first = Database::open(path, Database::Mode::kReadOnly);
  ASSERT_TRUE(posix_locked_here(path));
  EXPECT_EQ(Database::open(path, Database::Mode::kReadOnly).frames(), 5);
  EXPECT_TRUE(posix_locked_here(path)) << "after a second reader checked the log and closed";
  EXPECT_EQ(first.frames(), 5);
}

// End to end: a writer (a child process) opens and closes a reader of its
// file, another program's connection reads the file and closes, the writer
// commits more frames and is killed. Every committed frame is there: the
// other connection did not delete the log under the writer.
TEST(DatabaseLocks, FramesCommittedBeforeAKillSurviveAnotherConnection) {
  const std::string path = temp_path("locks_kill");
  const DetectorOptions o = options(kExhaustiveSearch, "none");
  { Database created = Database::create(path, o); }
  int to_parent[2], to_child[2];
  ASSERT_EQ(::pipe(to_parent), 0);
  ASSERT_EQ(::pipe(to_child), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::alarm(60);  // bounded, whatever the parent does
    Database writer = Database::open(path);
    Detector d(o);
    run(d, 0, 4, &writer);
    { const Database reader = Database::open(path, Database::Mode::kReadOnly); }
    run(d, 4, 8, &writer);
    char byte = 8;
    if (::write(to_parent[1], &byte, 1) != 1 || ::read(to_child[0], &byte, 1) != 1) ::_exit(1);
    run(d, 8, 16, &writer);  // committed: synchronous=FULL, no checkpoint before frame 32
    byte = 16;
    if (::write(to_parent[1], &byte, 1) != 1) ::_exit(1);
    ::pause();
    ::_exit(0);
  }
  char byte = 0;
  ASSERT_EQ(::read(to_parent[0], &byte, 1), 1);
  ASSERT_EQ(byte, 8);
  {  // another program's read (the sqlite3 shell, Python's sqlite3)
    sqlite3* other = nullptr;
    ASSERT_EQ(sqlite3_open_v2(path.c_str(), &other, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
    sqlite3_busy_timeout(other, 5000);
    EXPECT_EQ(sqlite3_exec(other, "SELECT count(*) FROM frames", nullptr, nullptr, nullptr), SQLITE_OK);
    EXPECT_EQ(sqlite3_close(other), SQLITE_OK);
  }
  EXPECT_TRUE(fs::exists(path + "-wal")) << "the writer's log was deleted under it";
  ASSERT_EQ(::write(to_child[1], &byte, 1), 1);
  ASSERT_EQ(::read(to_parent[0], &byte, 1), 1);
  ASSERT_EQ(byte, 16);
  ::kill(child, SIGKILL);
  int status = -1;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  for (const int fd : {to_parent[0], to_parent[1], to_child[0], to_child[1]}) ::close(fd);
  const Database after = Database::open(path, Database::Mode::kReadOnly);
  EXPECT_EQ(after.frames(), 16) << after.note();
}

// A database file replaced (mv other.db FILE) or deleted while a writer has
// it open: the writer's frames go to a file no name reaches. Said at the
// next checkpoint (every 32 frames), before save_index() and forget() write,
// and at close(), naming the file; the file now at the path is not written.
TEST(DatabaseLocks, AFileReplacedUnderTheWriterIsAnIoError) {
  const std::string path = temp_path("replaced"), other = temp_path("replacing");
  const DetectorOptions o = options(kExhaustiveSearch, "none");
  Database writer = Database::create(path, o);
  Detector d(o);
  run(d, 0, 10, &writer);
  { Database created = Database::create(other, o); }
  ASSERT_EQ(::rename(other.c_str(), path.c_str()), 0);
  const auto replaced = [&](const std::string& message) {
    for (const std::string& part : {"database " + path + ": was replaced while this writer had it open",
                                   std::string("run again to store the frames")}) {
      EXPECT_NE(message.find(part), std::string::npos) << part << "\n" << message;
    }
  };
  replaced(message_of<IoError>([&] { writer.save_index(d); }));
  replaced(message_of<IoError>([&] { writer.forget(0, 0); }));
  run(d, 10, 31, &writer);  // no checkpoint yet
  // The 32nd frame is committed, then its checkpoint finds the file replaced.
  replaced(message_of<IoError>([&] { run(d, 31, 32, &writer); }));
  replaced(message_of<IoError>([&] { writer.close(); }));
  EXPECT_NO_THROW(writer.close());  // closed: nothing
  EXPECT_EQ(writer.frames(), 32);
  EXPECT_NE(message_of<InvalidArgument>([&] { writer.frame_ids(); }).find("is closed"), std::string::npos);
  EXPECT_EQ(Database::open(path, Database::Mode::kReadOnly).frames(), 0);  // the other one, as it was
  // Deleted under the writer.
  const std::string deleted = temp_path("deleted");
  Database gone = Database::create(deleted, o);
  ASSERT_EQ(::unlink(deleted.c_str()), 0);
  const std::string message = message_of<IoError>([&] { gone.close(); });
  EXPECT_NE(message.find("was deleted or moved away while this writer had it open"), std::string::npos)
      << message;
  // A file left in place closes without a word.
  const std::string kept = temp_path("kept");
  Database fine = Database::create(kept, o);
  EXPECT_NO_THROW(fine.close());
  EXPECT_NO_THROW(Database::open(kept));
}

// Two creators of one new path (two `lsgd run --database NEW.db` started
// together): the second to publish said "already exists" of a file that did
// not exist when it began. It says another process created it, keeps nothing
// of its own and leaves the other's file as it was. The other creator here is
// a thread woken (inotify) when this creation's temporary file appears; when
// it comes too late the creation wins and the race is tried again.
TEST(Database, TheLoserOfTwoCreatorsOfOnePathSaysAnotherProcessCreatedIt) {
  const std::string dir = temp_path("race");
  fs::create_directories(dir);
  const std::string path = dir + "/map.db";
  const std::string tmp_name = "map.db.tmp-" + std::to_string(::getpid());
  const DetectorOptions o = options(kExhaustiveSearch, "temporal");
  bool raced = false;
  for (int attempt = 0; attempt < 20 && !raced; ++attempt) {
    for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(path + suffix);
    const int watch = ::inotify_init1(IN_CLOEXEC);
    ASSERT_GE(watch, 0) << std::strerror(errno);
    ASSERT_GE(::inotify_add_watch(watch, dir.c_str(), IN_CREATE), 0) << std::strerror(errno);
    std::thread other([&] {
      alignas(inotify_event) char buffer[4096];
      for (;;) {
        pollfd p{watch, POLLIN, 0};
        if (::poll(&p, 1, 10000) <= 0) return;
        const ssize_t n = ::read(watch, buffer, sizeof buffer);
        for (ssize_t at = 0; at < n;) {
          const auto* e = reinterpret_cast<const inotify_event*>(buffer + at);
          if (e->len > 0 && tmp_name == e->name) {
            const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
            if (fd >= 0) {
              EXPECT_EQ(::write(fd, "the other's", 11), 11);
              ::close(fd);
            }
            return;
          }
          at += static_cast<ssize_t>(sizeof(inotify_event) + e->len);
        }
      }
    });
    std::string message;
    try {
      Database db = Database::create(path, o);  // the other thread came too late
    } catch (const IoError& e) {
      message = e.what();
    }
    other.join();
    ::close(watch);
    if (message.empty()) continue;
    raced = true;
    EXPECT_NE(message.find("was created by another process while this one created it"), std::string::npos)
        << message;
    EXPECT_NE(message.find(path), std::string::npos) << message;
    EXPECT_EQ(database_test_support::read_bytes(path), "the other's");
    for (const auto& entry : fs::directory_iterator(dir)) {
      EXPECT_EQ(entry.path().string().find(".tmp-"), std::string::npos) << entry.path();
    }
  }
  EXPECT_TRUE(raced) << "the other creator never came between the check and the publication in 20 tries";
}

}  // namespace
}  // namespace lsgd::io
