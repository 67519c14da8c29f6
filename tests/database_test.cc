// Tests of the persistence of the detector (include/lsgd/io/database.h):
// resuming gives exactly the results of an uninterrupted run (both search
// modes, temporal and temporal+geometric verification), the saved index of
// index mode, sessions, option compatibility and the caller's ids. Damaged
// files: database_damage_test.cc; older formats: database_formats_test.cc;
// the write-ahead log: database_wal_test.cc; `lsgd run --database` /
// `lsgd db info` end to end: database_cli_test.cc.
#include "lsgd/io/database.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/io/session.h"
#include "lsgd/limits.h"
#include "database_test_support.h"
#include "detector_util.h"
#include "test_util.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using database_test_support::options;
using database_test_support::run;
using database_test_support::temp_path;
using test::expect_same;
using test::expect_same_state;
using test::frame;
using test::message_of;
using test::world;

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

// The saved graph of index mode, saved after 140 of 220 frames, and what
// resuming from it must give: the run of one detector over all 220.
class DatabaseIndex : public ::testing::Test {
 protected:
  static constexpr std::int64_t kSplit = 140, kFrames = 220;

  static DetectorOptions index_options() {
    DetectorOptions o = options(kIndexSearch, "temporal");
    o.search.index.exhaustive_up_to = 0;  // the graph answers every query
    return o;
  }
  static void SetUpTestSuite() {
    o_ = index_options();
    Detector reference(o_);
    expected_ = run(reference, 0, kFrames);
    path_ = temp_path("index_damage");
    Database db = Database::create(path_, o_);
    Detector first(o_);
    run(first, 0, kSplit, &db);
    ASSERT_GT(db.save_index(first), 0);
    ASSERT_GT(first.save_index(graph_), 0);
  }
  static void edit(const char* sql) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path_.c_str(), &db), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    sqlite3_close(db);
  }
  static std::string restore_error(IndexUse use) {
    Detector d(o_);
    try {
      Database::open(path_, Database::Mode::kReadOnly).restore(d, use);
    } catch (const FormatError& e) {
      return std::string(e.what());
    }
    return std::string();
  }
  static void resumes_exactly(Detector& d) {
    const std::vector<Result> tail = run(d, kSplit, kFrames);
    for (std::size_t i = 0; i < tail.size(); ++i) expect_same(tail[i], expected_[kSplit + i]);
  }
  // Bytes with a valid checksum that are not this map's graph: refused by
  // Detector::restore_index, which leaves a detector that rebuilds the graph
  // and continues exactly.
  static void refused(std::vector<std::uint8_t> bytes, const std::string& expected_message) {
    SCOPED_TRACE(expected_message);
    Detector d(o_);
    Database::open(path_, Database::Mode::kReadOnly).restore(d, IndexUse::kRebuild);
    const std::string e = message_of<InvalidArgument>([&] { d.restore_index(bytes.data(), bytes.size()); });
    EXPECT_NE(e.find(expected_message), std::string::npos) << e;
    std::vector<std::uint8_t> none;
    EXPECT_EQ(d.save_index(none), 0);  // no half-restored graph
    resumes_exactly(d);
  }

  inline static DetectorOptions o_;
  inline static std::vector<Result> expected_;
  inline static std::string path_;
  inline static std::vector<std::uint8_t> graph_;
};

// Damage to the saved graph is a FormatError naming the saved index
// (kRebuild ignores it and resumes exactly).
TEST_F(DatabaseIndex, DamagedSavedIndexIsRefusedAndRebuildIgnoresIt) {
  const std::string& path = path_;
  const DetectorOptions& o = o_;
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
}

