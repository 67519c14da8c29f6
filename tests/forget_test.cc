// Tests of forgetting frames (Detector::forget, io::Database::forget and
// forget_session): the kept frames' state is what restoring them gives, the
// records renumbered; forgetting the last frames gives the detector as it was
// before them; a database forgets as the detector does, and stays readable,
// resumable and consistent.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "detector_util.h"
#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/io/database.h"
#include "lsgd/stage.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::expect_same;
using test::expect_same_state;
using test::frame;
using test::message_of;
using test::Remembering;
using test::world;

using ForgetCase = test::ModeCase;
using test::index_of;
using test::options;

std::string temp_path(const std::string& name) {
  std::filesystem::create_directories(LSGD_TEST_TMP);
  const std::string path = std::string(LSGD_TEST_TMP) + "/forget_" + test::test_file_tag() + "_" + name;
  std::filesystem::remove_all(path);
  for (const char* suffix : {"-wal", "-shm", "-journal"}) std::filesystem::remove(path + suffix);
  return path;
}

// A database of the street's first `frames` frames, one session.
std::string written_database(const std::string& name, const DetectorOptions& o, std::int64_t frames) {
  const std::string path = temp_path(name);
  io::Database db = io::Database::create(path, o);
  Detector writer(o);
  for (std::int64_t i = 0; i < frames; ++i) db.append(writer, writer.process(frame(i)), 0);
  return path;
}

// Every node's frames are stored, increasing, and the nodes are in the order
// of their first frames (as assign() creates them).
void expect_consistent_nodes(const Detector& d) {
  std::int64_t previous_first = -1;
  std::int64_t members = 0;
  for (std::int64_t k = 0; k < d.nodes(); ++k) {
    const std::vector<std::int64_t>& m = d.search().members(k);
    ASSERT_FALSE(m.empty());
    EXPECT_GT(m.front(), previous_first) << "node " << k;
    previous_first = m.front();
    EXPECT_TRUE(std::is_sorted(m.begin(), m.end()));
    for (const std::int64_t f : m) {
      EXPECT_GE(f, 0);
      EXPECT_LT(f, d.size());
      EXPECT_EQ(d.search().group_of(f), k);
    }
    members += static_cast<std::int64_t>(m.size());
  }
  if (d.search().has_groups()) { EXPECT_EQ(members, d.size()); }
}

class Forget : public ::testing::TestWithParam<ForgetCase> {};

// Forgetting the frames processed last gives the detector as it was before
// it processed them: the same state, the same index graph, every later
// answer the same.
TEST_P(Forget, TheLastFramesGiveTheDetectorBeforeThem) {
  const DetectorOptions o = options(GetParam());
  Detector forgetting(o), before(o);
  const std::int64_t kept = 180, processed = 240, n = world().frames();
  for (std::int64_t i = 0; i < processed; ++i) {
    forgetting.process(frame(i));
    if (i < kept) before.process(frame(i));
  }
  EXPECT_EQ(forgetting.forget(kept, processed - 1), processed - kept);
  expect_same_state(forgetting, before);
  std::int64_t loops = 0;
  for (std::int64_t i = kept; i < n; ++i) {
    const Result r = forgetting.process(frame(i));
    expect_same(r, before.process(frame(i)));
    loops += r.loop ? 1 : 0;
  }
  if (std::string(GetParam().stages).find("geometric") != std::string::npos) { EXPECT_GT(loops, 10); }
  expect_same_state(forgetting, before);
  EXPECT_EQ(index_of(forgetting), index_of(before));
}

