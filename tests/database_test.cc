// Tests of the persistence of the detector (include/lsgd/io/database.h):
// resuming gives exactly the results of an uninterrupted run (both search
// modes, temporal and temporal+geometric verification), sessions, option
// compatibility, damaged files (not SQLite, truncated at many lengths, bytes
// flipped anywhere, edited rows and meta) and `lsgd run --database` /
// `lsgd db info` end to end.
#include "lsgd/io/database.h"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <cstring>
#include <limits>
#include <numeric>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "synthetic/synthetic.h"
#include "detector_util.h"
#include "test_util.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using test::expect_same;
using test::expect_same_state;
using test::frame;
using test::message_of;
using test::world;

std::string temp_path(const std::string& name) {
  fs::create_directories(LSGD_TEST_TMP);
  const std::string path = std::string(LSGD_TEST_TMP) + "/database_" + name;
  fs::remove_all(path);
  for (const char* suffix : {"-wal", "-shm", "-journal"}) fs::remove(path + suffix);
  return path;
}

DetectorOptions options(const std::string& mode, const std::string& stages,
                        HistogramStorage storage = HistogramStorage::kExact) {
  DetectorOptions o;
  o.descriptor.storage = storage;
  o.search.mode = mode;
  o.search.min_gap = 20;
  parse_verification_stages(stages, o.verification);
  return o;
}

// Frames [first, last) through `detector`, each appended to `db` when given.
std::vector<Result> run(Detector& detector, std::int64_t first, std::int64_t last,
                        Database* db = nullptr, std::int64_t session = 0) {
  std::vector<Result> results;
  for (std::int64_t i = first; i < last; ++i) {
    results.push_back(detector.process(frame(i)));
    if (db) db->append(detector, results.back(), session, "frame" + std::to_string(i));
  }
  return results;
}

struct ResumeCase {
  std::string mode;
  const char* stages;
  std::int64_t frames;  // M
  std::int64_t split;   // N
  bool append_all;      // save with append_all() instead of per-frame append()
  HistogramStorage storage = HistogramStorage::kExact;
  // Index mode: Database::save_index() after this many frames (the frames
  // after it up to the split are stored without saving it again); -1: never.
  std::int64_t saved_at = -1;
  // Index mode: search.index.exhaustive_up_to (0: the graph from the start).
  std::int64_t exhaustive_up_to = 0;
};

void PrintTo(const ResumeCase& c, std::ostream* out) {
  *out << c.mode << " " << c.stages << ", frames " << c.frames << ", split at "
       << c.split << (c.append_all ? ", append_all" : "") << ", " << to_string(c.storage)
       << (c.saved_at >= 0 ? ", index saved at " + std::to_string(c.saved_at) : "")
       << (c.exhaustive_up_to > 0 ? ", exhaustive up to " + std::to_string(c.exhaustive_up_to) : "");
}

class Resume : public ::testing::TestWithParam<ResumeCase> {};

