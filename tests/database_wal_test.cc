// The write-ahead log of a database (include/lsgd/io/database.h): a closed
// database holds every frame in its file, a crashed writer's log is replayed,
// a deleted database's log and a newer log beside a backup are refused, as
// are companions that are not files, a rollback journal at the path and
// hard links; damage that would lose a commit, a lost or cut log, a second
// writer.
#include "lsgd/io/database.h"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "database_test_support.h"
#include "detector_util.h"
#include "test_util.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using database_test_support::load;
using database_test_support::options;
using database_test_support::read_bytes;
using database_test_support::run;
using database_test_support::temp_path;
using database_test_support::write_bytes;
using test::frame;
using test::message_of;

// The files a writer killed after appending `frames` frames leaves behind:
// the database file as of its last checkpoint and its write-ahead log,
// copied while the writer is still open (its destructor would checkpoint).
std::string crashed_database(const std::string& name, std::int64_t frames) {
  const std::string live = temp_path(name + "_live"), copy = temp_path(name);
  DetectorOptions o = options(kNodesSearch, "temporal,geometric");
  o.search.min_gap = 2;
  o.verification.geometric_options.max_features = 32;
  Database db = Database::create(live, o);
  Detector d(o);
  run(d, 0, frames, &db);
  fs::copy_file(live, copy);
  fs::copy_file(live + "-wal", copy + "-wal");
  return copy;
}

std::int64_t be32_at(const std::string& bytes, std::size_t at) {
  return (static_cast<std::int64_t>(static_cast<unsigned char>(bytes[at])) << 24) |
         (static_cast<unsigned char>(bytes[at + 1]) << 16) |
         (static_cast<unsigned char>(bytes[at + 2]) << 8) |
         static_cast<unsigned char>(bytes[at + 3]);
}

// A writer that closes leaves every frame in the file itself: the log is
// emptied, so damage to it (or its loss) cannot lose a frame; while it runs,
// the log holds at most the frames since its last checkpoint (every 32).
TEST(DatabaseWal, AClosedDatabaseHoldsEveryFrameInItsFile) {
  const std::string path = temp_path("closed");
  DetectorOptions o = options(kExhaustiveSearch, "temporal");
  o.search.min_gap = 2;
  {
    Database db = Database::create(path, o);
    Detector d(o);
    run(d, 0, 40, &db);
    const std::string copy = temp_path("closed_file_only");
    fs::copy_file(path, copy);  // the file without its log, while the writer runs
    const Database ro = Database::open(copy, Database::Mode::kReadOnly);
    EXPECT_EQ(ro.frames(), 32);  // checkpointed at frame 32
    EXPECT_NE(ro.note().find("stopped before closing"), std::string::npos) << ro.note();
  }
  EXPECT_TRUE(!fs::exists(path + "-wal") || fs::file_size(path + "-wal") == 0);
  fs::remove(path + "-wal");
  fs::remove(path + "-shm");
  const Database ro = Database::open(path, Database::Mode::kReadOnly);
  EXPECT_EQ(ro.frames(), 40);
  EXPECT_EQ(ro.note(), "");
  EXPECT_NO_THROW(ro.verify());
}

TEST(DatabaseWal, ACrashedWritersLogIsReplayedAndSaidSo) {
  const std::string path = crashed_database("crashed", 20);
  {
    const Database ro = Database::open(path, Database::Mode::kReadOnly);
    EXPECT_EQ(ro.frames(), 20);
    EXPECT_NE(ro.note().find("stopped before closing"), std::string::npos) << ro.note();
    EXPECT_NO_THROW(ro.verify());
  }
  Database db = Database::open(path);
  EXPECT_EQ(db.frames(), 20);
  EXPECT_NE(db.note().find("replayed: 20 frames"), std::string::npos) << db.note();
}

