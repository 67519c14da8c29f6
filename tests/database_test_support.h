// Helpers of the tests of the persistence of the detector (database_test,
// database_damage_test, database_formats_test, database_wal_test,
// database_cli_test): temporary paths, the options and runs of the synthetic
// street, a small valid database, a file's bytes, loading a file with its
// FormatError, and rewriting the stored options. Header-only.
#pragma once

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/io/database.h"
#include "detector_util.h"
#include "test_util.h"

namespace lsgd::io::database_test_support {

namespace fs = std::filesystem;
using test::expect_same_state;
using test::frame;

inline std::string temp_path(const std::string& name) {
  fs::create_directories(LSGD_TEST_TMP);
  const std::string path = std::string(LSGD_TEST_TMP) + "/database_" + test::test_file_tag() + "_" + name;
  fs::remove_all(path);
  for (const char* suffix : {"-wal", "-shm", "-journal"}) fs::remove(path + suffix);
  return path;
}

inline DetectorOptions options(const std::string& mode, const std::string& stages,
                               HistogramStorage storage = HistogramStorage::kExact) {
  DetectorOptions o;
  o.descriptor.storage = storage;
  o.search.mode = mode;
  o.search.min_gap = 20;
  parse_verification_stages(stages, o.verification);
  return o;
}

// Frames [first, last) through `detector`, each appended to `db` when given.
inline std::vector<Result> run(Detector& detector, std::int64_t first, std::int64_t last,
                               Database* db = nullptr, std::int64_t session = 0) {
  std::vector<Result> results;
  for (std::int64_t i = first; i < last; ++i) {
    results.push_back(detector.process(frame(i)));
    if (db) db->append(detector, results.back(), session, "frame" + std::to_string(i));
  }
  return results;
}

// A small valid database: 12 frames, nodes mode, temporal + geometric (every column in use).
inline const std::string& small_database() {
  static const std::string path = [] {
    // Per process: ctest runs the tests that share this file in parallel.
    const std::string p = temp_path("small_" + std::to_string(::getpid()));
    DetectorOptions o = options(kNodesSearch, "temporal,geometric");
    o.search.min_gap = 2;
    o.verification.geometric_options.max_features = 32;
    Database db = Database::create(p, o);
    Detector d(o);
    run(d, 0, 12, &db);
    return p;
  }();
  return path;
}

inline std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_bytes(const std::string& path, const std::string& bytes) {
  for (const char* suffix : {"-wal", "-shm", "-journal"}) fs::remove(path + suffix);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Opens and restores `path`; returns the FormatError's message, or "" when it loaded.
inline std::string load(const std::string& path, Detector* out = nullptr) {
  try {
    Database db = Database::open(path, Database::Mode::kReadOnly);
    Detector d(db.options());
    db.restore(d);
    if (out) {
      Detector copy(db.options());
      Database::open(path, Database::Mode::kReadOnly).restore(copy);
      expect_same_state(copy, d);
    }
    return "";
  } catch (const FormatError& e) {
    return e.what();
  }
}

// Rewrites the stored options with `edit` and re-signs the meta table (the
// checksum is the CRC-32 of "key=value\n" over the keys in order), as a file
// written by an older version that lacked some keys would look.
inline void rewrite_options(const std::string& path,
                            const std::function<void(std::string&)>& edit) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  std::map<std::string, std::string> meta;
  sqlite3_stmt* st = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "SELECT key, value FROM meta", -1, &st, nullptr), SQLITE_OK);
  while (sqlite3_step(st) == SQLITE_ROW) {
    meta[reinterpret_cast<const char*>(sqlite3_column_text(st, 0))] =
        reinterpret_cast<const char*>(sqlite3_column_text(st, 1));
  }
  sqlite3_finalize(st);
  edit(meta["options"]);
  std::string text;
  for (const auto& [key, value] : meta) {
    if (key != "checksum") text += key + "=" + value + "\n";
  }
  const auto crc = crc32(crc32(0, Z_NULL, 0), reinterpret_cast<const Bytef*>(text.data()),
                         static_cast<uInt>(text.size()));
  ASSERT_EQ(
      sqlite3_prepare_v2(db, "UPDATE meta SET value = ?1 WHERE key = 'options'", -1, &st, nullptr),
      SQLITE_OK);
  sqlite3_bind_text(st, 1, meta["options"].c_str(), -1, SQLITE_TRANSIENT);
  ASSERT_EQ(sqlite3_step(st), SQLITE_DONE);
  sqlite3_finalize(st);
  ASSERT_EQ(
      sqlite3_prepare_v2(db, "UPDATE meta SET value = ?1 WHERE key = 'checksum'", -1, &st, nullptr),
      SQLITE_OK);
  sqlite3_bind_int64(st, 1, static_cast<sqlite3_int64>(crc));
  ASSERT_EQ(sqlite3_step(st), SQLITE_DONE);
  sqlite3_finalize(st);
  sqlite3_close(db);
}

}  // namespace lsgd::io::database_test_support