TEST_P(Resume, EqualsUninterruptedRun) {
  const ResumeCase c = GetParam();
  DetectorOptions o = options(c.mode, c.stages, c.storage);
  o.search.index.exhaustive_up_to = c.exhaustive_up_to;
  Detector reference(o);
  const std::vector<Result> expected = run(reference, 0, c.frames);

  std::string stages = c.stages;
  std::replace(stages.begin(), stages.end(), ',', '_');
  const std::string path = temp_path("resume_" + c.mode + "_" + stages +
                                     (c.append_all ? "_all" : "") + "_" + to_string(c.storage) +
                                     (c.saved_at >= 0 ? "_saved" : "") +
                                     (c.exhaustive_up_to > 0 ? "_up_to" : ""));
  std::int64_t saved_frames = 0;
  {
    Database db = Database::create(path, o);
    Detector first(o);
    if (c.saved_at >= 0) {
      run(first, 0, c.saved_at, &db);
      saved_frames = db.save_index(first);
      ASSERT_GT(saved_frames, 0);
      ASSERT_LT(saved_frames, c.saved_at);  // the frames that left the temporal window
      EXPECT_EQ(db.info().index_frames, saved_frames);
      EXPECT_GT(db.info().index_bytes, 0);
      run(first, c.saved_at, c.split, &db);
    } else {
      run(first, 0, c.split, c.append_all ? nullptr : &db);
      if (c.append_all) db.append_all(first, 0);
    }
    EXPECT_EQ(db.frames(), c.split);
  }
  Database db = Database::open(path);
  Detector resumed(o);
  db.restore(resumed);
  ASSERT_EQ(resumed.size(), c.split);
  {
    // The saved graph is back before any query (no rebuild); without one,
    // the graph is built at the first query.
    std::vector<std::uint8_t> graph;
    EXPECT_EQ(resumed.save_index(graph), saved_frames);
  }
  const auto tail = run(resumed, c.split, c.frames, &db);
  std::int64_t found_before_split = 0;
  for (std::size_t i = 0; i < tail.size(); ++i) {
    expect_same(tail[i], expected[static_cast<std::size_t>(c.split) + i]);
    const Result& r = tail[i];
    if (r.best.frame >= 0 && r.best.frame < c.split &&
        world().ground_truth().is_loop(r.frame, r.best.frame)) {
      ++found_before_split;
    }
  }
  // The comparison means something: the resumed detector found the revisit
  // (B' to B) in frames it only loaded.
  EXPECT_GE(found_before_split, 10);
  EXPECT_EQ(db.frames(), c.frames);
  expect_same_state(resumed, reference);

  // The whole file, loaded again, is the uninterrupted detector's state.
  Detector again(o);
  Database::open(path, Database::Mode::kReadOnly).restore(again);
  expect_same_state(again, reference);
}

INSTANTIATE_TEST_SUITE_P(
    Modes, Resume,
    ::testing::Values(ResumeCase{kExhaustiveSearch, "temporal", 260, 110, false},
                      ResumeCase{kNodesSearch, "temporal", 260, 125, false},
                      ResumeCase{kExhaustiveSearch, "none", 260, 100, false},
                      ResumeCase{kNodesSearch, "temporal", 260, 140, true},
                      ResumeCase{kExhaustiveSearch, "temporal,geometric", 190, 150, false},
                      ResumeCase{kNodesSearch, "temporal,geometric", 190, 163, false},
                      ResumeCase{kExhaustiveSearch, "temporal", 260, 110, false,
                                 HistogramStorage::kCompact},
                      ResumeCase{kNodesSearch, "temporal", 260, 140, true,
                                 HistogramStorage::kCompact},
                      // The index rebuilds its graph from the stored frames;
                      // the last frame's places travel in its record.
                      ResumeCase{kIndexSearch, "temporal", 260, 130, false},
                      ResumeCase{kIndexSearch, "temporal,geometric", 190, 155, true,
                                 HistogramStorage::kCompact},
                      // The graph saved in the file: restored as it was, the
                      // frames stored after it indexed at the next query.
                      ResumeCase{kIndexSearch, "temporal", 260, 130, false,
                                 HistogramStorage::kExact, 130},
                      ResumeCase{kIndexSearch, "temporal,geometric", 190, 155, false,
                                 HistogramStorage::kCompact, 120},
                      // Every frame scored while a query has at most 60
                      // candidates (queries up to 80), the graph after: split
                      // after the switch; and with 140 (queries up to 160),
                      // before it.
                      ResumeCase{kIndexSearch, "temporal", 260, 130, false,
                                 HistogramStorage::kExact, 100, 60},
                      ResumeCase{kIndexSearch, "temporal,geometric", 190, 150, false,
                                 HistogramStorage::kExact, -1, 140}),
    [](const ::testing::TestParamInfo<ResumeCase>& param) {
      std::string name = param.param.mode + "_" + param.param.stages +
                         (param.param.append_all ? "_append_all" : "") +
                         (param.param.storage == HistogramStorage::kCompact ? "_compact" : "") +
                         (param.param.saved_at >= 0 ? "_saved_index" : "") +
                         (param.param.exhaustive_up_to > 0 ? "_exhaustive_first" : "");
      std::replace(name.begin(), name.end(), ',', '_');
      return name;
    });