// A writer killed, its file deleted, its log left beside it: a database
// created at that path must not take in the dead one's frames.
TEST(DatabaseWal, ANewDatabaseRefusesADeletedOnesLog) {
  const std::string path = crashed_database("deleted", 20);
  const std::string wal = read_bytes(path + "-wal");
  ASSERT_GT(wal.size(), 32u);
  fs::remove(path);
  const DetectorOptions o = options(kExhaustiveSearch, "temporal");
  const std::string m = message_of<IoError>([&] { Database::create(path, o); });
  EXPECT_NE(m.find("'" + path + "-wal' is the write-ahead log of a database that was deleted"),
            std::string::npos) << m;
  EXPECT_NE(m.find("Move '" + path + "-wal' and '" + path + "-shm' away"), std::string::npos) << m;
  EXPECT_FALSE(fs::exists(path));
  EXPECT_EQ(read_bytes(path + "-wal"), wal);
  fs::rename(path + "-wal", path + "-wal.old");
  Database db = Database::create(path, o);
  EXPECT_EQ(db.frames(), 0);
}

// A hot rollback journal (a transaction of another SQLite database cut off
// by a kill, its pages spilled): its bytes, taken while the transaction is
// open.
std::string hot_rollback_journal(const std::string& path) {
  for (const char* suffix : {"", "-journal"}) fs::remove(path + suffix);
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  const auto exec = [&](const std::string& sql) {
    EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sql;
  };
  exec("PRAGMA journal_mode=DELETE; CREATE TABLE t(x BLOB);");
  for (int i = 0; i < 50; ++i) exec("INSERT INTO t VALUES (randomblob(3000))");
  exec("PRAGMA cache_size=1; BEGIN; UPDATE t SET x = randomblob(3000);");
  for (int i = 0; i < 50; ++i) exec("INSERT INTO t VALUES (randomblob(3000))");
  const std::string journal = read_bytes(path + "-journal");
  exec("ROLLBACK");
  sqlite3_close(db);
  for (const char* suffix : {"", "-journal"}) fs::remove(path + suffix);
  return journal;
}

// A rollback journal at a database's path is never the database's own (a
// database here is in WAL mode): SQLite would roll its pages back into the
// file. A new database beside one left by a deleted database (which took
// its pages and was then "damaged"), and a database beside one, are
// refused, saying to move it away, with nothing created or changed.
TEST(DatabaseWal, ARollbackJournalAtThePathIsRefused) {
  const std::string path = temp_path("journal_new");
  const std::string journal = hot_rollback_journal(path);
  ASSERT_GT(journal.size(), 100000u);
  write_bytes(path + "-journal", journal);
  const DetectorOptions o = options(kExhaustiveSearch, "temporal");
  std::string m = message_of<IoError>([&] { Database::create(path, o); });
  EXPECT_NE(m.find("'" + path + "-journal' is the rollback journal of a database that was deleted"),
            std::string::npos) << m;
  EXPECT_NE(m.find("Move '" + path + "-journal' away"), std::string::npos) << m;
  EXPECT_FALSE(fs::exists(path));
  EXPECT_EQ(read_bytes(path + "-journal"), journal);
  fs::rename(path + "-journal", path + "-journal.old");
  {
    Database db = Database::create(path, o);
    Detector d(o);
    run(d, 0, 6, &db);
  }
  const std::string file = read_bytes(path);
  write_bytes(path + "-journal", journal);
  for (const Database::Mode mode : {Database::Mode::kReadOnly, Database::Mode::kReadWrite}) {
    m = message_of<IoError>([&] { Database::open(path, mode); });
    EXPECT_NE(m.find("'" + path + "-journal' (" + std::to_string(journal.size()) +
                     " bytes) is a rollback journal, which a database in WAL mode never has"),
              std::string::npos) << m;
    EXPECT_NE(m.find("move '" + path + "-journal' away"), std::string::npos) << m;
  }
  EXPECT_EQ(read_bytes(path), file);
  EXPECT_EQ(read_bytes(path + "-journal"), journal);
  fs::remove(path + "-journal");
  Database db = Database::open(path);
  EXPECT_EQ(db.frames(), 6);
  EXPECT_NO_THROW(db.verify());
}

