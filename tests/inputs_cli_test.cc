// End-to-end tests of what the lsgd commands read (docs/reliability.md, "What
// a command reads"): special files (pipes, devices) are refused instead of
// blocking or reading forever, a run that could process no frame is an error
// (exit 1) and leaves no database behind, and an entry of a folder that cannot
// be read keeps its place, so later frames keep their ids.
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli_util.h"

namespace fs = std::filesystem;

namespace {

const fs::path kTmp = fs::path(LSGD_TEST_TMP) / ("inputs-cli-" + std::to_string(getpid()));

using lsgd::test::CmdResult;
using lsgd::test::slurp;

// Runs lsgd under `timeout`: a command that blocks fails the test (exit 124)
// instead of hanging the suite.
CmdResult lsgd(const std::string& args) {
  return lsgd::test::run_command("timeout", "60 '" + std::string(LSGD_CLI) + "' " + args, kTmp);
}

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// The `frame` column of every row of a `lsgd run` CSV, and its image column.
std::vector<std::pair<long, std::string>> rows_of(const std::string& csv) {
  std::vector<std::pair<long, std::string>> rows;
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    const auto a = line.find(','), b = line.find(',', a + 1);
    rows.emplace_back(std::stol(line.substr(0, a)), line.substr(a + 1, b - a - 1));
  }
  return rows;
}

class Inputs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::remove_all(kTmp);
    dir_ = kTmp / "seq";
    fs::create_directories(dir_);
    cv::Mat m(48, 64, CV_8UC1);
    cv::RNG rng(7);
    for (int i = 0; i < 6; ++i) {
      rng.fill(m, cv::RNG::UNIFORM, 0, 255);
      ASSERT_TRUE(cv::imwrite((dir_ / (std::to_string(i) + ".png")).string(), m));
    }
  }
  static void TearDownTestSuite() { fs::remove_all(kTmp); }
  static fs::path dir_;
};
fs::path Inputs::dir_;

TEST_F(Inputs, APipeNamedLikeAnImageIsSkippedNotWaitedFor) {
  const fs::path fifo = kTmp / "f.jpg";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const fs::path list = kTmp / "fifo.txt";
  std::ofstream(list) << dir_.string() << "/0.png\n" << fifo.string() << "\n"
                      << dir_.string() << "/1.png\n/dev/zero\n" << dir_.string() << "/2.png\n";
  const CmdResult r = lsgd("run --sequence " + q(list) + " --output " + q(kTmp / "fifo.csv"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("skipped frame 1 (" + fifo.string() + "): image '" + fifo.string() +
                       "' is not a regular file"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("skipped frame 3 (/dev/zero)"), std::string::npos) << r.err;
  const auto rows = rows_of(slurp(kTmp / "fifo.csv"));
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[1].first, 2);  // the images keep their indices
  EXPECT_EQ(rows[2].first, 4);
  // Under --strict the pipe stops the run, again without blocking.
  const CmdResult strict = lsgd("run --strict --sequence " + q(list));
  EXPECT_EQ(strict.code, 1);
  EXPECT_NE(strict.err.find("frame 1 (" + fifo.string() + ")"), std::string::npos) << strict.err;
}

// A list of many files that cannot be read lists the first 100 skips, says
// the rest are counted, and the summary counts them all (half a million
// missing files printed 43 MB over 30 s).
TEST_F(Inputs, ManySkippedFramesAreCountedNotEachListed) {
  const fs::path list = kTmp / "missing.txt";
  {
    std::ofstream out(list);
    for (int i = 0; i < 150; ++i) out << "missing-" << i << ".png\n";
    out << dir_.string() << "/0.png\n";
  }
  const CmdResult r = lsgd("run --sequence " + q(list) + " --output " + q(kTmp / "missing.csv"));
  ASSERT_EQ(r.code, 0) << r.err;
  std::size_t listed = 0;
  for (std::size_t at = r.err.find("skipped frame "); at != std::string::npos; at = r.err.find("skipped frame ", at + 1)) {
    ++listed;
  }
  EXPECT_EQ(listed, 100u) << r.err;
  EXPECT_NE(r.err.find("skipped frame 99 ("), std::string::npos);
  EXPECT_EQ(r.err.find("skipped frame 100 ("), std::string::npos);
  EXPECT_NE(r.err.find("only the first 100 are listed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(150 skipped)"), std::string::npos) << r.err;
  EXPECT_EQ(rows_of(slurp(kTmp / "missing.csv")).size(), 1u);
}

TEST_F(Inputs, SpecialFilesAreRefusedAsEveryOtherInput) {
  const std::string seq = "--sequence " + q(dir_);
  const fs::path pairs = kTmp / "special-pairs.txt";
  std::ofstream(pairs) << "1 0\n";
  for (const std::string& args : std::vector<std::string>{
           "run " + seq + " --config /dev/zero", "eval " + seq + " --gt /dev/zero --min-gap 1 --json /dev/null",
        "eval --detections /dev/zero --gt " + q(pairs) + " --min-gap 1 --json /dev/null", "run --sequence /dev/zero",
        "gt stats /dev/zero --frames 10", "gt convert /dev/zero --output " + q(kTmp / "x.txt"),
        "db info /dev/zero", "run " + seq + " --database /dev/zero"}) {
    const CmdResult r = lsgd(args);
    EXPECT_EQ(r.code, 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("/dev/zero"), std::string::npos) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("regular file"), std::string::npos) << args << "\n" << r.err;
  }
  EXPECT_FALSE(fs::exists(kTmp / "x.txt"));
}