// The saved graph of index mode: damage is a FormatError naming the saved
// index (kRebuild ignores it and resumes exactly); bytes that pass the
// checksum but not the graph's own checks (links out of range, another map's
// graph, cut short) are refused by Detector::restore_index, which leaves a
// detector that rebuilds the graph and continues exactly.
TEST(DatabaseIndex, DamagedSavedIndexIsRefusedAndRebuildIgnoresIt) {
  DetectorOptions o = options(kIndexSearch, "temporal");
  o.search.index.exhaustive_up_to = 0;  // the graph answers every query
  constexpr std::int64_t kSplit = 140, kFrames = 220;
  Detector reference(o);
  const std::vector<Result> expected = run(reference, 0, kFrames);
  const std::string path = temp_path("index_damage");
  std::vector<std::uint8_t> graph;
  {
    Database db = Database::create(path, o);
    Detector first(o);
    run(first, 0, kSplit, &db);
    ASSERT_GT(db.save_index(first), 0);
    ASSERT_GT(first.save_index(graph), 0);
  }
  const auto edit = [&](const char* sql) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    sqlite3_close(db);
  };
  const auto restore_error = [&](IndexUse use) {
    Detector d(o);
    try {
      Database::open(path, Database::Mode::kReadOnly).restore(d, use);
    } catch (const FormatError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const auto resumes_exactly = [&](Detector& d) {
    const std::vector<Result> tail = run(d, kSplit, kFrames);
    for (std::size_t i = 0; i < tail.size(); ++i) expect_same(tail[i], expected[kSplit + i]);
  };

  // A flipped byte: the part's checksum.
  edit("UPDATE indexes SET data = CAST(substr(data, 1, 99) || x'5a' || substr(data, 101) AS BLOB) "
       "WHERE part = 0");
  std::string m = restore_error(IndexUse::kSaved);
  EXPECT_NE(m.find(path), std::string::npos) << m;
  EXPECT_NE(m.find("saved index of search mode index, part 0: checksum"), std::string::npos) << m;
  EXPECT_NE(m.find("--rebuild-index"), std::string::npos) << m;
  EXPECT_EQ(restore_error(IndexUse::kRebuild), "");
  {
    Detector d(o);
    Database::open(path, Database::Mode::kReadOnly).restore(d, IndexUse::kRebuild);
    resumes_exactly(d);
  }
  edit("UPDATE indexes SET part = 3");
  m = restore_error(IndexUse::kSaved);
  EXPECT_NE(m.find("parts are not numbered 0, 1, 2"), std::string::npos) << m;
  edit("UPDATE indexes SET part = 0, frames = 100000");
  m = restore_error(IndexUse::kSaved);
  EXPECT_NE(m.find("covers 100000 frames (140 stored"), std::string::npos) << m;

  // Bytes with a valid checksum that are not this map's graph.
  const auto refused = [&](std::vector<std::uint8_t> bytes, const std::string& expected_message) {
    SCOPED_TRACE(expected_message);
    Detector d(o);
    Database::open(path, Database::Mode::kReadOnly).restore(d, IndexUse::kRebuild);
    const std::string e = message_of<InvalidArgument>([&] { d.restore_index(bytes.data(), bytes.size()); });
    EXPECT_NE(e.find(expected_message), std::string::npos) << e;
    std::vector<std::uint8_t> none;
    EXPECT_EQ(d.save_index(none), 0);  // no half-restored graph
    resumes_exactly(d);
  };
  // The first bottom-layer link (after the header: mark 8, version 8,
  // marker 4, seven integers, the generator text's size and text).
  std::int64_t text = 0;
  std::memcpy(&text, graph.data() + 76, 8);
  const std::size_t links = 84 + static_cast<std::size_t>(text);
  std::vector<std::uint8_t> bad = graph;
  ASSERT_GT(bad[links], 0);  // the first frame has links
  std::memset(bad.data() + links + 4, 0xff, 4);
  refused(bad, "frame 0: bottom-layer links out of range");
  refused({graph.begin(), graph.end() - 3}, "index snapshot");
  bad = graph;
  bad[0] = 'x';
  refused(bad, "not an index snapshot");
  // The same frames' graph made for another similarity metric.
  {
    DetectorOptions l1 = o;
    l1.similarity.metric = SimilarityMetric::kL1;
    Detector other(l1);
    run(other, 0, kSplit);
    std::vector<std::uint8_t> foreign;
    ASSERT_GT(other.save_index(foreign), 0);
    refused(foreign, "made for similarity metric");
  }
  // Another map's graph (the same options, other frames): its keys.
  {
    Detector other(o);
    for (std::int64_t i = 0; i < kSplit; ++i) other.process(frame(kFrames - 1 - i));
    std::vector<std::uint8_t> foreign;
    ASSERT_GT(other.save_index(foreign), 0);
    refused(foreign, "is not the stored frame's");
  }
}

TEST(Database, SessionsFindLoopsAcrossSessions) {
  // Session 0 drives A and B, session 1 drives C, B' (the revisit of B, with
  // moving objects) and D.
  const auto& route = world().route();
  ASSERT_GE(route.size(), 6u);
  ASSERT_TRUE(route[4].revisit);
  const DetectorOptions o = options(kExhaustiveSearch, "temporal,geometric");
  const std::string path = temp_path("sessions");
  std::int64_t session0 = 0;
  {
    Database db = Database::create(path, o);
    EXPECT_EQ(db.last_session(), -1);
    Detector detector(o);
    run(detector, 0, route[1].last_frame + 1, &db, 0);
    session0 = db.frames();
  }
  Database db = Database::open(path);
  EXPECT_EQ(db.last_session(), 0);
  Detector detector(o);
  db.restore(detector);
  std::int64_t cross = 0, correct = 0;
  const std::int64_t first = route[3].first_frame, last = route[5].last_frame;
  for (std::int64_t i = first; i <= last; ++i) {
    const Result r = detector.process(frame(i));
    db.append(detector, r, 1, "revisit");
    if (r.loop && r.best.frame < session0) {
      ++cross;
      // Map the result's frame id back to the world's frame to check the place.
      const std::int64_t world_frame = first + (r.frame - session0);
      correct += world().ground_truth().is_loop(world_frame, r.best.frame) ? 1 : 0;
    }
  }
  EXPECT_GE(cross, 15);
  EXPECT_GE(correct, cross * 9 / 10);
  const DatabaseInfo info = db.info();
  ASSERT_EQ(info.sessions.size(), 2u);
  EXPECT_EQ(info.sessions[0].session, 0);
  EXPECT_EQ(info.sessions[0].frames, session0);
  EXPECT_EQ(info.sessions[0].first_frame, 0);
  EXPECT_EQ(info.sessions[0].last_frame, session0 - 1);
  EXPECT_EQ(info.sessions[1].session, 1);
  EXPECT_EQ(info.sessions[1].frames, last - first + 1);
  EXPECT_EQ(info.frames, db.frames());
  EXPECT_EQ(info.width, 160);
  EXPECT_EQ(info.height, 120);
  EXPECT_EQ(info.format_version, kDatabaseFormatVersion);
  EXPECT_GT(info.bytes, info.frames * 12 * 512);
}

TEST(Database, OptionsMustMatchExceptThreshold) {
  const DetectorOptions o = options(kExhaustiveSearch, "temporal");
  const std::string path = temp_path("options");
  Database db = Database::create(path, o);
  DetectorOptions other = o;
  other.search.min_gap = 40;
  const std::string message = message_of<InvalidArgument>([&] { db.check_compatible(other); });
  EXPECT_NE(message.find("search.min_gap = 40"), std::string::npos) << message;
  EXPECT_NE(message.find("stored 20"), std::string::npos) << message;
  EXPECT_NE(message.find(path), std::string::npos) << message;
  Detector wrong(other);
  EXPECT_NE(message_of<InvalidArgument>([&] { db.restore(wrong); }).find("search.min_gap"),
            std::string::npos);

  other = o;
  other.segmentation.superpixel_size = 30;
  EXPECT_NE(message_of<InvalidArgument>([&] {
              db.check_compatible(other);
            }).find("segmentation.superpixel_size = 30"),
            std::string::npos);
  other = o;
  parse_verification_stages("temporal,geometric", other.verification);
  EXPECT_NE(
      message_of<InvalidArgument>([&] { db.check_compatible(other); }).find("verification.stages"),
      std::string::npos);
  other = o;
  other.descriptor.storage = HistogramStorage::kCompact;
  EXPECT_NE(
      message_of<InvalidArgument>([&] { db.check_compatible(other); }).find("descriptor.storage"),
      std::string::npos);
  other = o;
  other.similarity.metric = SimilarityMetric::kL1;
  EXPECT_NE(
      message_of<InvalidArgument>([&] { db.check_compatible(other); }).find("similarity.metric"),
      std::string::npos);

  // The decision threshold, and options of stages and modes not in use, may differ.
  other = o;
  other.decision.threshold = 0.5;
  other.verification.geometric_options.min_inliers = 50;
  other.search.nodes.beta = 1.1;
  EXPECT_NO_THROW(db.check_compatible(other));
  Detector fine(other);
  EXPECT_NO_THROW(db.restore(fine));

  // A detector that already holds frames cannot be restored into.
  Detector used(o);
  used.process(frame(0));
  EXPECT_NE(message_of<InvalidArgument>([&] { db.restore(used); }).find("new detector"),
            std::string::npos);
  // Appends must follow the database's frame count.
  Result r = used.process(frame(1));
  EXPECT_NE(message_of<InvalidArgument>([&] { db.append(used, r, 0); }).find("holds 0"),
            std::string::npos);
}

TEST(Database, CreateIsAtomicAndNeverOverwrites) {
  const std::string path = temp_path("create");
  const DetectorOptions o = options(kExhaustiveSearch, "temporal");
  { Database db = Database::create(path, o); }
  const std::string dir = fs::path(path).parent_path();
  for (const auto& entry : fs::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().string().find(".tmp-"), std::string::npos) << entry.path();
  }
  EXPECT_NE(message_of<IoError>([&] { Database::create(path, o); }).find("already exists"),
            std::string::npos);
  const std::string missing = temp_path("missing");
  EXPECT_NE(message_of<IoError>([&] { Database::open(missing); }).find(missing), std::string::npos);
  const std::string no_dir = std::string(LSGD_TEST_TMP) + "/no/such/dir/x.db";
  EXPECT_NE(message_of<IoError>([&] { Database::create(no_dir, o); }).find(no_dir),
            std::string::npos);
  // Read-only handles refuse to append.
  Database ro = Database::open(path, Database::Mode::kReadOnly);
  Detector d(o);
  const Result r = d.process(frame(0));
  EXPECT_NE(message_of<InvalidArgument>([&] { ro.append(d, r, 0); }).find("read-only"),
            std::string::npos);
}

