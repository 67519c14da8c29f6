// The values of the lsgd command line's flags, end to end (tools/lsgd/main.cc):
// numbers as typed, in decimal and within their type, empty values and flags
// given twice refused, naming the flag. They run the real binary.
#include <unistd.h>

#include <filesystem>
#include <iomanip>
#include <sstream>
#include <string>
#include <utility>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli_util.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace {

// Unique per process: CTest may run these tests in parallel processes.
const fs::path kTmp =
    lsgd::test::removed_at_exit(fs::path(LSGD_TEST_TMP) / ("flags-cli-" + std::to_string(getpid())));

using lsgd::test::CmdResult;

// Runs `lsgd ARGS`, capturing stdout and stderr.
CmdResult lsgd(const std::string& args) { return lsgd::test::run_command(LSGD_CLI, args, kTmp); }

int lines_of(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

// An integer flag given a number beyond 64 bits, or a negative one where only
// 0 and up make sense, is refused naming it: CLI11 alone read
// --seed 99999999999999999999999 as seed 18446744073709551615 and --seed -5
// as 18446744073709551611.
TEST(Cli, IntegerFlagsBeyond64BitsOrBelowZeroAreRefusedAsTyped) {
  const std::pair<const char*, const char*> cases[] = {
      {"demo --seed 99999999999999999999999",
       "--seed: value 99999999999999999999999 is out of range: far beyond the values it takes"},
      {"demo --seed -5", "--seed: value -5 is out of range: must be 0 or more"},
      {"demo --min-gap 99999999999999999999999",
       "--min-gap: value 99999999999999999999999 is out of range"},
      {"demo --min-gap -99999999999999999999999",
       "--min-gap: value -99999999999999999999999 is out of range"},
  };
  for (const auto& [args, expected] : cases) {
    const CmdResult r = lsgd(args);
    EXPECT_EQ(r.code, 1) << args;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(lines_of(r.err), 1) << r.err;
  }
  // Within 64 bits the flag's own checks still speak (the window's range).
  const CmdResult within = lsgd("demo --min-gap 9223372036854775807");
  EXPECT_EQ(within.code, 1);
  EXPECT_EQ(within.err.find("far beyond"), std::string::npos) << within.err;
}

// Numbers on the command line are decimal, read as --option and a config
// read them: CLI11 took a leading 0 for octal (--first 010 kept frame 8
// onwards, though frame 10 is the image 010.png), 0x10 for 16, ' 5' for 5
// (and '5 ' as an error), and refused --threshold 1e400 as "inf".
TEST(Cli, NumbersAreDecimalAsTypedWithLeadingZeros) {
  const fs::path dir = kTmp / "padded";
  fs::remove_all(dir);
  fs::create_directories(dir);
  cv::Mat image(48, 64, CV_8UC1);
  for (int i = 0; i < 12; ++i) {
    cv::randu(image, 0, 255);
    std::ostringstream name;
    name << std::setw(3) << std::setfill('0') << i << ".png";
    ASSERT_TRUE(cv::imwrite((dir / name.str()).string(), image));
  }
  const CmdResult run = lsgd("run --sequence '" + dir.string() + "' --first 010 --last 011");
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_EQ(run.out.find("008.png"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("010.png"), std::string::npos) << run.out;
  EXPECT_EQ(lines_of(run.out), 3) << run.out;
  const CmdResult gap = lsgd("options --yaml --min-gap 010");
  ASSERT_EQ(gap.code, 0) << gap.err;
  EXPECT_NE(gap.out.find("min_gap: 10 "), std::string::npos) << gap.out;
  const std::pair<const char*, const char*> refused[] = {
      {"options --yaml --min-gap 0x10", "--min-gap: '0x10' is not a decimal integer"},
      {"options --yaml --min-gap ' 5'", "--min-gap: ' 5' is not a decimal integer"},
      {"options --yaml --min-gap 08", nullptr},
      {"options --yaml --threshold 0x10", "--threshold: '0x10' is not a number"},
      {"options --yaml --threshold ' 5'", "--threshold: ' 5' is not a number"},
      {"options --yaml --threshold 1e400",
       "--threshold: value 1e400 is out of range: beyond what a double holds"},
      {"demo --seed 0X1F", "--seed: '0X1F' is not a decimal integer"},
  };
  for (const auto& [args, expected] : refused) {
    const CmdResult r = lsgd(args);
    if (expected == nullptr) {  // 08 is 8, not an octal digit too many
      EXPECT_EQ(r.code, 0) << args << ": " << r.err;
      EXPECT_NE(r.out.find("min_gap: 8 "), std::string::npos) << r.out;
      continue;
    }
    EXPECT_EQ(r.code, 1) << args;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(lines_of(r.err), 1) << r.err;
  }
}

// lsgd db forget --frames is read as typed, before the database is opened
// for writing: a newline or spaces before an id were skipped (' 5:' forgot
// from frame 5; '5: ' was refused), and the message echoed a long value
// whole, twice.
TEST(Cli, DbForgetFramesAreReadAsTypedBeforeTheDatabaseIsOpened) {
  const std::pair<std::string, std::string> cases[] = {
      {"' 5:'", "--frames ' 5:': ' 5' is not a frame id in [0, 9007199254740991]"},
      {"\"$(printf '1:\\n2')\"", "--frames '1:\\x0a2': '\\x0a2' is not a frame id"},
      {"1:" + std::string(1000, '9'), "... (1002 bytes)': '999"},
  };
  for (const auto& [frames, expected] : cases) {
    const CmdResult r = lsgd("db forget no-such.db --frames " + frames);
    EXPECT_EQ(r.code, 1) << frames;
    EXPECT_NE(r.err.find(expected), std::string::npos) << frames << ": " << r.err;
    EXPECT_EQ(r.err.find("does not exist"), std::string::npos) << r.err;
    EXPECT_LT(r.err.size(), 400u) << r.err;
    EXPECT_EQ(lines_of(r.err), 1) << r.err;
  }
}

// A flag given twice is said to be, with its values (CLI11 said "At Most 1
// required but received 2").
TEST(Cli, AFlagGivenTwiceIsSaidToBe) {
  const std::pair<const char*, const char*> cases[] = {
      {"options --min-gap 5 --min-gap 6", "--min-gap is given more than once ('5', '6'): give it once"},
      {"run --sequence a.txt --sequence b.txt", "--sequence is given more than once ('a.txt', 'b.txt')"},
  };
  for (const auto& [args, expected] : cases) {
    const CmdResult r = lsgd(args);
    EXPECT_EQ(r.code, 1) << args;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(r.err.find("At Most"), std::string::npos) << r.err;
    EXPECT_EQ(lines_of(r.err), 1) << r.err;
  }
}

// An empty value (an unset shell variable) names nothing: refused, naming
// the flag, where it was read as 0 (eval's required --min-gap) or the default.
TEST(Cli, EmptyValuesAreRefusedNamingTheFlag) {
  const std::pair<const char*, const char*> cases[] = {
      {"eval --detections /dev/null --gt /dev/null --min-gap ''", "--min-gap: an empty value"},
      {"run --sequence s.txt --last ''", "--last: an empty value"},
      {"run --sequence s.txt --every ''", "--every: an empty value"},
      {"options --threshold ''", "--threshold: an empty value"},
      {"options --verify ''", "--verify: an empty value"},
      {"demo --output ''", "--output: an empty"},
  };
  for (const auto& [args, expected] : cases) {
    const CmdResult r = lsgd(args);
    EXPECT_EQ(r.code, 1) << args;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(lines_of(r.err), 1) << r.err;
  }
}

}  // namespace
