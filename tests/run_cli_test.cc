// End-to-end tests of `lsgd run` frame ids and of a run stopped and started
// again (README, "Frame ids" and "Resuming"): image i is frame i whatever was
// skipped before it; a re-run of the same command continues the session it
// interrupted, cuts the CSV rows the database never committed and ends with
// the CSV and database of an uninterrupted run, also after kill -9 at any
// moment; anything else that would store an image twice is refused.
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli_util.h"
#include "lsgd/decision.h"
#include "synthetic/synthetic.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace {

const fs::path kTmp = fs::path(LSGD_TEST_TMP) / ("run-cli-" + std::to_string(getpid()));
constexpr int kFrames = 140;  // the street's first revisit starts near frame 90

using lsgd::test::CmdResult;
using lsgd::test::slurp;

CmdResult lsgd(const std::string& args) {
  return lsgd::test::run_command("timeout", "120 '" + std::string(LSGD_CLI) + "' " + args, kTmp);
}

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// The rows of a run CSV without the `ms` column (a time, different in every run).
std::vector<std::string> rows_without_time(const fs::path& csv) {
  std::vector<std::string> rows;
  for (const std::vector<std::string>& fields : lsgd::test::csv_rows(csv)) {
    std::string row;
    for (std::size_t k = 0; k < fields.size(); ++k) {
      if (k != 5) row += fields[k] + ",";
    }
    rows.push_back(row);
  }
  return rows;
}

// Every column of every frame row of a database, as text, in id order.
std::vector<std::string> database_rows(const fs::path& db) {
  sqlite3* handle = nullptr;
  EXPECT_EQ(sqlite3_open_v2(db.c_str(), &handle, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(handle,
                               "SELECT id, session, name, hex(histogram), hex(pixels), node, place, "
                               "hex(features), crc32, loop, loop_inliers, frame FROM frames "
                               "ORDER BY id",
                               -1, &st, nullptr),
            SQLITE_OK);
  std::vector<std::string> rows;
  while (sqlite3_step(st) == SQLITE_ROW) {
    std::string row;
    for (int c = 0; c < 12; ++c) {
      const auto* text = sqlite3_column_text(st, c);
      row += (text ? reinterpret_cast<const char*>(text) : "NULL") + std::string("|");
    }
    rows.push_back(row);
  }
  sqlite3_finalize(st);
  sqlite3_close(handle);
  return rows;
}

std::vector<long> frame_column(const fs::path& csv) {
  std::vector<long> frames;
  std::istringstream in(slurp(csv));
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) frames.push_back(std::stol(line.substr(0, line.find(','))));
  return frames;
}

class RunCli : public ::testing::Test {
 protected:
  // 140 frames of the synthetic street (160x120) in a folder, and a list of
  // them with image 7 replaced by a file that is not an image.
  static void SetUpTestSuite() {
    fs::remove_all(kTmp);
    dir_ = kTmp / "street";
    fs::create_directories(dir_);
    lsgd::eval::SyntheticOptions o;
    o.width = 160;
    o.height = 120;
    o.route_scale = 0.3;
    const lsgd::eval::SyntheticWorld world(o);
    std::ofstream list(kTmp / "broken.txt");
    for (int i = 0; i < kFrames; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "%04d.png", i);
      ASSERT_TRUE(cv::imwrite((dir_ / name).string(), world.render(i)));
      list << (i == 7 ? (kTmp / "not-an-image.png").string() : (dir_ / name).string()) << "\n";
    }
    std::ofstream(kTmp / "not-an-image.png") << "text";
  }
  static void TearDownTestSuite() { fs::remove_all(kTmp); }

  void SetUp() override {
    for (const char* name : {"a.db", "a.db-wal", "a.db-shm", "a.csv", "b.db", "b.csv"}) {
      fs::remove(kTmp / name);
    }
  }

  static std::string run_args(const std::string& db, const std::string& csv,
                              const std::string& extra = "") {
    return "run --sequence " + q(dir_) + " --min-gap 20 --database " + q(kTmp / db) +
           " --output " + q(kTmp / csv) + extra;
  }

  static fs::path dir_;
};
fs::path RunCli::dir_;

