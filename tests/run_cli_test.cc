// End-to-end tests of `lsgd run` frame ids and of a run stopped and started
// again (README, "Frame ids" and "Resuming"): image i is frame i whatever was
// skipped before it; a re-run of the same command continues the session it
// interrupted, cuts the CSV rows the database never committed and ends with
// the CSV and database of an uninterrupted run, also after kill -9 at any
// moment; anything else that would store an image twice is refused.
#include "run_cli_test_support.h"

namespace run_cli_test_support {  // the fixture and its helpers
namespace {

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

}  // namespace
}  // namespace run_cli_test_support