// A file restored from an older backup beside its newer log: refused, on
// one line, saying to move the log away; moved away, the backup opens.
TEST(DatabaseWal, ABackupBesideANewerLogSaysToMoveTheLogAway) {
  const std::string newer = crashed_database("newer", 45);  // frames 32 .. 44 in its log
  const std::string older = crashed_database("older", 3);  // its file alone: no frame yet
  const std::string path = temp_path("restored");
  fs::copy_file(older, path);
  fs::copy_file(newer + "-wal", path + "-wal");
  std::string m;
  try {
    Database db = Database::open(path, Database::Mode::kReadOnly);
    db.verify();
  } catch (const Error& e) {
    m = e.what();
  }
  ASSERT_FALSE(m.empty()) << "the newer log was replayed over the backup without a word";
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  EXPECT_LT(m.size(), 800u) << m;
  EXPECT_NE(m.find("move '" + path + "-wal'"), std::string::npos) << m;
  fs::rename(path + "-wal", path + "-wal.newer");
  fs::remove(path + "-shm");
  const Database db = Database::open(path, Database::Mode::kReadOnly);
  EXPECT_EQ(db.frames(), 0);
  EXPECT_NO_THROW(db.verify());
}

// The other way round: a log copied before its file (a backup tool that
// copies FILE-wal first, while the writer runs on). SQLite replays the old
// log's pages over the newer file without damage: 130 frames would read as
// 45, and the next writer would make it so. Refused by the checkpoint count
// each log carries; readers and writers alike, nothing changed.
TEST(DatabaseWal, ALogOlderThanItsFileIsRefused) {
  const std::string live = temp_path("older_log_live"), path = temp_path("older_log");
  DetectorOptions o = options(kExhaustiveSearch, "temporal");
  o.search.min_gap = 2;
  {
    Database db = Database::create(live, o);
    Detector d(o);
    run(d, 0, 45, &db);  // frames 32 .. 44 in the log
    fs::copy_file(live + "-wal", path + "-wal");
    run(d, 45, 130, &db);  // checkpoints at 64 and 96 (and 128)
    fs::copy_file(live, path);
  }
  const std::string before = read_bytes(path) + read_bytes(path + "-wal");
  for (const auto mode : {Database::Mode::kReadOnly, Database::Mode::kReadWrite}) {
    const std::string m = message_of<IoError>([&] { Database::open(path, mode); });
    EXPECT_NE(m.find("'" + path + "-wal' is older than the file"), std::string::npos) << m;
    EXPECT_NE(m.find("move '" + path + "-wal'"), std::string::npos) << m;
  }
  EXPECT_EQ(read_bytes(path) + read_bytes(path + "-wal"), before);
  fs::rename(path + "-wal", path + "-wal.older");
  fs::remove(path + "-shm");
  EXPECT_GE(Database::open(path, Database::Mode::kReadOnly).frames(), 128);
  // Only a checkpoint that moved something written counts: a writer that
  // appends nothing leaves the count as it was (a re-run with nothing to do
  // changes nothing in the database).
  const auto checkpoints = [&] {
    sqlite3* db = nullptr;
    std::string value;
    if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
      sqlite3_stmt* s = nullptr;
      sqlite3_prepare_v2(db, "SELECT value FROM meta WHERE key = 'checkpoints'", -1, &s, nullptr);
      if (s != nullptr && sqlite3_step(s) == SQLITE_ROW) value = reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
      sqlite3_finalize(s);
    }
    sqlite3_close(db);
    return value;
  };
  const std::string closed = checkpoints();
  EXPECT_FALSE(closed.empty());
  { Database db = Database::open(path); }
  EXPECT_EQ(checkpoints(), closed);
  {
    Database db = Database::open(path);
    Detector d(o);
    db.restore(d);
    db.append(d, d.process(frame(130)), 0);
  }
  EXPECT_EQ(checkpoints(), std::to_string(std::stoll(closed) + 1));
}

