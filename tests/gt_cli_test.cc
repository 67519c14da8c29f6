// End-to-end tests of `lsgd gt convert` and `lsgd gt stats`: they run the real binary.
#include <gtest/gtest.h>

#include "cli_util.h"
#include "test_util.h"
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "lsgd/eval/groundtruth.h"
#include "lsgd/eval/gt_formats.h"

namespace fs = std::filesystem;

namespace {

const fs::path kTmp =
    lsgd::test::removed_at_exit(fs::path(LSGD_TEST_TMP) / ("gtcli-" + std::to_string(getpid())));
const fs::path kGt = fs::path(LSGD_SHARED_DIR) / "groundtruth";

using lsgd::test::CmdResult;
using lsgd::test::slurp;

fs::path write_file(const std::string& name, const std::string& text) {
  fs::create_directories(kTmp);
  const fs::path path = kTmp / name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// Runs `lsgd ARGS`, capturing stdout and stderr.
CmdResult lsgd(const std::string& args) {
  return lsgd::test::run_command(LSGD_CLI, args, kTmp);
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

bool same(const lsgd::eval::GroundTruth& a, const lsgd::eval::GroundTruth& b) {
  if (a.frames() != b.frames() || a.pairs() != b.pairs()) return false;
  for (std::int64_t q = 0; q < a.frames(); ++q) {
    if (a.matches(q) != b.matches(q)) return false;
  }
  return true;
}

// A loopinf file: frames 30..39 revisit 0..9, frame 45 revisits 5, -1 elsewhere.
fs::path write_loopinf() {
  std::string text;
  for (int k = 0; k < 50; ++k) {
    const int j = (k >= 30 && k < 40) ? k - 30 : (k == 45 ? 5 : -1);
    text += std::to_string(k) + "\t" + std::to_string(j) + "\n";
  }
  return write_file("seq.loopinf", text);
}

TEST(GtCli, ConvertWritesPairsThatReadBackTheSame) {
  const fs::path src = write_loopinf(), out = kTmp / "converted.txt";
  const CmdResult r = lsgd("gt convert '" + src.string() + "' --output '" + out.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "11 pairs over 50 frames")) << r.out;
  EXPECT_TRUE(contains(r.out, "loopinf")) << r.out;
  const auto back = lsgd::eval::read_pairs(out.string(), 50);
  EXPECT_TRUE(same(back, lsgd::eval::read_loopinf(src.string())));
  EXPECT_TRUE(back.is_loop(45, 5));
  EXPECT_TRUE(back.is_loop(39, 9));

  // Forcing another format or count is honoured (and fails here).
  EXPECT_EQ(lsgd("gt convert '" + src.string() + "' --output x --frames 49").code, 1);
  EXPECT_EQ(lsgd("gt convert '" + src.string() + "' --output x --format mat").code, 1);
}

TEST(GtCli, ConvertDerivesLoopsFromPoses) {
  // Out and back along a line, 1 m per frame, with a timestamp column.
  std::string text;
  for (int i = 0; i < 40; ++i) {
    const double x = i < 20 ? i : 39 - i;
    text += std::to_string(0.1 * i) + " 1 0 0 " + std::to_string(x) + " 0 1 0 0 0 0 1 0\n";
  }
  const fs::path src = write_file("poses.txt", text), out = kTmp / "poses-pairs.txt";
  const CmdResult r = lsgd("gt convert '" + src.string() + "' --output '" + out.string() +
                           "' --distance 0.5 --min-gap 3");
  ASSERT_EQ(r.code, 0) << r.err;
  lsgd::eval::GtOptions o;
  o.poses_distance = 0.5;
  o.poses_min_gap = 3;
  const auto expected = lsgd::eval::load_groundtruth(src.string(), o);
  EXPECT_EQ(expected.pairs(), 18);  // (39 - i, i) for i = 0..17; 18 and 21 are 3 apart
  EXPECT_TRUE(same(lsgd::eval::read_pairs(out.string(), 40), expected));
}

TEST(GtCli, StatsPrintsAndWritesJson) {
  const fs::path src = write_loopinf(), json = kTmp / "stats.json";
  CmdResult r = lsgd("gt stats '" + src.string() + "' --json '" + json.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "frames: 50")) << r.out;
  EXPECT_TRUE(contains(r.out, "pairs: 11")) << r.out;
  EXPECT_TRUE(contains(r.out, "positive queries: 11")) << r.out;
  EXPECT_TRUE(contains(r.out, "gap (frames): min 30, median 30, max 40")) << r.out;
  EXPECT_FALSE(contains(r.out, "with min gap")) << r.out;
  auto j = nlohmann::json::parse(slurp(json));
  EXPECT_EQ(j["format"], "loopinf");
  EXPECT_EQ(j["frames"], 50);
  EXPECT_EQ(j["pairs"], 11);
  EXPECT_EQ(j["positives"], 11);
  EXPECT_EQ(j["frames_in_loops"], 21);
  EXPECT_EQ(j["gap_max"], 40);

  r = lsgd("gt stats '" + src.string() + "' --min-gap 35 --json '" + json.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "with min gap 35: positive queries 1, pairs 1")) << r.out;
  j = nlohmann::json::parse(slurp(json));
  EXPECT_EQ(j["min_gap"], 35);
  EXPECT_EQ(j["window_positives"], 1);
}