// Forgetting frames in the middle: the kept frames keep their ids and
// stamps, no answer names a forgotten frame, the nodes stay consistent, and
// the detector equals the one a database of its kept frames restores, then
// and for every later frame.
TEST_P(Forget, AMiddleRangeKeepsTheRestAsADatabaseRestoresIt) {
  const DetectorOptions o = options(GetParam());
  Detector d(o);
  const std::int64_t n = world().frames();
  for (std::int64_t i = 0; i < n; ++i) d.process(frame(i), 2 * i, 0.5 * static_cast<double>(i));
  const std::int64_t nodes_before = d.nodes();
  // Ids 120 .. 239: frames 60 .. 119, the first street the revisits return to.
  EXPECT_EQ(d.forget(119, 239), 60);
  ASSERT_EQ(d.size(), n - 60);
  EXPECT_EQ(d.frame_of(120), -1);
  EXPECT_EQ(d.frame_of(118), 59);
  EXPECT_EQ(d.id_of(60), 240);
  EXPECT_EQ(d.stamp_of(60), 60.0);
  EXPECT_EQ(d.frame_of(2 * (n - 1)), n - 61);
  expect_consistent_nodes(d);
  if (d.search().has_groups()) { EXPECT_LE(d.nodes(), nodes_before); }

  const std::string path = temp_path("middle_" + GetParam().mode + ".lsgd");
  {
    io::Database db = io::Database::create(path, o);
    db.append_all(d, 0);
  }
  const io::Database db = io::Database::open(path, io::Database::Mode::kReadOnly);
  Detector restored(o);
  db.restore(restored);
  expect_same_state(d, restored);
  // The start again: revisits of kept frames, none of the forgotten ones.
  for (std::int64_t i = 0; i < 60; ++i) {
    const Result r = d.process(frame(i), 2 * (n + i));
    expect_same(r, restored.process(frame(i), 2 * (n + i)));
    for (const Candidate& c : r.candidates) EXPECT_NE(d.id_of(c.frame) / 2 % n / 60, 1) << c.frame;
    if (r.best.frame >= 0) { EXPECT_TRUE(r.loop_id < 120 || r.loop_id > 239) << r.loop_id; }
  }
  expect_same_state(d, restored);
  expect_consistent_nodes(d);
}

INSTANTIATE_TEST_SUITE_P(
    Modes, Forget,
    ::testing::Values(ForgetCase{kExhaustiveSearch, "temporal,geometric"},
                      ForgetCase{kExhaustiveSearch, "none"},
                      ForgetCase{kNodesSearch, "temporal,geometric"},
                      ForgetCase{kIndexSearch, "temporal,geometric", 0}));

TEST(Forget, NothingInTheRangeChangesNothing) {
  const DetectorOptions o = options({kExhaustiveSearch, "temporal,geometric"});
  Detector d(o), reference(o);
  for (std::int64_t i = 0; i < 60; ++i) {
    d.process(frame(i), 10 + i);
    reference.process(frame(i), 10 + i);
  }
  EXPECT_EQ(d.forget(0, 9), 0);
  EXPECT_EQ(d.forget(70, 1000), 0);
  const std::string m = message_of<InvalidArgument>([&] { d.forget(20, 19); });
  EXPECT_NE(m.find("the first id 20 is above the last 19"), std::string::npos) << m;
  expect_same_state(d, reference);
  for (std::int64_t i = 60; i < 80; ++i) expect_same(d.process(frame(i)), reference.process(frame(i)));
}

// A cut() still holds for the next frame after a forget that keeps the last
// frame: as a cut() after the forget.
TEST(Forget, ACutBeforeItStillHolds) {
  const DetectorOptions o = options({kExhaustiveSearch, "temporal,geometric"});
  Detector d(o), reference(o);
  // Up to the first frame that declares a loop.
  std::int64_t i = 0;
  for (; i < world().frames() && d.continuity().loop < 0; ++i) {
    d.process(frame(i));
    reference.process(frame(i));
  }
  ASSERT_GE(d.continuity().loop, 40) << "a revisit of the street";
  d.cut();
  EXPECT_EQ(d.forget(0, 39), 40);
  EXPECT_EQ(reference.forget(0, 39), 40);
  reference.cut();
  EXPECT_EQ(d.continuity().loop, -1);
  expect_same_state(d, reference);
  for (const std::int64_t end = i + 40; i < end; ++i) {
    expect_same(d.process(frame(i)), reference.process(frame(i)));
  }
}

