// Database files written by older versions (include/lsgd/io/database.h):
// options without the keys added since keep their behaviour; formats 1, 2
// and 3 are read, and upgraded in place when opened for writing.
#include "lsgd/io/database.h"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numeric>
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
using database_test_support::rewrite_options;
using database_test_support::run;
using database_test_support::small_database;
using database_test_support::temp_path;
using test::expect_same_state;
using test::frame;
using test::message_of;

void erase(std::string& text, const std::string& what) {
  const auto at = text.find(what);
  ASSERT_NE(at, std::string::npos) << what << " not in:\n" << text;
  text.erase(at, what.size());
}

// Keys added after a file was written take the value of the version that
// wrote it: no `descriptor` section means exact storage, no
// verification.temporal.long_frames means the single 16-frame sequence, no
// segmentation.working_side frames segmented at their own size.
TEST(Database, OptionsOfAnOlderVersionKeepTheirBehaviour) {
  const std::string path = temp_path("older");
  fs::copy_file(small_database(), path);
  rewrite_options(path, [](std::string& yaml) {
    erase(yaml, "    long_frames: 48  # frames\n");
    erase(yaml, "  working_side: 240  # pixels\n");
    const auto from = yaml.find("descriptor:\n");
    ASSERT_NE(from, std::string::npos);
    yaml.erase(from, yaml.find("similarity:") - from);
  });
  const std::string damage = load(path);
  ASSERT_EQ(damage, "");
  const Database db = Database::open(path, Database::Mode::kReadOnly);
  EXPECT_EQ(db.options().verification.temporal_options.long_frames, 0);
  EXPECT_EQ(db.options().descriptor.storage, HistogramStorage::kExact);
  EXPECT_EQ(db.options().segmentation.working_side, 0);  // frames segmented at their own size
  // Today's defaults differ from such a file: resuming says which option.
  DetectorOptions today = db.options();
  today.verification.temporal_options.long_frames = 48;
  EXPECT_NE(message_of<InvalidArgument>([&] {
              db.check_compatible(today);
            }).find("verification.temporal.long_frames = 48 differs from the stored 0"),
            std::string::npos);
  Detector resumed(db.options());
  EXPECT_NO_THROW(db.restore(resumed));
  EXPECT_EQ(resumed.size(), 12);
}

// Formats 1 to 3 kept the components' state in columns of their own: the
// version-1 records of the state column of `db`'s 12 rows, moved there.
void move_state_into_columns(sqlite3* db) {
  for (int id = 0; id < 12; ++id) {
    sqlite3_stmt* st = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db, ("SELECT state FROM frames WHERE id = " + std::to_string(id)).c_str(),
                                 -1, &st, nullptr),
              SQLITE_OK);
    EXPECT_EQ(sqlite3_step(st), SQLITE_ROW);
    const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(st, 0));
    const std::vector<StateRecord> records =
        decode_records(blob, static_cast<std::size_t>(sqlite3_column_bytes(st, 0)));
    sqlite3_finalize(st);
    EXPECT_EQ(sqlite3_prepare_v2(db,
                                 "UPDATE frames SET place = ?1, features = ?2, loop = ?3, "
                                 "loop_inliers = ?4, state = NULL WHERE id = ?5",
                                 -1, &st, nullptr),
              SQLITE_OK);
    for (const StateRecord& r : records) {
      StateReader in(r.bytes.data(), r.bytes.size(), r.component);
      if (r.component == kTemporalStage) sqlite3_bind_int64(st, 1, in.get_i64());
      if (r.component == kGeometricStage) {
        sqlite3_bind_blob(st, 2, r.bytes.data(), static_cast<int>(r.bytes.size()), SQLITE_TRANSIENT);
        if (r.bytes.empty()) sqlite3_bind_zeroblob(st, 2, 0);
      }
      if (r.component == "decision") {
        sqlite3_bind_int64(st, 3, in.get_i64());
        sqlite3_bind_double(st, 4, in.get_f64());
      }
    }
    sqlite3_bind_int64(st, 5, id);
    EXPECT_EQ(sqlite3_step(st), SQLITE_DONE);
    sqlite3_finalize(st);
  }
}