// Bytes that pass the checksum but not the graph's own checks (links out of
// range, another map's graph, cut short) are refused by
// Detector::restore_index, which leaves a detector that rebuilds the graph
// and continues exactly.
TEST_F(DatabaseIndex, AGraphThatIsNotThisMapsIsRefusedAndTheDetectorRebuildsIt) {
  const DetectorOptions& o = o_;
  const std::vector<std::uint8_t>& graph = graph_;
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

// A frame appended twice (or a detector with nothing new) says so, rather
// than "a detector holding 1 frames, but the database holds 1".
TEST(Database, AFrameIsAppendedOnce) {
  const std::string path = temp_path("once");
  const DetectorOptions o = options(kExhaustiveSearch, "temporal");
  Database db = Database::create(path, o);
  Detector d(o);
  const Result r = d.process(frame(0));
  db.append(d, r, 0);
  EXPECT_NE(message_of<InvalidArgument>([&] { db.append(d, r, 0); }).find("is stored already"), std::string::npos);
  EXPECT_EQ(db.frames(), 1);
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
    // Names no image has: a NUL inside, longer than a list line.
    EXPECT_NE(message_of<InvalidArgument>([&] { db.append(writer, other, 0, std::string("a\0b", 3)); })
                  .find("NUL character"),
              std::string::npos);
    EXPECT_NE(message_of<InvalidArgument>([&] { db.append(writer, other, 0, std::string(65537, 'x')); })
                  .find("more than 65536"),
              std::string::npos);
    // A Result of another detector (or a query's) names another frame: refused.
    Detector stranger(o);
    const Result foreign = stranger.process(frame(60));
    EXPECT_NE(message_of<InvalidArgument>([&] { db.append(writer, foreign, 0, "frame"); })
                  .find("the Result is of frame id 0, not of the detector's last frame (id 2000)"),
              std::string::npos);
    EXPECT_NE(message_of<InvalidArgument>([&] { db.append(writer, writer.query(frame(61)), 0, "frame"); })
                  .find("the Result is of frame id 2001"),
              std::string::npos);
    EXPECT_EQ(db.frames(), 60);
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

// plan_session (io/session.h) refuses, before any frame is processed, what
// the run would be refused for at its first frame or would store wrongly: a
// detector that does not hold the database's frames (a fresh one, or one a
// frame ahead of it), options the database does not take, a session id out
// of range. The detector restored from the database plans as lsgd run does.
TEST(DatabaseSession, APlanNeedsTheDatabasesDetectorAndASessionInRange) {
  const std::string path = temp_path("plan");
  const DetectorOptions o = options(kExhaustiveSearch, "temporal");
  Database db = Database::create(path, o);
  Detector stored(o);
  run(stored, 0, 6, &db);
  std::vector<std::string> images;
  for (int i = 0; i < 6; ++i) images.push_back("frame" + std::to_string(i));
  Detector fresh(o);
  std::string e = message_of<InvalidArgument>([&] { plan_session(db, fresh, images, std::nullopt); });
  EXPECT_NE(e.find("holds 6 frames, the detector 0"), std::string::npos) << e;
  e = message_of<InvalidArgument>([&] { plan_session(db, fresh, images, std::int64_t{4}); });
  EXPECT_NE(e.find("the detector 0"), std::string::npos) << e;
  Detector restored(o);
  db.restore(restored);
  for (const std::int64_t bad : {std::int64_t{-1}, kMaxSession + 1}) {
    e = message_of<InvalidArgument>([&] { plan_session(db, restored, images, bad); });
    EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  }
  DetectorOptions other = o;
  other.search.min_gap = o.search.min_gap + 1;
  Database empty = Database::create(temp_path("plan_empty"), o);
  e = message_of<InvalidArgument>([&] { plan_session(empty, Detector(other), images, std::nullopt); });
  EXPECT_NE(e.find("search.min_gap"), std::string::npos) << e;
  EXPECT_EQ(plan_session(empty, Detector(o), images, std::nullopt).session, 0);
  // The database's own detector: a new session after its frames, and one
  // frame ahead of the database (processed, not appended) it plans nothing.
  const SessionPlan plan = plan_session(db, restored, {"other0", "other1"}, std::nullopt);
  EXPECT_EQ(plan.session, 1);
  EXPECT_EQ(plan.first_id, 6);
  EXPECT_FALSE(plan.resume);
  EXPECT_EQ(plan_session(db, restored, images, kMaxSession).session, kMaxSession);
  restored.process(frame(6));
  e = message_of<InvalidArgument>([&] { plan_session(db, restored, images, std::nullopt); });
  EXPECT_NE(e.find("holds 6 frames, the detector 7"), std::string::npos) << e;
}

}  // namespace
}  // namespace lsgd::io