// The log's companions must be files of their own: a folder, a FIFO or a
// link where SQLite keeps them is refused, naming it, before anything is
// created or read.
TEST(DatabaseWal, CompanionsThatAreNotFilesAreRefusedByName) {
  const DetectorOptions o = options(kExhaustiveSearch, "temporal");
  const std::string path = temp_path("companions");
  { Database db = Database::create(path, o); }
  const std::string other = temp_path("companions_target");
  write_bytes(other, "");
  struct Case {
    const char* suffix;
    const char* kind;
    std::function<void(const std::string&)> make;
  };
  const std::vector<Case> cases = {
      {"-wal", "a directory", [](const std::string& p) { fs::create_directory(p); }},
      {"-wal", "a FIFO", [](const std::string& p) { ASSERT_EQ(::mkfifo(p.c_str(), 0600), 0); }},
      {"-wal", "a symbolic link", [&](const std::string& p) { fs::create_symlink(other, p); }},
      {"-shm", "a directory", [](const std::string& p) { fs::create_directory(p); }},
      {"-journal", "a directory", [](const std::string& p) { fs::create_directory(p); }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.suffix) + " " + c.kind);
    const std::string companion = path + c.suffix;
    fs::remove_all(companion);
    c.make(companion);
    for (const Database::Mode mode : {Database::Mode::kReadOnly, Database::Mode::kReadWrite}) {
      const std::string m = message_of<IoError>([&] { Database::open(path, mode); });
      EXPECT_NE(m.find("'" + companion + "' is " + c.kind), std::string::npos) << m;
      EXPECT_NE(m.find("move it away"), std::string::npos) << m;
    }
    const std::string fresh = temp_path("companions_fresh");
    fs::remove_all(fresh + c.suffix);
    c.make(fresh + c.suffix);
    const std::string m = message_of<IoError>([&] { Database::create(fresh, o); });
    EXPECT_NE(m.find("'" + fresh + c.suffix + "' is " + c.kind), std::string::npos) << m;
    EXPECT_FALSE(fs::exists(fresh));
    fs::remove_all(fresh + c.suffix);
    fs::remove_all(companion);
  }
  Database db = Database::open(path);
  EXPECT_EQ(db.frames(), 0);
}

// Two names of one file have two logs: a writer through either could have
// its frames undone through the other, so writers refuse a linked file.
TEST(DatabaseWal, AWriterRefusesAFileWithHardLinks) {
  const DetectorOptions o = options(kExhaustiveSearch, "temporal");
  const std::string path = temp_path("linked");
  {
    Database db = Database::create(path, o);
    Detector d(o);
    for (int i = 0; i < 5; ++i) db.append(d, d.process(frame(i)), 0);
  }
  const std::string second = temp_path("linked_second");
  fs::create_hard_link(path, second);
  for (const std::string& name : {path, second}) {
    const std::string m = message_of<IoError>([&] { Database::open(name); });
    EXPECT_NE(m.find("has 2 hard links"), std::string::npos) << m;
    EXPECT_EQ(Database::open(name, Database::Mode::kReadOnly).frames(), 5);
  }
  fs::remove(second);
  EXPECT_EQ(Database::open(path).frames(), 5);
}

