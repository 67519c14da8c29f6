// Damaged database files (include/lsgd/io/database.h): not SQLite or empty,
// truncated at many lengths, bytes flipped anywhere, edited rows and meta,
// a huge frame size in the meta table.
#include "lsgd/io/database.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "database_test_support.h"
#include "detector_util.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using database_test_support::load;
using database_test_support::read_bytes;
using database_test_support::rewrite_options;
using database_test_support::small_database;
using database_test_support::temp_path;
using database_test_support::write_bytes;
using test::expect_same_state;

TEST(DatabaseDamage, NotSqliteOrEmpty) {
  const std::string path = temp_path("text");
  write_bytes(path, "frame,image,loop_frame\n0,a.png,-1\n");
  std::string m = load(path);
  EXPECT_NE(m.find(path), std::string::npos) << m;
  write_bytes(path, "");
  m = load(path);
  EXPECT_NE(m.find("not an lsgd database"), std::string::npos) << m;
  EXPECT_NE(m.find(path), std::string::npos) << m;
  EXPECT_EQ(fs::file_size(path), 0u);  // opening did not turn it into a database
  // An SQLite file of another program.
  fs::remove(path);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_exec(db, "CREATE TABLE t(x); INSERT INTO t VALUES(1);", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  m = load(path);
  EXPECT_NE(m.find("not an lsgd database"), std::string::npos) << m;
}

TEST(DatabaseDamage, EveryTruncationIsAFormatError) {
  const std::string good = read_bytes(small_database());
  ASSERT_EQ(load(small_database()), "");
  const std::string path = temp_path("truncated");
  std::vector<std::size_t> lengths;
  for (std::size_t n = 0; n <= 128; ++n) lengths.push_back(n);  // the 100-byte header and a bit
  for (std::size_t n = 129; n < good.size(); n += 97) lengths.push_back(n);
  for (std::size_t page = 4096; page < good.size(); page += 4096) {  // page boundaries
    lengths.push_back(page);
    lengths.push_back(page - 1);
  }
  lengths.push_back(good.size() - 1);
  for (const std::size_t n : lengths) {
    write_bytes(path, good.substr(0, n));
    const std::string m = load(path);
    ASSERT_NE(m.find(path), std::string::npos) << "truncated to " << n << " bytes: '" << m << "'";
  }
}

TEST(DatabaseDamage, FlippedBytesAnywhereAreDetectedOrHarmless) {
  const std::string good = read_bytes(small_database());
  Detector original(Database::open(small_database()).options());
  Database::open(small_database()).restore(original);
  const std::string path = temp_path("flipped");
  int errors = 0, harmless = 0;
  for (std::size_t at = 0; at < good.size(); at += 61) {
    std::string bad = good;
    bad[at] = static_cast<char>(bad[at] ^ 0x5A);
    write_bytes(path, bad);
    Detector loaded(original.options());
    const std::string m = [&]() -> std::string {
      try {
        Database db = Database::open(path, Database::Mode::kReadOnly);
        db.restore(loaded);
        return "";
      } catch (const FormatError& e) {
        return e.what();
      }
    }();
    if (m.empty()) {
      // Not detected: then it must not have changed anything the detector uses.
      SCOPED_TRACE("byte " + std::to_string(at) + " flipped, no error");
      expect_same_state(loaded, original);
      ++harmless;
    } else {
      ASSERT_NE(m.find(path), std::string::npos) << m;
      ++errors;
    }
  }
  EXPECT_GT(errors, 10);
}

// Edits the database with SQL, then expects a FormatError containing `expected`.
void expect_edit_detected(const std::string& sql, const std::string& expected) {
  const std::string path = temp_path("edited");
  fs::copy_file(small_database(), path);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  char* error = nullptr;
  ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error), SQLITE_OK) << error;
  sqlite3_close(db);
  const std::string m = load(path);
  EXPECT_NE(m.find(path), std::string::npos) << sql << ": " << m;
  EXPECT_NE(m.find(expected), std::string::npos) << sql << ": " << m;
}