TEST(Forget, EverythingLeavesAnEmptyDetectorThatTakesAnySize) {
  Detector d(options({kNodesSearch, "temporal,geometric"}));
  for (std::int64_t i = 0; i < 30; ++i) d.process(frame(i));
  EXPECT_EQ(d.forget(0, kMaxFrameId), 30);
  EXPECT_EQ(d.size(), 0);
  EXPECT_EQ(d.nodes(), 0);
  const cv::Mat other(96, 128, CV_8UC1, cv::Scalar(90));
  const Result r = d.process(other);
  EXPECT_EQ(r.frame, 0);
  EXPECT_EQ(r.id, 0);  // ids go on from the last frame kept: none
  EXPECT_EQ(d.width(), 128);
}

TEST(Forget, AComponentThatCannotIsRefusedByName) {
  register_verification_stage({"test-remembering", "a gate with state",
                               [](const VerificationOptions&) -> std::unique_ptr<VerificationStage> {
                                 return std::make_unique<Remembering>();
                               }});
  DetectorOptions o = options({kExhaustiveSearch, "temporal"});
  o.verification.stages.push_back("test-remembering");
  Detector d(o);
  for (std::int64_t i = 0; i < 30; ++i) d.process(frame(i));
  const std::string m = message_of<InvalidArgument>([&] { d.forget(0, 9); });
  EXPECT_NE(m.find("test-remembering keeps per-frame state and cannot forget frames"), std::string::npos) << m;
  EXPECT_EQ(d.size(), 30);
  EXPECT_EQ(d.process(frame(30)).frame, 30);
}

// A database of three sessions forgets a range and a session as the
// detector does; the rows before the range stay as written, the saved index
// goes, and lsgd run's numbering of each session survives.
TEST(ForgetDatabase, ForgetsAsTheDetectorDoes) {
  DetectorOptions o = options({kIndexSearch, "temporal,geometric", 0});
  const std::string path = temp_path("sessions.lsgd");
  const std::int64_t n = world().frames();
  Detector all(o);
  {
    io::Database db = io::Database::create(path, o);
    for (std::int64_t i = 0; i < n; ++i) {
      const std::int64_t session = i < 100 ? 0 : i < 200 ? 1 : 2;
      if (i == 100 || i == 200) all.cut();
      const Result r = all.process(frame(i), 1000 + i);
      db.append(all, r, session, "image" + std::to_string(i));
    }
    EXPECT_EQ(db.save_index(all), n - 21);  // the frames out of the temporal window
  }
  std::optional<io::Database> db(io::Database::open(path));
  // Opens the file again (the one open closed first: one writer at a time).
  const auto reopen = [&] {
    db.reset();
    db.emplace(io::Database::open(path));
  };
  EXPECT_EQ(db->session_frames(2).first_id, 1200);
  const std::int64_t bytes = db->info().bytes;

  // The end of session 0 and the start of session 1.
  EXPECT_EQ(db->forget(1080, 1129), 50);
  EXPECT_EQ(all.forget(1080, 1129), 50);
  EXPECT_EQ(db->frames(), n - 50);
  EXPECT_EQ(db->info().index_frames, 0);
  EXPECT_LT(db->info().bytes, bytes);
  db->verify();
  {
    Detector restored(o);
    db->restore(restored);
    expect_same_state(restored, all);
  }
  // Session 1 was numbered from 1100: its frames are image (id - 1100).
  const io::SessionFrames second = db->session_frames(1);
  EXPECT_EQ(second.first_id, 1100);
  ASSERT_EQ(second.frames.size(), 70u);
  EXPECT_EQ(second.frames.front().frame, 1130);
  EXPECT_EQ(second.frames.front().name, "image130");
  EXPECT_EQ(db->session_frames(2).first_id, 1200);

  // A whole session.
  EXPECT_EQ(db->forget_session(0), 80);
  EXPECT_EQ(all.forget(1000, 1079), 80);
  const io::DatabaseInfo info = db->info();
  ASSERT_EQ(info.sessions.size(), 2u);
  EXPECT_EQ(info.sessions[0].session, 1);
  EXPECT_EQ(info.sessions[0].first_frame, 1130);
  EXPECT_EQ(db->session_frames(1).first_id, 1100);
  const std::string m = message_of<InvalidArgument>([&] { db->forget_session(0); });
  EXPECT_NE(m.find("session 0 has no frames (sessions: 1, 2)"), std::string::npos) << m;
  EXPECT_EQ(db->forget(0, 999), 0);

  // Opened again: the same, and it resumes as the detector goes on.
  reopen();
  EXPECT_EQ(db->session_frames(1).first_id, 1100);
  EXPECT_EQ(db->session_frames(2).first_id, 1200);
  Detector restored(o);
  db->restore(restored);
  expect_same_state(restored, all);
  for (std::int64_t i = 0; i < 40; ++i) {
    const Result r = restored.process(frame(i), 2000 + i);
    expect_same(r, all.process(frame(i), 2000 + i));
    db->append(restored, r, 3, "again" + std::to_string(i));
  }
  reopen();
  Detector again(o);
  db->restore(again);
  expect_same_state(again, all);
}