// Nothing processed is an error, not an empty success: a list of garbage, or
// a ground-truth file given as --sequence.
TEST_F(Inputs, ARunThatProcessesNoFrameExitsOneAndLeavesNoDatabase) {
  const fs::path gt = kTmp / "gt.txt";
  std::ofstream(gt) << "5 1\n6 2\n";
  const fs::path pairs = kTmp / "pairs.txt";
  std::ofstream(pairs) << "1 0\n";
  const fs::path db = kTmp / "none.db";
  for (const std::string& args : std::vector<std::string>{
           "run --sequence " + q(gt),
                                  "run --sequence " + q(gt) + " --database " + q(db),
                                  "eval --sequence " + q(gt) + " --gt " + q(pairs) +
                                      " --min-gap 1 --json " + q(kTmp / "none.json")}) {
    const CmdResult r = lsgd(args);
    EXPECT_EQ(r.code, 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("no frame was processed: all 2 images were skipped"), std::string::npos)
        << args << "\n" << r.err;
    EXPECT_NE(r.err.find("5 1' does not exist"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(db));
  EXPECT_FALSE(fs::exists(kTmp / "none.db-wal"));
  EXPECT_FALSE(fs::exists(kTmp / "none.json"));
}

// A 16-bit sequence: every frame is rejected by the detector.
TEST_F(Inputs, EveryFrameRejectedIsAnError) {
  const fs::path deep = kTmp / "deep";
  fs::create_directories(deep);
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(cv::imwrite((deep / (std::to_string(i) + ".png")).string(),
                            cv::Mat(40, 40, CV_16UC1, cv::Scalar(1000 * i))));
  }
  const CmdResult r = lsgd("run --sequence " + q(deep));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no frame was processed: all 3 images were skipped"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("16-bit"), std::string::npos) << r.err;
}

// A dangling or looping link in a folder is a frame that cannot be read: it
// is reported and skipped, and every later image keeps its index.
TEST_F(Inputs, BrokenLinksInAFolderKeepTheirPlace) {
  const fs::path links = kTmp / "links";
  fs::create_directories(links);
  for (int i : {0, 1, 3, 5}) {
    fs::copy_file(dir_ / (std::to_string(i) + ".png"), links / (std::to_string(i) + ".png"));
  }
  fs::create_symlink(links / "missing.png", links / "2.png");
  fs::create_symlink(links / "4.png", links / "4.png");  // loops on itself
  const CmdResult r = lsgd("run --sequence " + q(links) + " --output " + q(kTmp / "links.csv"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("skipped frame 2"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("skipped frame 4"), std::string::npos) << r.err;
  const auto rows = rows_of(slurp(kTmp / "links.csv"));
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[2].first, 3);
  EXPECT_EQ(rows[3].first, 5);
  EXPECT_EQ(fs::path(rows[3].second).filename(), "5.png");
}

}  // namespace