// Flips one byte of a blob in place (same size), then expects a FormatError.
void expect_flip_detected(const char* column, std::int64_t row, int offset,
                          const std::string& expected) {
  const std::string path = temp_path("edited");
  fs::copy_file(small_database(), path);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_blob* blob = nullptr;
  ASSERT_EQ(sqlite3_blob_open(db, "main", "frames", column, row, 1, &blob), SQLITE_OK);
  ASSERT_GT(sqlite3_blob_bytes(blob), offset);
  unsigned char byte = 0;
  ASSERT_EQ(sqlite3_blob_read(blob, &byte, 1, offset), SQLITE_OK);
  byte ^= 0x01;
  ASSERT_EQ(sqlite3_blob_write(blob, &byte, 1, offset), SQLITE_OK);
  sqlite3_blob_close(blob);
  sqlite3_close(db);
  const std::string m = load(path);
  EXPECT_NE(m.find(path), std::string::npos) << column << ": " << m;
  EXPECT_NE(m.find(expected), std::string::npos) << column << ": " << m;
}

// A frame size claimed by the meta table is bounded before any memory is
// committed for it (the checksum is valid: a file written that way).
TEST(DatabaseDamage, HugeFrameSizeInMetaIsAFormatError) {
  const std::string path = temp_path("huge_meta");
  fs::copy_file(small_database(), path);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_exec(db, "UPDATE meta SET value = 1048576 WHERE key IN ('width', 'height')", nullptr,
               nullptr, nullptr);
  sqlite3_close(db);
  rewrite_options(path, [](std::string&) {});  // re-signs the meta table
  const std::string m = load(path);
  EXPECT_NE(m.find("meta width = 1048576 is out of range"), std::string::npos) << m;
}

TEST(DatabaseDamage, EditedRowsAndMeta) {
  expect_edit_detected("UPDATE frames SET histogram = zeroblob(10) WHERE id = 3",
                       "frame 3: histogram blob has 10 bytes");
  expect_edit_detected("UPDATE frames SET pixels = zeroblob(4) WHERE id = 0", "pixels blob");
  expect_flip_detected("histogram", 5, 100, "frame 5: checksum");
  expect_flip_detected("pixels", 7, 0, "frame 7: checksum");
  expect_flip_detected("state", 9, 3, "frame 9: checksum");
  expect_flip_detected("state", 10, 40, "frame 10: checksum");
  expect_edit_detected("UPDATE frames SET state = NULL WHERE id = 11", "frame 11: checksum");
  expect_edit_detected("UPDATE frames SET state = x'00' WHERE id = 8", "frame 8: checksum");
  expect_edit_detected("UPDATE frames SET state = 7 WHERE id = 8", "frame 8: state is not a blob");
  expect_edit_detected("UPDATE frames SET features = x'00' WHERE id = 2",
                       "frame 2: has both a state and the place, features or loop columns");
  expect_edit_detected("UPDATE frames SET node = node + 7 WHERE id = 4", "frame 4");
  expect_edit_detected("UPDATE frames SET session = 3 WHERE id = 4", "frame 4: checksum");
  expect_edit_detected("UPDATE frames SET name = 'x' WHERE id = 4", "frame 4: checksum");
  expect_edit_detected("DELETE FROM frames WHERE id = 6", "frame ids are not 0 .. 10");
  expect_edit_detected("UPDATE meta SET value = 'x1' WHERE key = 'format_version'",
                       "format_version 'x1' is not an integer");
  expect_edit_detected("UPDATE meta SET value = 6 WHERE key = 'format_version'",
                       "format version 6 is newer");
  expect_edit_detected("UPDATE frames SET loop_inliers = 'x' WHERE id = 5", "loop_inliers");
  expect_edit_detected("UPDATE meta SET value = 0 WHERE key = 'format_version'",
                       "unknown format version 0");
  expect_edit_detected(
      "UPDATE meta SET value = replace(value, 'min_gap: 2', 'min_gap: 3') WHERE key = 'options'",
      "meta checksum");
  expect_edit_detected("UPDATE meta SET value = 'garbage: [' WHERE key = 'options'",
                       "meta checksum");
  expect_edit_detected("DELETE FROM meta WHERE key = 'width'", "meta has no width");
  expect_edit_detected("DROP TABLE frames", "not an lsgd database");
}

}  // namespace
}  // namespace lsgd::io