// The SQL that sets each of the 12 rows' checksum as format `format`
// computed it (database.cc row_checksum).
std::string older_checksums(sqlite3* db, int format) {
  std::string sql;
  for (int id = 0; id < 12; ++id) {
    sqlite3_stmt* st = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db,
                                 ("SELECT id, session, node, place, loop, loop_inliers, name, "
                                  "histogram, pixels, features, frame FROM frames WHERE id = " +
                                  std::to_string(id))
                                     .c_str(),
                                 -1, &st, nullptr),
              SQLITE_OK);
    EXPECT_EQ(sqlite3_step(st), SQLITE_ROW);
    uLong crc = crc32(0, Z_NULL, 0);
    const auto add_int = [&](std::int64_t v) {
      unsigned char b[8];
      for (int i = 0; i < 8; ++i) b[i] = static_cast<unsigned char>(static_cast<std::uint64_t>(v) >> (8 * i));
      crc = crc32(crc, b, 8);
    };
    for (int c = 0; c < 4; ++c) {
      add_int(sqlite3_column_type(st, c) == SQLITE_NULL ? std::numeric_limits<std::int64_t>::min()
                                                         : sqlite3_column_int64(st, c));
    }
    const bool loop_state = format >= 2 && sqlite3_column_type(st, 5) != SQLITE_NULL;
    if (loop_state) {
      add_int(sqlite3_column_int64(st, 4));
      const double inliers = sqlite3_column_double(st, 5);
      std::int64_t bits = 0;
      std::memcpy(&bits, &inliers, sizeof bits);
      add_int(bits);
    }
    if (format >= 3) add_int(sqlite3_column_int64(st, 10));
    for (int c = 6; c < 10; ++c) {
      const bool null = sqlite3_column_type(st, c) == SQLITE_NULL;
      const void* data = c == 6 ? static_cast<const void*>(sqlite3_column_text(st, c))
                                : sqlite3_column_blob(st, c);
      const int n = sqlite3_column_bytes(st, c);
      add_int(null ? -1 : n);
      if (n > 0) crc = crc32(crc, static_cast<const Bytef*>(data), static_cast<uInt>(n));
    }
    sqlite3_finalize(st);
    sql += "UPDATE frames SET crc32 = " + std::to_string(crc) + " WHERE id = " +
           std::to_string(id) + ";";
  }
  return sql;
}

// A file of an older format: 1 (written before the loop decision kept its
// state: no loop columns, a decision threshold that was a raw similarity) or
// 2 (before frame ids: no frame column). Made from a current file with
// append_all (whose rows but the last have no loop state): the newer columns
// dropped, every row's checksum recomputed without them, the meta re-signed.
std::string older_database(int format) {
  const std::string path = temp_path("format" + std::to_string(format));
  {
    DetectorOptions o = options(kExhaustiveSearch, "temporal,geometric");
    o.search.min_gap = 2;
    o.verification.geometric_options.max_features = 32;
    o.verification.temporal_options.place_cut = 0;  // formats 1 to 3 predate the places' records
    Database db = Database::create(path, o);
    Detector d(o);
    run(d, 0, 12);
    db.append_all(d, 0);
  }
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  move_state_into_columns(db);
  std::string sql = older_checksums(db, format);
  sql += "ALTER TABLE frames DROP COLUMN state;";
  if (format < 3) sql += "ALTER TABLE frames DROP COLUMN frame;";
  if (format < 2) {
    sql += "ALTER TABLE frames DROP COLUMN loop; ALTER TABLE frames DROP COLUMN loop_inliers;";
  }
  sql += "DELETE FROM meta WHERE key IN ('writer', 'checkpoint_frames');";
  char* error = nullptr;
  EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error), SQLITE_OK) << error;
  sqlite3_close(db);
  rewrite_options(path, [&](std::string& yaml) {
    if (format >= 2) return;
    const auto at = yaml.find("decision:");
    ASSERT_NE(at, std::string::npos);
    yaml = yaml.substr(0, at) + "decision:\n  threshold: 0.841\n";
  });
  // format_version (an integer meta key), re-signed.
  EXPECT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_exec(db,
               ("UPDATE meta SET value = " + std::to_string(format) +
                " WHERE key = 'format_version'")
                   .c_str(),
               nullptr, nullptr, nullptr);
  sqlite3_close(db);
  rewrite_options(path, [](std::string&) {});
  return path;
}