// ---- damaged files

// A small valid database: 12 frames, nodes mode, temporal + geometric (every column in use).
const std::string& small_database() {
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

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::string& bytes) {
  for (const char* suffix : {"-wal", "-shm", "-journal"}) fs::remove(path + suffix);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Opens and restores `path`; returns the FormatError's message, or "" when it loaded.
std::string load(const std::string& path, Detector* out = nullptr) {
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

// Rewrites the stored options with `edit` and re-signs the meta table (the
// checksum is the CRC-32 of "key=value\n" over the keys in order), as a file
// written by an older version that lacked some keys would look.
void rewrite_options(const std::string& path, const std::function<void(std::string&)>& edit) {
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

void erase(std::string& text, const std::string& what) {
  const auto at = text.find(what);
  ASSERT_NE(at, std::string::npos) << what << " not in:\n" << text;
  text.erase(at, what.size());
}

// Keys added after a file was written take the value of the version that
// wrote it: no `descriptor` section means exact storage, no
// verification.temporal.long_frames means the single 16-frame sequence.
TEST(Database, OptionsOfAnOlderVersionKeepTheirBehaviour) {
  const std::string path = temp_path("older");
  fs::copy_file(small_database(), path);
  rewrite_options(path, [](std::string& yaml) {
    erase(yaml, "    long_frames: 48  # frames\n");
    const auto from = yaml.find("descriptor:\n");
    ASSERT_NE(from, std::string::npos);
    yaml.erase(from, yaml.find("similarity:") - from);
  });
  const std::string damage = load(path);
  ASSERT_EQ(damage, "");
  const Database db = Database::open(path, Database::Mode::kReadOnly);
  EXPECT_EQ(db.options().verification.temporal_options.long_frames, 0);
  EXPECT_EQ(db.options().descriptor.storage, HistogramStorage::kExact);
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
    Database db = Database::create(path, o);
    Detector d(o);
    run(d, 0, 12);
    db.append_all(d, 0);
  }
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  // Formats 1 to 3 kept the components' state in columns of their own: the
  // version-1 records of the state column, moved there.
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
  // Each row's checksum as that format computed it (database.cc row_checksum).
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

// ---- the write-ahead log

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

// The caller's ids (with gaps) and time stamps survive the database, and a
// frame appended under another id than the detector's is refused.
TEST(Database, CallersIdsAndStampsAreKept) {
  const std::string path = temp_path("ids_and_stamps");
  const DetectorOptions o = options(kExhaustiveSearch, "temporal,geometric");
  Detector writer(o);
  std::vector<Result> expected;
  {
    Database db = Database::create(path, o);
    for (std::int64_t i = 0; i < 60; ++i) {
      const std::int64_t id = 1000 + 3 * i;  // keyframe ids with gaps
      const Result r = writer.process(frame(i), id, 0.25 * static_cast<double>(i));
      EXPECT_EQ(r.id, id);
      EXPECT_EQ(r.stamp, 0.25 * static_cast<double>(i));
      EXPECT_EQ(r.loop_id, r.best.frame >= 0 ? 1000 + 3 * r.best.frame : -1);
      db.append(writer, r, 0, "frame");
    }
    const Result other = writer.process(frame(60), 2000);
    EXPECT_NE(message_of<InvalidArgument>([&] { db.append(writer, other, 0, "frame", 2001); })
                  .find("frame id 2001 is not the detector's id 2000"),
              std::string::npos);
    for (std::int64_t i = 61; i < 90; ++i) expected.push_back(writer.process(frame(i)));
  }
  const Database db = Database::open(path, Database::Mode::kReadOnly);
  EXPECT_EQ(db.frame_ids().front(), 1000);
  EXPECT_EQ(db.frame_ids().back(), 1177);
  Detector restored(o);
  db.restore(restored);
  for (std::int64_t f = 0; f < 60; ++f) {
    EXPECT_EQ(restored.id_of(f), 1000 + 3 * f);
    EXPECT_EQ(restored.stamp_of(f), 0.25 * static_cast<double>(f));
    EXPECT_EQ(restored.frame_of(1000 + 3 * f), f);
  }
  EXPECT_EQ(restored.frame_of(1001), -1);
  // The frame the writer did not store goes in again, and the rest follows as before.
  restored.process(frame(60), 2000);
  for (std::int64_t i = 61; i < 90; ++i) {
    const Result r = restored.process(frame(i));
    expect_same(r, expected[static_cast<std::size_t>(i - 61)]);
    EXPECT_EQ(r.id, 2000 + (i - 60));
    EXPECT_TRUE(std::isnan(r.stamp));
  }
}

// ---- the command line

#ifdef LSGD_CLI
int run_cli(const std::string& args, const std::string& out = "") {
  const std::string command =
      std::string(LSGD_CLI) + " " + args + (out.empty() ? "" : " > " + out) + " 2>/dev/null";
  return std::system(command.c_str());
}

std::vector<std::string> csv_columns(const std::string& path, std::vector<int> keep) {
  std::ifstream in(path);
  std::vector<std::string> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream s(line);
    std::string f;
    while (std::getline(s, f, ',')) fields.push_back(f);
    std::string row;
    for (const int k : keep) row += (k < static_cast<int>(fields.size()) ? fields[k] : "?") + ",";
    rows.push_back(row);
  }
  return rows;
}

// Frames 0-99 in DIR/a, 100-149 in DIR/b, all of them listed in DIR/all.txt.
std::string write_split_sequence(const std::string& name) {
  const std::string dir = temp_path(name);
  fs::remove_all(dir);
  fs::create_directories(dir + "/a");
  fs::create_directories(dir + "/b");
  std::ofstream all(dir + "/all.txt");
  for (std::int64_t i = 0; i < 150; ++i) {
    char file_name[32];
    std::snprintf(file_name, sizeof(file_name), "/%04d.png", static_cast<int>(i));
    const std::string file = dir + (i < 100 ? "/a" : "/b") + file_name;
    cv::imwrite(file, frame(i));
    all << file << "\n";
  }
  return dir;
}

TEST(DatabaseCli, RunResumesAndDbInfo) {
  const std::string dir = write_split_sequence("cli_frames");
  const std::string db = temp_path("cli.db");
  const std::string flags = " --min-gap 20 --mode nodes";
  ASSERT_EQ(run_cli("run --sequence " + dir + "/all.txt --layout list" + flags + " --output " +
                    dir + "/all.csv"),
            0);
  ASSERT_EQ(run_cli("run --sequence " + dir + "/a --database " + db + flags + " --output " + dir +
                    "/a.csv"),
            0);
  // Resuming takes the stored options; a different min_gap is refused.
  EXPECT_NE(run_cli("run --sequence " + dir + "/b --database " + db + " --min-gap 30"), 0);
  ASSERT_EQ(run_cli("run --sequence " + dir + "/b --database " + db + " --session 7 --output " +
                    dir + "/b.csv"),
            0);
  // frame, loop_frame, candidate_frame, score: equal to the uninterrupted run.
  const auto expected = csv_columns(dir + "/all.csv", {0, 2, 3, 4});
  auto split = csv_columns(dir + "/a.csv", {0, 2, 3, 4});
  const auto tail = csv_columns(dir + "/b.csv", {0, 2, 3, 4});
  split.insert(split.end(), tail.begin() + 1, tail.end());  // skip b.csv's header
  EXPECT_EQ(split, expected);

  ASSERT_EQ(run_cli("db info " + db + " --json", dir + "/info.json"), 0);
  std::ifstream in(dir + "/info.json");
  const nlohmann::json info = nlohmann::json::parse(in);
  EXPECT_EQ(info["frames"], 150);
  EXPECT_EQ(info["format_version"], kDatabaseFormatVersion);
  ASSERT_EQ(info["sessions"].size(), 2u);
  EXPECT_EQ(info["sessions"][0]["session"], 0);
  EXPECT_EQ(info["sessions"][0]["frames"], 100);
  EXPECT_EQ(info["sessions"][1]["session"], 7);
  EXPECT_EQ(info["sessions"][1]["frames"], 50);
  EXPECT_GT(info["nodes"].get<int>(), 0);
  EXPECT_NE(info["options"].get<std::string>().find("mode: nodes"), std::string::npos);
  ASSERT_EQ(run_cli("db info " + db, dir + "/info.txt"), 0);
  const std::string text = read_bytes(dir + "/info.txt");
  EXPECT_NE(text.find("frames: 150"), std::string::npos) << text;
  EXPECT_NE(text.find("session 7: 50 frames"), std::string::npos) << text;

  write_bytes(dir + "/bad.db", "not a database at all, just text that is long enough");
  EXPECT_NE(run_cli("db info " + dir + "/bad.db"), 0);
}

// lsgd db forget: a range of ids in the middle of the last session, then
// the session before it; lsgd run --database resumes the last session at its
// next image, its rows as a detector that forgot the same frames gives them.
TEST(DatabaseCli, ForgetThenResume) {
  const std::string dir = write_split_sequence("cli_forget_frames");
  const std::string db = temp_path("cli_forget.db");
  fs::remove(db);
  const std::string flags = " --min-gap 20 --mode nodes";
  {
    std::ofstream first(dir + "/first.txt");
    std::ifstream all(dir + "/all.txt");
    std::string line;
    for (int i = 0; i < 120 && std::getline(all, line); ++i) first << line << "\n";
  }
  ASSERT_EQ(run_cli("run --sequence " + dir + "/a --database " + db + flags), 0);
  ASSERT_EQ(run_cli("run --sequence " + dir + "/first.txt --layout list --database " + db +
                    " --session 1"),
            0);
  ASSERT_EQ(run_cli("db forget " + db + " --frames 110:114", dir + "/forget.txt"), 0);
  EXPECT_EQ(read_bytes(dir + "/forget.txt"),
            "forgot 5 frames (ids 110 .. 114) of " + db + ": it holds 215 frames in 2 sessions, " +
                std::to_string(fs::file_size(db)) + " bytes\n");
  ASSERT_EQ(run_cli("run --sequence " + dir + "/all.txt --layout list --database " + db +
                    " --output " + dir + "/rest.csv"),
            0);
  // The same frames forgotten by a detector, then the rest processed.
  DetectorOptions o;
  o.search.min_gap = 20;
  o.search.mode = kNodesSearch;
  Detector d(o);
  for (std::int64_t i = 0; i < 100; ++i) d.process(frame(i));
  d.cut();
  for (std::int64_t i = 0; i < 120; ++i) d.process(frame(i));
  EXPECT_EQ(d.forget(110, 114), 5);
  auto rows = csv_columns(dir + "/rest.csv", {0, 2, 3});
  ASSERT_EQ(rows.size(), 31u);  // images 120 .. 149 as ids 220 .. 249
  for (std::int64_t i = 120; i < 150; ++i) {
    const Result r = d.process(frame(i));
    EXPECT_EQ(rows[static_cast<std::size_t>(i - 119)],
              std::to_string(r.id) + "," + std::to_string(r.loop ? d.id_of(r.best.frame) : -1) + "," +
                  std::to_string(r.best.frame >= 0 ? d.id_of(r.best.frame) : -1) + ",")
        << "image " << i;
  }
  ASSERT_EQ(run_cli("db forget " + db + " --session 0", dir + "/forget.txt"), 0);
  ASSERT_EQ(run_cli("db info " + db + " --json", dir + "/info.json"), 0);
  std::ifstream in(dir + "/info.json");
  const nlohmann::json info = nlohmann::json::parse(in);
  EXPECT_EQ(info["frames"], 145);
  EXPECT_EQ(info["rows_verified"], true);
  ASSERT_EQ(info["sessions"].size(), 1u);
  EXPECT_EQ(info["sessions"][0]["first_frame"], 100);
  // Nothing left to do: every image of the session is stored.
  ASSERT_EQ(run_cli("run --sequence " + dir + "/all.txt --layout list --database " + db), 0);
  ASSERT_EQ(run_cli("db info " + db + " --json", dir + "/info.json"), 0);
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(dir + "/info.json"))["frames"], 145);
  // Refused: no selection, both, a backward or malformed range, an unknown session.
  EXPECT_NE(run_cli("db forget " + db), 0);
  EXPECT_NE(run_cli("db forget " + db + " --session 1 --frames 0:5"), 0);
  EXPECT_NE(run_cli("db forget " + db + " --frames 9:3"), 0);
  EXPECT_NE(run_cli("db forget " + db + " --frames 3-9"), 0);
  EXPECT_NE(run_cli("db forget " + db + " --session 0"), 0);
}

