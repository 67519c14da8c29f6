// End-to-end tests of what `lsgd run` writes and says (README, "Frame ids"
// and "Resuming"; the frame ids and resuming themselves: run_cli_test.cc): a
// CSV of an older version resumed in its columns, images of another size
// refused up front, every row's status, messages, outputs that are not this
// run's, and --option checked on resume.
#include "run_cli_test_support.h"

namespace run_cli_test_support {  // the fixture and its helpers
namespace {

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
}  // namespace run_cli_test_support