// The median gap is printed whole: the stream's 6 digits wrote the gap
// 9999997 as "median 1e+07" beside "max 9999997".
TEST(GtCli, StatsPrintsTheMedianGapWhole) {
  const fs::path src = write_file("far.txt", "9999999 2\n");
  const CmdResult r = lsgd("gt stats '" + src.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "gap (frames): min 9999997, median 9999997, max 9999997")) << r.out;
  const CmdResult half = lsgd("gt stats '" + write_file("half.txt", "1234570 0\n1234571 0\n").string() + "'");
  EXPECT_TRUE(contains(half.out, "median 1234570.5, max 1234571")) << half.out;
}

TEST(GtCli, BadInputExitsNonZeroNamingTheFile) {
  const fs::path corrupt =
      write_file("corrupt.mat", std::string("MATLAB 5.0 MAT-file") + std::string(200, '\x07'));
  const fs::path odd = write_file("odd.txt", "1 2 3\n");
  const fs::path absent = kTmp / "absent.txt";
  for (const fs::path& p : {corrupt, odd, absent}) {
    for (const std::string& cmd :
         {"gt stats '" + p.string() + "'",
          "gt convert '" + p.string() + "' --output '" + (kTmp / "never.txt").string() + "'"}) {
      const CmdResult r = lsgd(cmd);
      EXPECT_EQ(r.code, 1) << cmd;
      EXPECT_TRUE(contains(r.err, p.string())) << cmd << ": " << r.err;
    }
  }
  EXPECT_FALSE(fs::exists(kTmp / "never.txt"));
  // Flags that do not apply to the format are errors, not ignored.
  const fs::path pairs = write_file("p.txt", "5 1\n");
  CmdResult r = lsgd("gt stats '" + pairs.string() + "' --distance 5");
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(contains(r.err, "--distance")) << r.err;
  r = lsgd("gt convert '" + pairs.string() + "' --output x --min-gap 5");
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(contains(r.err, "--min-gap")) << r.err;
  r = lsgd("gt stats '" + pairs.string() + "' --format xml");
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(contains(r.err, "'xml'")) << r.err;
  EXPECT_NE(lsgd("gt").code, 0);  // a subcommand is required
  // A frame count or window out of range is said in words (no -1 sentinel,
  // no 309-digit bound), for gt and eval alike.
  for (const char* bad : {"-5", "0", "1e3"}) {
    r = lsgd("gt stats '" + pairs.string() + "' --frames " + bad);
    EXPECT_EQ(r.code, 1);
    EXPECT_TRUE(contains(r.err, "'" + std::string(bad) + "' is not a frame count from 1 to 10000000")) << r.err;
    r = lsgd("eval --detections '" + pairs.string() + "' --gt '" + pairs.string() +
             "' --min-gap 0 --json /dev/null --frames " + bad);
    EXPECT_EQ(r.code, 1);
    EXPECT_TRUE(contains(r.err, "is not a frame count")) << r.err;
  }
  r = lsgd("gt stats '" + pairs.string() + "' --min-gap -1");
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(contains(r.err, "--min-gap: Value -1 not in range 0 to 1000000000")) << r.err;
}

TEST(GtCli, Kitti00PosesGiveTheDocumentedCount) {
  const fs::path poses = kGt / "kitti-poses" / "00.txt";
  if (!fs::exists(poses)) GTEST_SKIP() << poses << " not found (../shared is absent)";
  const fs::path json = kTmp / "k00.json";
  const CmdResult r =
      lsgd("gt stats '" + poses.string() + "' --min-gap 100 --json '" + json.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(json));
  EXPECT_EQ(j["format"], "kitti-poses");
  EXPECT_EQ(j["frames"], 4541);
  EXPECT_EQ(j["pairs"], 29698);
  EXPECT_EQ(j["poses_distance"], 10.0);
  EXPECT_EQ(j["poses_min_gap"], 100);
  EXPECT_EQ(j["window_pairs"], 29698);
  std::cout << r.out;
}

}  // namespace