// lsgd run --database in index mode saves the graph when it ends and the
// next run resumes from it (or rebuilds it with --rebuild-index): both equal
// to the uninterrupted run.
TEST(DatabaseCli, IndexModeSavesItsGraph) {
  const std::string dir = write_split_sequence("cli_index_frames");
  const std::string flags = " --min-gap 20 --mode index --option search.index.exhaustive_up_to=0";
  ASSERT_EQ(run_cli("run --sequence " + dir + "/all.txt --layout list" + flags + " --output " +
                    dir + "/all.csv"),
            0);
  const auto expected = csv_columns(dir + "/all.csv", {0, 2, 3, 4});
  for (const std::string resume : {"", " --rebuild-index"}) {
    SCOPED_TRACE(resume);
    const std::string db = temp_path("cli_index.db");
    ASSERT_EQ(run_cli("run --sequence " + dir + "/a --database " + db + flags + " --output " + dir +
                      "/a.csv"),
              0);
    ASSERT_EQ(run_cli("db info " + db + " --json", dir + "/info.json"), 0);
    std::ifstream in(dir + "/info.json");
    const nlohmann::json info = nlohmann::json::parse(in);
    EXPECT_EQ(info["index_frames"], 100 - 20 - 1);  // the frames that left the temporal window
    EXPECT_GT(info["index_bytes"].get<int>(), 0);
    ASSERT_EQ(run_cli("run --sequence " + dir + "/b --database " + db + " --session 7 --output " +
                      dir + "/b.csv" + resume),
              0);
    auto split = csv_columns(dir + "/a.csv", {0, 2, 3, 4});
    const auto tail = csv_columns(dir + "/b.csv", {0, 2, 3, 4});
    split.insert(split.end(), tail.begin() + 1, tail.end());
    EXPECT_EQ(split, expected);
    ASSERT_EQ(run_cli("db info " + db, dir + "/info.txt"), 0);
    const std::string text = read_bytes(dir + "/info.txt");
    EXPECT_NE(text.find("saved search index: 129 frames"), std::string::npos) << text;
  }
}
#endif

}  // namespace
}  // namespace lsgd::io