TEST(Database, Format1IsReadAndUpgradedInPlace) {
  const std::string path = older_database(1);
  {
    const Database ro = Database::open(path, Database::Mode::kReadOnly);
    EXPECT_EQ(ro.info().format_version, 1);
    // A raw-similarity threshold means nothing in sigma: today's decision.
    EXPECT_EQ(ro.options().decision.threshold, DecisionOptions{}.threshold);
    Detector d(ro.options());
    ro.restore(d);
    EXPECT_EQ(d.size(), 12);
    EXPECT_EQ(d.continuity().query, 11);
    EXPECT_EQ(d.continuity().loop, -1);
  }
  ASSERT_EQ(load(path), "");
  {
    Database db = Database::open(path);  // read-write: upgraded
    EXPECT_EQ(db.info().format_version, kDatabaseFormatVersion);
    Detector d(db.options());
    db.restore(d);
    const auto more = run(d, 12, 20, &db);
    EXPECT_EQ(db.frames(), 20);
  }
  const Database again = Database::open(path, Database::Mode::kReadOnly);
  EXPECT_EQ(again.info().format_version, kDatabaseFormatVersion);
  Detector d(again.options());
  again.restore(d);
  EXPECT_EQ(d.size(), 20);
  EXPECT_EQ(d.continuity().query, 19);
  // Older rows have no frame column: their ids are their row ids.
  std::vector<std::int64_t> ids(20);
  std::iota(ids.begin(), ids.end(), 0);
  EXPECT_EQ(again.frame_ids(), ids);
}

// A format 3 file (the components' state in columns of their own) restores
// exactly as the format 4 file it was made from, is upgraded in place when
// opened for writing, and its old rows then still read.
TEST(Database, Format3IsReadAsTheComponentsRecordsAndUpgradedInPlace) {
  const std::string path = older_database(3);
  DetectorOptions o = options(kExhaustiveSearch, "temporal,geometric");
  o.search.min_gap = 2;
  o.verification.geometric_options.max_features = 32;
  o.verification.temporal_options.place_cut = 0;  // as older_database()
  Detector fresh(o);
  run(fresh, 0, 12);
  {
    const Database ro = Database::open(path, Database::Mode::kReadOnly);
    EXPECT_EQ(ro.info().format_version, 3);
    Detector d(ro.options());
    ro.restore(d);
    expect_same_state(fresh, d);
  }
  {
    Database db = Database::open(path);
    EXPECT_EQ(db.info().format_version, kDatabaseFormatVersion);
    Detector d(db.options());
    db.restore(d);
    run(d, 12, 20, &db);
    run(fresh, 12, 20);
  }
  const Database again = Database::open(path, Database::Mode::kReadOnly);
  again.verify();
  Detector d(again.options());
  again.restore(d);
  expect_same_state(fresh, d);
}

// A format 2 file (before frame ids) reads with frame id = row id, is
// upgraded in place when opened for writing, and its frames then continue
// with the caller's ids.
TEST(Database, Format2IsReadAndUpgradedInPlace) {
  const std::string path = older_database(2);
  {
    const Database ro = Database::open(path, Database::Mode::kReadOnly);
    EXPECT_EQ(ro.info().format_version, 2);
    EXPECT_EQ(ro.last_frame(), 11);
    Detector d(ro.options());
    ro.restore(d);
    EXPECT_EQ(d.size(), 12);
  }
  {
    Database db = Database::open(path);
    EXPECT_EQ(db.info().format_version, kDatabaseFormatVersion);
    Detector d(db.options());
    db.restore(d);
    EXPECT_EQ(d.id_of(11), 11);  // the row's id: format 2 kept no ids in the state
    const Result r = d.process(frame(12), 40);
    db.append(d, r, 1, "later", 40);
  }
  const Database again = Database::open(path, Database::Mode::kReadOnly);
  std::vector<std::int64_t> ids(12);
  std::iota(ids.begin(), ids.end(), 0);
  ids.push_back(40);
  EXPECT_EQ(again.frame_ids(), ids);
  EXPECT_EQ(again.session_frames(1).first_id, 12);
  ASSERT_EQ(again.session_frames(1).frames.size(), 1u);
  EXPECT_EQ(again.session_frames(1).frames[0].frame, 40);
  EXPECT_NO_THROW(again.verify());
}

}  // namespace
}  // namespace lsgd::io