// Image 7 cannot be read: it is skipped, and image 8 is still frame 8, in the
// CSV of `run` with and without a database, in the database, and in `eval`.
TEST_F(RunCli, FrameIdsAreImageIndicesWhateverWasSkipped) {
  const std::string list = q(kTmp / "broken.txt");
  ASSERT_EQ(lsgd("run --sequence " + list + " --min-gap 20 --output " + q(kTmp / "b.csv")).code,
            0);
  std::vector<long> expected;
  for (long i = 0; i < kFrames; ++i) {
    if (i != 7) expected.push_back(i);
  }
  EXPECT_EQ(frame_column(kTmp / "b.csv"), expected);
  const CmdResult r = lsgd("run --sequence " + list + " --min-gap 20 --database " +
                           q(kTmp / "a.db") + " --output " + q(kTmp / "a.csv"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("skipped frame 7"), std::string::npos) << r.err;
  EXPECT_EQ(frame_column(kTmp / "a.csv"), expected);
  EXPECT_EQ(rows_without_time(kTmp / "a.csv"), rows_without_time(kTmp / "b.csv"));
  // The database keeps the ids: frame 8 is row 7.
  const CmdResult info = lsgd("db info --json " + q(kTmp / "a.db"));
  ASSERT_EQ(info.code, 0) << info.err;
  const auto j = nlohmann::json::parse(info.out);
  EXPECT_EQ(j["frames"], kFrames - 1);
  EXPECT_EQ(j["sessions"][0]["first_frame"], 0);
  EXPECT_EQ(j["sessions"][0]["last_frame"], kFrames - 1);
  EXPECT_EQ(j["rows_verified"], true);
  // eval numbers frames the same way: the ground truth is in image indices.
  std::ofstream(kTmp / "gt.txt") << "8 1\n";
  const CmdResult e = lsgd("eval --sequence " + list + " --gt " + q(kTmp / "gt.txt") +
                           " --min-gap 5 --json " + q(kTmp / "e.json") + " --output " +
                           q(kTmp / "e.csv"));
  ASSERT_EQ(e.code, 0) << e.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(kTmp / "e.json"))["skipped_frames"], 1);
  EXPECT_EQ(frame_column(kTmp / "e.csv"), expected);
  // A new session's ids start one past the last stored id: 140 + image index.
  fs::remove(kTmp / "b.csv");
  const CmdResult second = lsgd("run --sequence " + q(dir_) + " --last 9 --database " +
                                q(kTmp / "a.db") + " --session 1 --output " + q(kTmp / "b.csv"));
  ASSERT_EQ(second.code, 0) << second.err;
  const std::vector<long> ids = frame_column(kTmp / "b.csv");
  ASSERT_EQ(ids.size(), 10u);
  EXPECT_EQ(ids.front(), kFrames);
  EXPECT_EQ(ids.back(), kFrames + 9);
}