TEST(ForgetDatabase, TheLastSessionLeavesTheMapBeforeIt) {
  const DetectorOptions o = options({kNodesSearch, "temporal,geometric"});
  const std::string path = temp_path("last.lsgd");
  Detector first(o);
  {
    io::Database db = io::Database::create(path, o);
    Detector writer(o);
    for (std::int64_t i = 0; i < 200; ++i) {
      if (i == 120) writer.cut();
      const Result r = writer.process(frame(i));
      if (i < 120) first.process(frame(i));
      db.append(writer, r, i < 120 ? 0 : 1);
    }
  }
  io::Database db = io::Database::open(path);
  EXPECT_EQ(db.forget_session(1), 80);
  EXPECT_EQ(db.last_session(), 0);
  EXPECT_EQ(db.last_frame(), 119);
  Detector restored(o);
  db.restore(restored);
  expect_same_state(restored, first);
}

TEST(ForgetDatabase, EverythingThenFramesOfAnotherSize) {
  const DetectorOptions o = options({kExhaustiveSearch, "temporal,geometric"});
  const std::string path = written_database("everything.lsgd", o, 30);
  {
    io::Database db = io::Database::open(path);
    EXPECT_EQ(db.forget(0, kMaxFrameId), 30);
    EXPECT_EQ(db.frames(), 0);
    EXPECT_EQ(db.last_session(), -1);
    EXPECT_EQ(db.info().width, 0);
  }
  {
    io::Database db = io::Database::open(path);
    Detector d(o);
    db.restore(d);
    const cv::Mat other(96, 128, CV_8UC1, cv::Scalar(90));
    db.append(d, d.process(other), 0);
  }
  const io::Database db = io::Database::open(path, io::Database::Mode::kReadOnly);
  EXPECT_EQ(db.info().width, 128);
  EXPECT_EQ(db.frame_ids(), std::vector<std::int64_t>{0});
}

TEST(ForgetDatabase, ReadOnlyOrABackwardRangeIsRefused) {
  const DetectorOptions o = options({kExhaustiveSearch, "temporal"});
  const std::string path = written_database("refused.lsgd", o, 10);
  {
    io::Database db = io::Database::open(path, io::Database::Mode::kReadOnly);
    const std::string m = message_of<InvalidArgument>([&] { db.forget(0, 5); });
    EXPECT_NE(m.find("was opened read-only"), std::string::npos) << m;
  }
  io::Database db = io::Database::open(path);
  const std::string m = message_of<InvalidArgument>([&] { db.forget(5, 0); });
  EXPECT_NE(m.find("the first id 5 is above the last 0"), std::string::npos) << m;
  EXPECT_EQ(db.frames(), 10);
}

}  // namespace
}  // namespace lsgd