// SQLite would replay a damaged log up to the damage and drop every commit
// after it without a word: lsgd reads the log first and refuses, changing
// nothing, when a commit would be lost.
TEST(DatabaseWal, DamageThatWouldLoseACommitIsAFormatError) {
  const std::string clean = crashed_database("wal_clean", 20);
  const std::string wal = read_bytes(clean + "-wal");
  ASSERT_GT(wal.size(), 32u);
  const std::size_t page = static_cast<std::size_t>(be32_at(wal, 8));
  const std::size_t frame_bytes = 24 + page;
  const std::size_t frames = (wal.size() - 32) / frame_bytes;
  std::vector<std::size_t> commits;  // frame indices that end a transaction
  for (std::size_t f = 0; f < frames; ++f) {
    if (be32_at(wal, 32 + f * frame_bytes + 4) != 0) commits.push_back(f);
  }
  ASSERT_GE(commits.size(), 10u);
  const std::string path = temp_path("wal_damaged");
  int detected = 0;
  // Bytes of frames before the second-to-last commit: page number, commit
  // size, salts, checksums, page data.
  for (std::size_t f = 0; f <= commits[commits.size() - 2]; f += 3) {
    for (const std::size_t offset : {std::size_t{0}, std::size_t{5}, std::size_t{9},
                                     std::size_t{17}, std::size_t{24}, std::size_t{24} + page / 2,
                                     frame_bytes - 1}) {
      std::string bad = wal;
      const std::size_t at = 32 + f * frame_bytes + offset;
      bad[at] = static_cast<char>(bad[at] ^ 0x10);
      write_bytes(path, read_bytes(clean));
      write_bytes(path + "-wal", bad);
      const std::string before = read_bytes(path) + read_bytes(path + "-wal");
      const std::string m = load(path);
      const std::string mw = [&] {
        try {
          Database::open(path);
          return std::string();
        } catch (const FormatError& e) {
          return std::string(e.what());
        }
      }();
      EXPECT_NE(m.find("write-ahead log"), std::string::npos) << "byte " << at << ": " << m;
      EXPECT_NE(mw.find("damaged at byte"), std::string::npos) << "byte " << at << ": " << mw;
      EXPECT_EQ(read_bytes(path) + read_bytes(path + "-wal"), before) << "byte " << at;
      detected += !m.empty() && !mw.empty();
    }
  }
  EXPECT_GT(detected, 30);
  // A damaged header hides every frame.
  std::string bad = wal;
  bad[20] = static_cast<char>(bad[20] ^ 1);
  write_bytes(path, read_bytes(clean));
  write_bytes(path + "-wal", bad);
  EXPECT_NE(load(path).find("damaged header"), std::string::npos);
}

// What the log alone cannot show: the log deleted, or cut (its last
// transactions look like ones never committed). The database opens as of
// what remains, and says that its last writer was stopped; `lsgd run` also
// compares with the rows of its CSV (tests/run_cli_test.cc).
TEST(DatabaseWal, ALostOrCutLogOpensWhatRemainsAndSaysSo) {
  const std::string path = crashed_database("wal_lost", 20);
  const std::string wal = read_bytes(path + "-wal");
  const std::string file = read_bytes(path);
  fs::remove(path + "-wal");
  {
    Database db = Database::open(path);
    EXPECT_EQ(db.frames(), 0);  // its last checkpoint, at open
    EXPECT_NE(db.note().find("left no write-ahead log"), std::string::npos) << db.note();
  }
  write_bytes(path, file);
  write_bytes(path + "-wal", wal.substr(0, wal.size() / 2));
  Database db = Database::open(path);
  EXPECT_GT(db.frames(), 0);
  EXPECT_LT(db.frames(), 20);
  EXPECT_NE(db.note().find("stopped before closing"), std::string::npos) << db.note();
  Detector d(db.options());
  EXPECT_NO_THROW(db.restore(d));
}

// One writer at a time, in this process or another; readers beside it.
TEST(DatabaseWal, ASecondWriterIsToldAnotherProcessIsWriting) {
  const std::string path = temp_path("two_writers");
  DetectorOptions o = options(kExhaustiveSearch, "none");
  Database first = Database::create(path, o);
  const auto refusal = [&] {
    try {
      Database::open(path);
      return std::string();
    } catch (const IoError& e) {
      return std::string(e.what());
    }
  };
  const std::string here = refusal();
  EXPECT_NE(here.find("is already open for writing in this process"), std::string::npos) << here;
  // Another process: exit status 0 when it was told so.
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const std::string there = refusal();
    ::_exit(there.find("another process is writing to it") != std::string::npos ? 0 : 1);
  }
  int status = -1;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  {
    // Closed, it opens again in this process.
    const std::string again = temp_path("closed_writer");
    { Database closed = Database::create(again, o); }
    EXPECT_NO_THROW(Database::open(again));
  }
  Detector d(o);
  run(d, 0, 5, &first);
  const Database reader = Database::open(path, Database::Mode::kReadOnly);
  EXPECT_EQ(reader.frames(), 5);
  EXPECT_NE(reader.note().find("a writer has it open"), std::string::npos) << reader.note();
  EXPECT_NO_THROW(reader.verify());
}

}  // namespace
}  // namespace lsgd::io