// The run is stopped after frame 49 (here with --last; below with kill -9),
// and one row the database never committed plus half a row are left in the
// CSV. The same command then continues session 0 at image 50, cuts those
// rows, and ends with the CSV and database of an uninterrupted run.
TEST_F(RunCli, ARerunContinuesTheInterruptedSessionAsIfNeverStopped) {
  ASSERT_EQ(lsgd(run_args("b.db", "b.csv")).code, 0);
  ASSERT_EQ(lsgd(run_args("a.db", "a.csv", " --last 49")).code, 0);
  std::ofstream(kTmp / "a.csv", std::ios::app)
      << "50," << (dir_ / "0050.png").string() << ",-1,-1,0,1,0,-1\n51,x,-1";
  const CmdResult r = lsgd(run_args("a.db", "a.csv"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("continuing session 0 at image 50"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("lost frames"), std::string::npos) << r.err;
  EXPECT_EQ(rows_without_time(kTmp / "a.csv"), rows_without_time(kTmp / "b.csv"));
  EXPECT_EQ(database_rows(kTmp / "a.db"), database_rows(kTmp / "b.db"));

  // Once more: nothing left to do, nothing changed.
  const std::string csv = slurp(kTmp / "a.csv");
  const CmdResult again = lsgd(run_args("a.db", "a.csv"));
  EXPECT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.err.find("nothing to do"), std::string::npos) << again.err;
  EXPECT_EQ(slurp(kTmp / "a.csv"), csv);
  EXPECT_EQ(database_rows(kTmp / "a.db"), database_rows(kTmp / "b.db"));

  // Another selection of the same images would store some twice: refused,
  // nothing changed.
  const CmdResult shifted = lsgd(run_args("a.db", "a.csv", " --first 3"));
  EXPECT_EQ(shifted.code, 1);
  EXPECT_NE(shifted.err.find("is already stored in session 0"), std::string::npos)
      << shifted.err;
  EXPECT_EQ(slurp(kTmp / "a.csv"), csv);
  EXPECT_EQ(database_rows(kTmp / "a.db").size(), static_cast<std::size_t>(kFrames));
  // Unless asked for: a new session.
  const CmdResult explicit_session =
      lsgd(run_args("a.db", "a.csv", " --first 130 --session 1"));
  EXPECT_EQ(explicit_session.code, 0) << explicit_session.err;
  EXPECT_EQ(database_rows(kTmp / "a.db").size(), static_cast<std::size_t>(kFrames + 10));
}

// A camera folder reused for a new recording keeps its file names: the
// images are compared with what was stored, and another content is refused.
TEST_F(RunCli, ReusedImageNamesWithOtherContentAreNotContinued) {
  const fs::path folder = kTmp / "reused";
  fs::remove_all(folder);
  fs::create_directories(folder);
  for (int i = 0; i < 30; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%04d.png", i);
    fs::copy_file(dir_ / name, folder / name);
  }
  const std::string args = "run --sequence " + q(folder) + " --database " + q(kTmp / "a.db");
  ASSERT_EQ(lsgd(args + " --last 9").code, 0);
  for (int i = 0; i < 30; ++i) {  // a new recording: other images, the same names
    char name[32], other[32];
    std::snprintf(name, sizeof name, "%04d.png", i);
    std::snprintf(other, sizeof other, "%04d.png", 100 + i);
    fs::copy_file(dir_ / other, folder / name, fs::copy_options::overwrite_existing);
  }
  const CmdResult r = lsgd(args);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("is not the one stored as frame 9"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--session"), std::string::npos) << r.err;
  EXPECT_EQ(database_rows(kTmp / "a.db").size(), 10u);
  const CmdResult second = lsgd(args + " --session 1");
  EXPECT_EQ(second.code, 0) << second.err;
  EXPECT_EQ(database_rows(kTmp / "a.db").size(), 40u);
}

// kill -9 at three moments of a run, each followed by the same command: the
// CSV and the database end as those of an uninterrupted run, row for row.
TEST_F(RunCli, KilledAtAnyMomentAndRerunEqualsAnUninterruptedRun) {
  ASSERT_EQ(lsgd(run_args("b.db", "b.csv")).code, 0);
  for (const int rows : {12, 47, 96}) {
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      const std::string out = (kTmp / "child.out").string();
      freopen(out.c_str(), "w", stderr);
      const std::string seq = dir_.string(), db = (kTmp / "a.db").string(),
                        csv = (kTmp / "a.csv").string();
      execl(LSGD_CLI, LSGD_CLI, "run", "--sequence", seq.c_str(), "--min-gap", "20",
            "--database", db.c_str(), "--output", csv.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    // Kill once the CSV holds `rows` rows past the header (or the run ended).
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    int status = 0;
    bool killed = false;
    while (std::chrono::steady_clock::now() < deadline) {
      if (waitpid(pid, &status, WNOHANG) == pid) break;
      if (static_cast<int>(frame_column(kTmp / "a.csv").size()) >= rows) {
        kill(pid, SIGKILL);
        waitpid(pid, &status, 0);
        killed = WIFSIGNALED(status);
        break;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    EXPECT_TRUE(killed) << "the run ended before " << rows << " rows";
  }
  const CmdResult r = lsgd(run_args("a.db", "a.csv"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("lost frames"), std::string::npos) << r.err;
  EXPECT_EQ(rows_without_time(kTmp / "a.csv"), rows_without_time(kTmp / "b.csv"));
  EXPECT_EQ(database_rows(kTmp / "a.db"), database_rows(kTmp / "b.db"));
}

// More than one row beyond the database's last frame means the database lost
// frames it had committed (a damaged or deleted write-ahead log): said, and
// the frames are processed again.
TEST_F(RunCli, RowsBeyondTheOneBeingCommittedAreReportedAsLostFrames) {
  ASSERT_EQ(lsgd(run_args("a.db", "a.csv", " --last 9")).code, 0);
  std::ofstream(kTmp / "a.csv", std::ios::app) << "10," << (dir_ / "0010.png").string()
                                               << ",-1,-1,0,1,0,-1\n11," << (dir_ / "0011.png").string()
                                               << ",-1,-1,0,1,0,-1\n";
  const CmdResult r = lsgd(run_args("a.db", "a.csv", " --last 19"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("had rows for 2 frames after frame 9"), std::string::npos) << r.err;
  EXPECT_EQ(frame_column(kTmp / "a.csv").size(), 20u);
  EXPECT_EQ(database_rows(kTmp / "a.db").size(), 20u);
}

// A new session of a database is another sequence: its first frame
// continues no loop of the session before it (Detector::cut()), even when it
// is the very next image of a revisit. Found in an uninterrupted run of
// corridor (the small street declares no loop at 160x120): a frame that
// continued its predecessor's loop (score = appearance + the geometric and
// continuity bonuses); stored as session 1 after the frames before it, it
// earns no continuity bonus, while a resumed session 0 gives it as before.
TEST_F(RunCli, ANewSessionContinuesNoLoopOfTheOneBefore) {
  const fs::path corridor = fs::path(LSGD_SHARED_DIR) / "datasets" / "corridor" / "sequence.txt";
  if (!fs::is_regular_file(corridor)) GTEST_SKIP() << corridor << " is absent (../shared)";
  const auto args = [&](const std::string& db, const std::string& csv, const std::string& extra) {
    return "run --sequence " + q(corridor) + " --min-gap 50 --database " + q(kTmp / db) +
           " --output " + q(kTmp / csv) + extra;
  };
  const auto fields = [](const std::string& line) {
    std::vector<std::string> f;
    std::stringstream in(line);
    for (std::string x; std::getline(in, x, ',');) f.push_back(x);
    return f;
  };
  ASSERT_EQ(lsgd(args("whole.db", "whole.csv", "")).code, 0);
  // Rows without the ms column: frame, image, loop_frame, candidate_frame, score, appearance, ...
  const std::vector<std::string> whole = rows_without_time(kTmp / "whole.csv");
  long continued = -1;
  for (std::size_t i = 1; i < whole.size() && continued < 0; ++i) {
    const std::vector<std::string> f = fields(whole[i]);
    if (std::stol(f[2]) >= 0 && std::fabs(std::stod(f[4]) - std::stod(f[5]) - 6.0) < 1e-3) {
      continued = std::stol(f[0]);
    }
  }
  ASSERT_GT(continued, 0) << "corridor has no continued loop any more";
  const std::string before = " --last " + std::to_string(continued - 1);
  const std::string through = " --last " + std::to_string(continued);
  ASSERT_EQ(lsgd(args("s.db", "s0.csv", before)).code, 0);
  ASSERT_EQ(lsgd(args("s.db", "s1.csv", " --first " + std::to_string(continued) + through +
                                            " --session 1"))
                .code,
            0);
  const std::vector<std::string> session1 = rows_without_time(kTmp / "s1.csv");
  ASSERT_EQ(session1.size(), 2u);
  const std::vector<std::string> f = fields(session1[1]);
  EXPECT_EQ(std::stol(f[0]), continued);
  EXPECT_GT(std::fabs(std::stod(f[4]) - std::stod(f[5]) - 6.0), 1e-3) << session1[1];
  // The same frames as one session, resumed: the loop continues as before.
  ASSERT_EQ(lsgd(args("r.db", "r.csv", before)).code, 0);
  ASSERT_EQ(lsgd(args("r.db", "r.csv", through)).code, 0);
  EXPECT_EQ(rows_without_time(kTmp / "r.csv").back(), whole[static_cast<std::size_t>(continued) + 1]);
}

// --localize: the sequence is localised against the map as a new session
// would be (the same rows as storing it as session 1), and the file is left
// byte for byte as it was.
TEST_F(RunCli, LocalizeAnswersAsANewSessionAndLeavesTheMapAsItWas) {
  ASSERT_EQ(lsgd(run_args("a.db", "a.csv", " --last 69")).code, 0);
  ASSERT_EQ(lsgd(run_args("b.db", "b.csv", " --last 69")).code, 0);
  const std::string map = slurp(kTmp / "a.db");
  const std::vector<std::string> stored = database_rows(kTmp / "a.db");
  const CmdResult r = lsgd(run_args("a.db", "loc.csv", " --first 70 --localize"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("read-only, 70 frames): frame ids 70 .. 139, nothing stored"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(kTmp / "a.db"), map);
  EXPECT_EQ(database_rows(kTmp / "a.db"), stored);
  ASSERT_EQ(lsgd(run_args("b.db", "b1.csv", " --first 70 --session 1")).code, 0);
  const std::vector<std::string> localized = rows_without_time(kTmp / "loc.csv");
  EXPECT_EQ(localized, rows_without_time(kTmp / "b1.csv"));
  ASSERT_EQ(localized.size(), 71u);
  // The revisits from frame ~90 rank places of the map (the street at this
  // size has too few ORB inliers to declare them: query_test counts loops).
  std::size_t in_map = 0;
  for (std::size_t i = 1; i < localized.size(); ++i) {
    std::stringstream row(localized[i]);
    std::string field;
    for (int k = 0; k < 4; ++k) std::getline(row, field, ',');  // frame, image, loop, candidate
    in_map += std::stol(field) >= 0 && std::stol(field) < 70 ? 1 : 0;
  }
  EXPECT_GT(in_map, 30u);
  // Refusals, each naming what is wrong, the map untouched.
  const CmdResult no_db = lsgd("run --sequence " + q(dir_) + " --localize");
  EXPECT_NE(no_db.err.find("--localize needs --database"), std::string::npos) << no_db.err;
  const CmdResult rebuild = lsgd("run --sequence " + q(dir_) + " --output x.csv --rebuild-index");
  EXPECT_EQ(rebuild.code, 1);
  EXPECT_NE(rebuild.err.find("--rebuild-index needs --database"), std::string::npos) << rebuild.err;
  EXPECT_FALSE(fs::exists(kTmp / "x.csv"));
  const CmdResult session = lsgd(run_args("a.db", "x.csv", " --localize --session 2"));
  EXPECT_NE(session.err.find("--localize stores nothing, so it takes no --session"), std::string::npos)
      << session.err;
  const CmdResult missing = lsgd(run_args("missing.db", "x.csv", " --localize"));
  EXPECT_NE(missing.code, 0);
  EXPECT_NE(missing.err.find("missing.db"), std::string::npos) << missing.err;
  EXPECT_FALSE(fs::exists(kTmp / "missing.db"));
  const CmdResult onto = lsgd("run --sequence " + q(dir_) + " --min-gap 20 --database " +
                              q(kTmp / "a.db") + " --localize --output " + q(kTmp / "a.db"));
  EXPECT_NE(onto.code, 0);
  EXPECT_EQ(slurp(kTmp / "a.db"), map);
}

// A CSV written before the ranking's columns existed resumes in its own
// columns: every row has as many fields as its header.
// A CSV written by an older version (without the stamp column, the status
// column too, or the ranking's columns too) resumes in its own columns: every row has as
// many fields as its header, and the old rows stay as they were.
TEST_F(RunCli, ACsvOfAnOlderVersionResumesInItsColumns) {
  const struct {
    int dropped;  // last columns removed
    const char* header;
  } versions[] = {
      {5, "frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers\n"},
      {2, "frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers,ranked_frame,"
          "ranked_score,ranked_confirmed\n"},
      {1, "frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers,ranked_frame,"
          "ranked_score,ranked_confirmed,status\n"},
  };
  for (const auto& v : versions) {
    SCOPED_TRACE(v.header);
    SetUp();
    ASSERT_EQ(lsgd(run_args("a.db", "a.csv", " --last 9")).code, 0);
    std::istringstream rows(slurp(kTmp / "a.csv"));
    std::string old, line;
    while (std::getline(rows, line)) {
      for (int k = 0; k < v.dropped; ++k) line.erase(line.rfind(','));
      old += line + "\n";
    }
    ASSERT_EQ(old.rfind(v.header, 0), 0u);
    std::ofstream(kTmp / "a.csv", std::ios::trunc) << old;
    const CmdResult r = lsgd(run_args("a.db", "a.csv", " --last 19"));
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string text = slurp(kTmp / "a.csv");
    EXPECT_EQ(text.rfind(old, 0), 0u);  // the old rows kept as they were
    std::istringstream all(text);
    const auto commas = std::count(v.header, v.header + std::strlen(v.header), ',');
    int n = 0;
    while (std::getline(all, line)) {
      EXPECT_EQ(std::count(line.begin(), line.end(), ','), commas) << line;
      ++n;
    }
    EXPECT_EQ(n, 21);
  }
}

// Images of another size than the map's are refused once, up front, naming
// both sizes, with or without --localize; nothing is stored or written.
TEST_F(RunCli, ImagesOfAnotherSizeAreRefusedOnceUpFront) {
  ASSERT_EQ(lsgd(run_args("a.db", "a.csv", " --last 29")).code, 0);
  const std::vector<std::string> stored = database_rows(kTmp / "a.db");
  const fs::path big = kTmp / "big";
  fs::create_directories(big);
  cv::Mat image(240, 320, CV_8UC1);
  for (int i = 0; i < 12; ++i) {
    cv::randu(image, 0, 255);
    ASSERT_TRUE(cv::imwrite((big / (std::to_string(i) + ".png")).string(), image));
  }
  for (const char* extra : {"", " --localize"}) {
    const CmdResult r = lsgd("run --sequence " + q(big) + " --min-gap 20 --database " + q(kTmp / "a.db") +
                             " --output " + q(kTmp / "big.csv") + extra);
    EXPECT_EQ(r.code, 1) << extra;
    EXPECT_NE(r.err.find("holds 160x120 frames, but " + (big / "0.png").string() +
                         " is 320x240: a map keeps one frame size"),
              std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(kTmp / "big.csv"));
  }
  EXPECT_EQ(database_rows(kTmp / "a.db"), stored);
}

// The status column: why each frame has a loop or none (LoopStatus's names),
// "loop" exactly on the rows with a loop.
TEST_F(RunCli, EveryRowSaysWhyThereIsALoopOrNone) {
  ASSERT_EQ(lsgd(run_args("a.db", "a.csv", "")).code, 0);
  std::istringstream rows(slurp(kTmp / "a.csv"));
  std::string line;
  std::getline(rows, line);
  ASSERT_EQ(line.substr(line.rfind(',') + 1), "stamp");
  line.erase(line.rfind(','));
  ASSERT_EQ(line.substr(line.rfind(',') + 1), "status");
  std::map<std::string, int> seen;
  while (std::getline(rows, line)) {
    ASSERT_EQ(line.back(), ',') << "a folder gives no stamps: " << line;
    std::vector<std::string> f;
    std::stringstream in(line);
    for (std::string x; std::getline(in, x, ',');) f.push_back(x);
    ASSERT_EQ(f.size(), 12u) << line;
    ++seen[f[11]];
    EXPECT_EQ(f[2] != "-1", f[11] == "loop") << line;
    EXPECT_EQ(lsgd::to_string(lsgd::parse_loop_status(f[11])), f[11]);
  }
  EXPECT_EQ(seen["too_few_frames"], 21);  // frames 0 .. 20 with --min-gap 20
  EXPECT_GT(seen["no_candidate"], 0);
  EXPECT_GT(seen["below_threshold"] + seen["not_confirmed"], 0);
}

// Messages that say what happened (issue 15, class 10).
TEST_F(RunCli, MessagesNameWhatHappened) {
  ASSERT_EQ(lsgd(run_args("a.db", "a.csv", " --last 9")).code, 0);
  // A new session whose frames all have another size stores nothing: exit 1,
  // refused up front (ImagesOfAnotherSizeAreRefusedOnceUpFront).
  const fs::path small = kTmp / "small";
  fs::create_directories(small);
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(cv::imwrite((small / (std::to_string(i) + ".png")).string(),
                            cv::Mat(48, 64, CV_8UC1, cv::Scalar(40 * i))));
  }
  CmdResult r = lsgd("run --sequence " + q(small) + " --database " + q(kTmp / "a.db"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("holds 160x120 frames, but "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("is 64x48"), std::string::npos) << r.err;
  EXPECT_EQ(database_rows(kTmp / "a.db").size(), 10u);
  // A full disk under the CSV names the file.
  r = lsgd("run --sequence " + q(small) + " --output /dev/full");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("'/dev/full'"), std::string::npos) << r.err;
  // An empty file name is not "no database".
  r = lsgd("run --sequence " + q(small) + " --database ''");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("--database: an empty file name"), std::string::npos) << r.err;
  // A session id beyond 2^53 - 1 is refused before anything (no overflow on resume).
  r = lsgd(run_args("a.db", "a.csv", " --session 9223372036854775807"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("not in range"), std::string::npos) << r.err;
  // An unreadable database is not "already exists".
  if (::geteuid() != 0) {
    fs::permissions(kTmp / "a.db", fs::perms::none);
    r = lsgd(run_args("a.db", "a.csv"));
    fs::permissions(kTmp / "a.db", fs::perms::owner_read | fs::perms::owner_write);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("cannot be read and written (Permission denied)"), std::string::npos)
        << r.err;
    EXPECT_EQ(r.err.find("already exists"), std::string::npos) << r.err;
  }
}

// An existing output that is not a CSV of lsgd run is not cut: the re-run
// stops and leaves it as it was.
TEST_F(RunCli, AForeignFileAsOutputIsNotCut) {
  ASSERT_EQ(lsgd(run_args("a.db", "a.csv", " --last 9")).code, 0);
  std::ofstream(kTmp / "a.csv") << "my notes\n";
  const CmdResult r = lsgd(run_args("a.db", "a.csv"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("is not a CSV of lsgd run"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(kTmp / "a.csv"), "my notes\n");
  EXPECT_EQ(database_rows(kTmp / "a.db").size(), 10u);
}


// Another run's CSV as --output (rows naming other images at those frame
// ids: another database's, another sequence's) is refused before anything
// is cut, naming the frame and both images, whether it is longer or shorter
// than the session; a CSV whose images are spelled otherwise (a relative
// --sequence given from another folder) is this run's and resumes.
TEST_F(RunCli, AnotherRunsCsvIsRefusedAndLeftAsItWas) {
  {
    std::ofstream reversed(kTmp / "reversed.txt");
    for (int i = kFrames - 1; i >= 0; --i) {
      char name[32];
      std::snprintf(name, sizeof name, "%04d.png", i);
      reversed << (dir_ / name).string() << "\n";
    }
  }
  const std::string reversed = "run --sequence " + q(kTmp / "reversed.txt") +
                               " --min-gap 20 --database " + q(kTmp / "b.db") + " --output ";
  ASSERT_EQ(lsgd(reversed + q(kTmp / "b.csv") + " --last 49").code, 0);
  for (const char* last : {" --last 99", " --last 29"}) {
    SCOPED_TRACE(last);
    fs::remove(kTmp / "a.db");
    ASSERT_EQ(lsgd(run_args("a.db", "a.csv", last)).code, 0);
    const std::string before = slurp(kTmp / "a.csv");
    const CmdResult r = lsgd(reversed + q(kTmp / "a.csv"));
    EXPECT_EQ(r.code, 1) << r.err;
    const int frame = last == std::string(" --last 99") ? 49 : 29;
    const auto image = [&](int i) {
      char name[32];
      std::snprintf(name, sizeof name, "%04d.png", i);
      return (dir_ / name).string();
    };
    for (const std::string& part :
         {"a.csv holds another run's rows: its row of frame " + std::to_string(frame) + " names " +
              image(frame),
          "this run's frame " + std::to_string(frame) + " is " + image(kFrames - 1 - frame),
          std::string("give that run's CSV as --output, or another --output")}) {
      EXPECT_NE(r.err.find(part), std::string::npos) << part << "\n" << r.err;
    }
    EXPECT_EQ(slurp(kTmp / "a.csv"), before);
    EXPECT_EQ(database_rows(kTmp / "b.db").size(), 50u);
  }
  // Its own CSV, the sequence spelled relatively from kTmp, resumed from elsewhere.
  fs::remove(kTmp / "a.db");
  fs::remove(kTmp / "a.csv");
  const auto from_tmp = [&](const std::string& args) {
    return lsgd::test::run_command("/bin/sh", "-c \"cd " + q(kTmp) + " && '" +
                                                   std::string(LSGD_CLI) + "' " + args + "\"",
                                   kTmp);
  };
  ASSERT_EQ(from_tmp("run --sequence street --min-gap 20 --database a.db --output a.csv --last 9").code, 0);
  const CmdResult resumed = lsgd(run_args("a.db", "a.csv", " --last 19"));
  EXPECT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_EQ(frame_column(kTmp / "a.csv").size(), 20u);
}

}  // namespace

namespace {

// --option sets any option of `lsgd options` on every command; a resumed
// database compares the result with what it stored.
TEST_F(RunCli, OptionFlagSetsAnyOptionAndIsCheckedOnResume) {
  CmdResult r = lsgd("options --option search.top_n=7 --option search.nodes.beta=1.25 --yaml");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("  top_n: 7\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("    beta: 1.25\n"), std::string::npos) << r.out;
  r = lsgd("options --option search.nodes.bta=1");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("unknown option 'search.nodes.bta'; did you mean 'search.nodes.beta'?"),
            std::string::npos) << r.err;
  r = lsgd("options --option search.top_n");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("expected KEY=VALUE"), std::string::npos) << r.err;

  ASSERT_EQ(lsgd(run_args("a.db", "a.csv", " --option verification.temporal.frames=12")).code, 0);
  const CmdResult info = lsgd("db info --json " + q(kTmp / "a.db"));
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_NE(info.out.find("frames: 12"), std::string::npos) << info.out;
  // Another value of a stored option is refused; decision.* may change.
  r = lsgd(run_args("a.db", "b.csv", " --option verification.temporal.frames=16"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("verification.temporal.frames = 16 differs from the stored 12"),
            std::string::npos)
      << r.err;
  r = lsgd(run_args("a.db", "b.csv", " --option decision.threshold=8"));
  EXPECT_EQ(r.code, 0) << r.err;
}

}  // namespace
