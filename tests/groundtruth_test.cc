// Tests of the loop ground truth and the pairs text format (eval/groundtruth.h).
#include "lsgd/eval/groundtruth.h"

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "lsgd/error.h"
#include "lsgd/eval/gt_formats.h"
#include "test_util.h"

namespace fs = std::filesystem;
using lsgd::eval::GroundTruth;

namespace {

const fs::path kTmp =
    lsgd::test::removed_at_exit(fs::path(LSGD_TEST_TMP) / ("gt-" + std::to_string(getpid())));

fs::path write_file(const std::string& name, const std::string& text) {
  const fs::path dir = kTmp;
  fs::create_directories(dir);
  const fs::path path = dir / name;
  std::ofstream(path) << text;
  return path;
}

TEST(GroundTruth, PairsAreSymmetricAndDeduplicated) {
  GroundTruth gt(10);
  gt.add(7, 2);
  gt.add(2, 7);
  gt.add(7, 3);
  gt.add(4, 4);  // a frame with itself is ignored
  EXPECT_EQ(gt.pairs(), 2);
  EXPECT_TRUE(gt.is_loop(7, 2));
  EXPECT_TRUE(gt.is_loop(2, 7));
  EXPECT_FALSE(gt.is_loop(7, 4));
  EXPECT_FALSE(gt.is_loop(4, 4));
  EXPECT_EQ(gt.matches(7), (std::vector<std::int64_t>{2, 3}));
  EXPECT_TRUE(gt.matches(2).empty());  // matches are earlier frames only
}

TEST(GroundTruth, HasLoopHonoursTheTemporalWindow) {
  GroundTruth gt(100);
  gt.add(60, 5);
  gt.add(60, 59);
  EXPECT_TRUE(gt.has_loop(60, 50));   // 5 < 60 - 50
  EXPECT_FALSE(gt.has_loop(60, 55));  // 5 is not < 5
  EXPECT_TRUE(gt.has_loop(60, 0));
  EXPECT_FALSE(gt.has_loop(59, 0));
}

TEST(GroundTruth, OutOfRangeIdsThrow) {
  GroundTruth gt(5);
  EXPECT_THROW(gt.add(5, 1), lsgd::InvalidArgument);
  EXPECT_THROW(gt.add(-1, 1), lsgd::InvalidArgument);
  EXPECT_THROW(gt.matches(5), lsgd::InvalidArgument);
  EXPECT_FALSE(gt.is_loop(9, 1));
  EXPECT_THROW(GroundTruth(-1), lsgd::InvalidArgument);
}

TEST(ReadPairs, ReadsCommentsBlankLinesAndEitherOrder) {
  const fs::path p = write_file("ok.txt", "# source x\n\n3 1\n  1 4\r\n5\t0\n");
  const GroundTruth gt = lsgd::eval::read_pairs(p.string(), 6);
  EXPECT_EQ(gt.frames(), 6);
  EXPECT_EQ(gt.pairs(), 3);
  EXPECT_TRUE(gt.is_loop(3, 1));
  EXPECT_TRUE(gt.is_loop(4, 1));
  EXPECT_TRUE(gt.is_loop(5, 0));
}

TEST(ReadPairs, MalformedLinesNameFileAndLine) {
  const fs::path p = write_file("bad.txt", "3 1\n4 x\n");
  try {
    lsgd::eval::read_pairs(p.string(), 10);
    FAIL() << "expected FormatError";
  } catch (const lsgd::FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(p.string() + ":2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(lsgd::eval::read_pairs(write_file("three.txt", "1 2 3\n").string(), 10),
               lsgd::FormatError);
  EXPECT_THROW(lsgd::eval::read_pairs(write_file("one.txt", "1\n").string(), 10),
               lsgd::FormatError);
}

TEST(ReadPairs, IdsBeyondTheSequenceAreFormatErrors) {
  const fs::path p = write_file("beyond.txt", "9 1\n");
  EXPECT_THROW(lsgd::eval::read_pairs(p.string(), 9), lsgd::FormatError);
  EXPECT_NO_THROW(lsgd::eval::read_pairs(p.string(), 10));
  EXPECT_THROW(lsgd::eval::read_pairs(write_file("neg.txt", "-1 3\n").string(), 10),
               lsgd::FormatError);
}

TEST(ReadPairs, MissingFileIsIoError) {
  EXPECT_THROW(lsgd::eval::read_pairs("/nonexistent/lsgd/gt.txt", 10), lsgd::IoError);
}

TEST(WritePairs, RoundTrips) {
  GroundTruth gt(20);
  gt.add(10, 2);
  gt.add(19, 0);
  gt.add(12, 11);
  const fs::path p = kTmp / "rt.txt";
  fs::create_directories(p.parent_path());
  lsgd::eval::write_pairs(gt, p.string());
  const GroundTruth back = lsgd::eval::read_pairs(p.string(), 20);
  EXPECT_EQ(back.pairs(), 3);
  for (std::int64_t q = 0; q < 20; ++q) EXPECT_EQ(back.matches(q), gt.matches(q));
  EXPECT_THROW(lsgd::eval::write_pairs(gt, "/nonexistent/lsgd/out.txt"), lsgd::IoError);
}

// A pairs file lsgd wrote carries its counts in its header, and a file that
// disagrees with them is refused: cut short at a line's end (a partial copy)
// it was read as a smaller ground truth, its true loops scored false, exit 0
// (issue 35, seventh pass); gt convert and gt stats took the frame count
// from the last pair instead of the header.
TEST(ReadPairs, ACutOrForeignFileDisagreesWithItsHeader) {
  GroundTruth gt(30);
  gt.add(10, 2);
  gt.add(19, 0);
  gt.add(12, 11);
  const fs::path p = kTmp / "whole.txt";
  fs::create_directories(p.parent_path());
  lsgd::eval::write_pairs(gt, p.string());
  std::ifstream in(p);
  std::string header, first;
  std::getline(in, header);
  std::getline(in, first);
  EXPECT_EQ(lsgd::eval::pairs_header(header).frames, 30);
  EXPECT_EQ(lsgd::eval::pairs_header(header).pairs, 3);
  EXPECT_EQ(lsgd::eval::pairs_header("# source x frames=3 pairs=1").frames, -1);  // not lsgd's
  const fs::path cut = write_file("cut.txt", header + "\n" + first + "\n");
  const std::string m = lsgd::test::message_of<lsgd::FormatError>(
      [&] { lsgd::eval::read_pairs(cut.string(), 30); });
  EXPECT_NE(m.find("holds 1 pairs but its header says pairs=3"), std::string::npos) << m;
  EXPECT_NE(m.find(cut.string()), std::string::npos) << m;
  const std::string other = lsgd::test::message_of<lsgd::FormatError>(
      [&] { lsgd::eval::read_pairs(p.string(), 31); });
  EXPECT_NE(other.find(p.string() + ":1: the header says frames=30 but the sequence has 31"),
            std::string::npos) << other;
  // Without a frame count the header gives it (frames after the last loop).
  EXPECT_EQ(lsgd::eval::load_groundtruth(p.string()).frames(), 30);
  EXPECT_EQ(lsgd::eval::load_groundtruth(p.string()).pairs(), 3);
  // A file without lsgd's header is read as before.
  EXPECT_EQ(lsgd::eval::read_pairs(write_file("plain.txt", first + "\n").string(), 30).pairs(), 1);
}

// Every published pairs file in ../shared parses (their ids fit their matrices).
TEST(ReadPairs, PublishedGroundTruthParses) {
  const fs::path dir = fs::path(LSGD_SHARED_DIR) / "groundtruth" / "published";
  if (!fs::exists(dir)) GTEST_SKIP() << "published ground truth not found at " << dir;
  int files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.size() < 10 || name.substr(name.size() - 10) != ".pairs.txt") continue;
    std::ifstream in(entry.path());
    std::string header;
    std::getline(in, header);
    // "# source X.mat var=truth dims=RxC; ..." gives the frame count.
    const auto dims = header.find("dims=");
    ASSERT_NE(dims, std::string::npos) << entry.path();
    const std::int64_t frames = std::stoll(header.substr(dims + 5));
    const GroundTruth gt = lsgd::eval::read_pairs(entry.path().string(), frames);
    EXPECT_GT(gt.pairs(), 0) << entry.path();
    ++files;
  }
  EXPECT_GT(files, 5);
}

}  // namespace
