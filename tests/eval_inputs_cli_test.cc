// End-to-end tests of what `lsgd eval` and `lsgd run` read: bad images
// skipped or fatal, results written once computed, detections files, dataset
// layouts (KITTI, FAB-MAP) and flags that would be ignored. The scoring
// itself: eval_cli_test.cc.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "eval_cli_test_support.h"

namespace fs = std::filesystem;

namespace {

using lsgd::test::CmdResult;
using lsgd::test::slurp;
using lsgd::test::eval_cli::kTmp;
using lsgd::test::eval_cli::lines_of;
using lsgd::test::eval_cli::lsgd;
using lsgd::test::eval_cli::q;
using lsgd::test::eval_cli::read_json;
using lsgd::test::eval_cli::write_image;
using lsgd::test::eval_cli::write_text;

// Bad images in a sequence: skipped and reported by default, fatal with --strict.
TEST(EvalCli, BadImagesAreSkippedAndReportedOrStopTheRunUnderStrict) {
  const fs::path dir = kTmp / "bad-images";
  for (int i = 0; i < 6; ++i) write_image(dir / (std::to_string(i) + ".png"), i);
  write_text(dir / "2.png", "");  // zero bytes
  fs::create_directories(dir);
  ASSERT_TRUE(cv::imwrite((dir / "4.png").string(), cv::Mat(20, 30, CV_8UC1, cv::Scalar(9))));
  const fs::path csv = kTmp / "bad-images.csv";
  CmdResult r = lsgd("run --sequence " + q(dir) + " --output " + q(csv));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("skipped frame 2 (" + (dir / "2.png").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("skipped frame 4 (" + (dir / "4.png").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(2 skipped)"), std::string::npos) << r.err;
  const std::string rows = slurp(csv);
  EXPECT_EQ(lines_of(rows), 5);  // header + frames 0, 1, 3, 5 under their own indices
  EXPECT_NE(rows.find("\n3," + (dir / "3.png").string() + ","), std::string::npos) << rows;
  EXPECT_NE(rows.find("\n5," + (dir / "5.png").string() + ","), std::string::npos) << rows;
  r = lsgd("run --sequence " + q(dir) + " --strict");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("frame 2 (" + (dir / "2.png").string() + ")"), std::string::npos) << r.err;
}

// Results once computed are written: a report over a run that skipped
// frames (they have no descriptor), a JSON naming a path that is not UTF-8;
// and what can be checked before the run is (a --compare file).
TEST(EvalCli, ResultsAreWrittenAndInputsCheckedBeforeTheRun) {
  const fs::path dir = kTmp / "skipped-report";
  for (int i = 0; i < 8; ++i) write_image(dir / (std::to_string(i) + ".png"), i % 4);
  write_text(dir / "3.png", "");  // skipped
  write_text(kTmp / "skipped-gt.txt", "4 0\n5 1\n7 3\n");
  const fs::path report = kTmp / "skipped.html", json = kTmp / "skipped.json";
  CmdResult r = lsgd("eval --sequence " + q(dir) + " --gt " + q(kTmp / "skipped-gt.txt") +
                     " --min-gap 1 --json " + q(json) + " --report " + q(report));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("skipped frame 3"), std::string::npos) << r.err;
  EXPECT_NE(slurp(report).find("<html"), std::string::npos);
  EXPECT_EQ(read_json(json)["skipped_frames"], 1);

  // A --compare file that does not exist: refused before any frame is run.
  const fs::path csv = kTmp / "compare-run.csv";
  r = lsgd("eval --sequence " + q(dir) + " --gt " + q(kTmp / "skipped-gt.txt") + " --min-gap 1 --json " +
           q(kTmp / "c.json") + " --output " + q(csv) + " --compare " + q(kTmp / "nowhere.csv"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("nowhere.csv"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(csv));
  EXPECT_FALSE(fs::exists(kTmp / "c.json"));
  // --poses that do not fit the evaluated frames, or are not poses: refused
  // before the run, as --compare.
  write_text(kTmp / "poses-3.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  write_text(kTmp / "poses-nan.txt", "1 0 0 nan 0 1 0 0 0 0 1 0\n");
  // Finite positions whose span is not (+-1e308): the map was all '-nan'.
  std::string wide;
  for (int i = 0; i < 8; ++i) wide += std::string("1 0 0 ") + (i % 2 ? "1e308" : "-1e308") + " 0 1 0 0 0 0 1 0\n";
  write_text(kTmp / "poses-wide.txt", wide);
  for (const char* poses : {"poses-3.txt", "poses-nan.txt", "poses-wide.txt"}) {
    r = lsgd("eval --sequence " + q(dir) + " --gt " + q(kTmp / "skipped-gt.txt") + " --min-gap 1 --json " +
             q(kTmp / "c.json") + " --output " + q(csv) + " --report " + q(kTmp / "p.html") + " --poses " +
             q(kTmp / poses));
    EXPECT_EQ(r.code, 1) << poses;
    EXPECT_NE(r.err.find(poses), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("skipped frame 3"), std::string::npos) << poses << ": the run started: " << r.err;
    EXPECT_FALSE(fs::exists(csv));
  }
  EXPECT_NE(r.err.find("positions span x from -1e+308 to 1e+308, more than a double holds"), std::string::npos)
      << r.err;
  // The same with --detections: --compare and --poses are read before anything is scored.
  write_text(kTmp / "d8.csv", "query,match,score\n4,0,1\n5,1,1\n6,-1,\n7,3,1\n");
  for (const std::string& extra : {" --compare " + q(kTmp / "nowhere.csv"),
                                  " --report " + q(kTmp / "p.html") + " --poses " + q(kTmp / "poses-3.txt")}) {
    r = lsgd("eval --detections " + q(kTmp / "d8.csv") + " --gt " + q(kTmp / "skipped-gt.txt") +
             " --min-gap 1 --frames 8 --json " + q(kTmp / "c.json") + extra);
    EXPECT_EQ(r.code, 1) << extra;
    EXPECT_TRUE(r.out.empty()) << extra << ": " << r.out;
    EXPECT_FALSE(fs::exists(kTmp / "c.json"));
  }
  // A folder whose name is not UTF-8: the JSON is written, the byte replaced.
  const fs::path odd = kTmp / "odd\xff\xfe";
  fs::create_directories(odd);
  for (int i = 0; i < 4; ++i) write_image(odd / (std::to_string(i) + ".png"), i);
  write_text(kTmp / "odd-gt.txt", "3 0\n");
  r = lsgd("eval --sequence " + q(odd) + " --gt " + q(kTmp / "odd-gt.txt") + " --min-gap 1 --json " +
           q(kTmp / "odd.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string sequence = read_json(kTmp / "odd.json")["sequence"];
  EXPECT_NE(sequence.find("odd\xEF\xBF\xBD"), std::string::npos) << sequence;  // U+FFFD
}

// Rows that count as missed (a revisit without one) or as false loops (a
// match to the query itself or a later frame) are said, on stderr and in the
// JSON.
TEST(EvalCli, DetectionsThatCountAsMissedOrFalseAreSaid) {
  write_text(kTmp / "skipped-gt.txt", "4 0\n5 1\n7 3\n");
  write_text(kTmp / "d8.csv", "query,match,score\n4,0,1\n5,1,1\n6,-1,\n7,3,1\n");
  CmdResult r;
  // Detections without rows for some of the ground truth's revisits (a CSV
  // of lsgd run --every 2 scored without --every 2): a warning, in the JSON too.
  r = lsgd("eval --detections " + q(kTmp / "d8.csv") + " --gt " + q(kTmp / "skipped-gt.txt") +
           " --min-gap 1 --frames 12 --json " + q(kTmp / "c.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // every revisit (4, 5, 7) has its row; frames that are none need not
  EXPECT_TRUE(read_json(kTmp / "c.json")["warnings"].empty());
  write_text(kTmp / "d-half.csv", "query,match,score\n4,0,1\n6,-1,\n");  // rows of --every 2
  r = lsgd("eval --detections " + q(kTmp / "d-half.csv") + " --gt " + q(kTmp / "skipped-gt.txt") +
           " --min-gap 1 --frames 8 --json " + q(kTmp / "c.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("has no row for 2 of the 3 revisits the ground truth lists: they count as missed"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(read_json(kTmp / "c.json")["warnings"].size(), 1u);
  // A match to the query itself or a later frame (a system that stores a frame
  // before it queries it, or columns given as match,query): a false loop under
  // the strict protocol, and said, with the first such row.
  write_text(kTmp / "d-self.csv", "query,match,score\n4,0,1\n5,5,1\n6,-1,\n7,9,1\n");
  r = lsgd("eval --detections " + q(kTmp / "d-self.csv") + " --gt " + q(kTmp / "skipped-gt.txt") +
           " --min-gap 1 --frames 12 --json " + q(kTmp / "c.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("reports 2 matches to the query itself or a later frame (1 to itself; the first: "
                       "query 5 -> 5)"),
            std::string::npos)
      << r.err;
  const auto self = read_json(kTmp / "c.json");
  EXPECT_EQ(self["warnings"].size(), 1u);
  EXPECT_EQ(self["declared_false"], 2) << self.dump();
}

TEST(EvalCli, DetectionsErrorNamesFileAndLine) {
  const fs::path dir = kTmp / "badcsv";
  write_text(dir / "gt.txt", "8 0\n");
  write_text(dir / "d.csv", "query,match,score\n8,0,0.9\n9,zero,0.5\n");
  const CmdResult r = lsgd("eval --detections " + q(dir / "d.csv") + " --gt " + q(dir / "gt.txt") +
                           " --min-gap 2 --json " + q(dir / "out.json"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find((dir / "d.csv").string() + ":3:"), std::string::npos) << r.err;
  EXPECT_EQ(lines_of(r.err), 1) << r.err;
}

TEST(EvalCli, FabmapBothSidesRemapsAPerPairGroundTruth) {
  // 60 pairs, 120 images; pair 50 revisits pair 0 and pair 51 revisits pair 1.
  const fs::path dir = kTmp / "fabmap-eval";
  write_text(dir / "gt.txt", "50 0\n51 1\n");
  write_text(dir / "d.csv",
             "100,0,0.9\n"    // pair 50 left -> pair 0 left: true
             "103,2,0.8\n"    // pair 51 right -> pair 1 left: true (the same place)
             "101,4,0.7\n");  // pair 50 right -> pair 2: false
  const fs::path json = dir / "out.json";
  const CmdResult r =
      lsgd("eval --detections " + q(dir / "d.csv") + " --gt " + q(dir / "gt.txt") +
           " --min-gap 10 --layout fabmap --side both --frames 60 --json " + q(json));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = read_json(json);
  EXPECT_EQ(j["frames"], 120);
  EXPECT_EQ(j["positives"], 4);  // frames 100, 101, 102, 103
  EXPECT_EQ(j["side"], "both");
  EXPECT_DOUBLE_EQ(j["recall_at_100_precision"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j["average_precision"].get<double>(), 0.5);
}

TEST(EvalCli, FlagsThatWouldBeIgnoredAreErrors) {
  const fs::path dir = kTmp / "flags";
  write_text(dir / "gt.txt", "8 0\n");
  write_text(dir / "d.csv", "8,0,0.9\n");
  write_image(dir / "images" / "0.png", 0);
  const std::string base =
      " --gt " + q(dir / "gt.txt") + " --min-gap 2 --json " + q(dir / "o.json");
  const std::string det = "eval --detections " + q(dir / "d.csv") + base;
  const std::string seq = "eval --sequence " + q(dir / "images") + base;
  for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
           {det + " --side left", "--side"},
           {det + " --tolerance 10", "--tolerance"},
           {det + " --mode nodes", "--mode"},
           {det + " --gt-rows image", "--gt-rows"},
           {seq + " --frames 10", "--frames"},
           // A shortcut and an --option of the same key: one would be lost.
           {seq + " --option search.min_gap=3", "--option search.min_gap and --min-gap both set search.min_gap"},
           {seq + " --mode nodes --option search.mode=index", "both set search.mode: give one"},
           {seq + " --threshold 5 --option decision.threshold=6", "both set decision.threshold"},
           {seq + " --verify none --option verification.stages=temporal", "both set verification.stages"},
           // Two --option of one key with different values: the first was lost.
           {seq + " --option search.top_n=3 --option search.top_n=4",
            "--option search.top_n=3 and --option search.top_n=4 both set search.top_n: give one"},
           {seq + " --detections " + q(dir / "d.csv"), "exactly one"},
           {"eval" + base, "exactly one"}}) {
    const CmdResult r = lsgd(args);
    EXPECT_EQ(r.code, 1) << args;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << "\n" << r.err;
  }
}

TEST(EvalCli, RunReadsKittiAndFabmapLayouts) {
  const fs::path root = kTmp / "kitti";
  const fs::path seq = root / "sequences" / "03";
  std::string times;
  for (int i = 0; i < 4; ++i) {
    char name[16];
    std::snprintf(name, sizeof(name), "%06d.png", i);
    write_image(seq / "image_1" / name, i);
    times += std::to_string(i) + ".0\n";
  }
  write_text(seq / "times.txt", times);
  CmdResult r = lsgd("run --sequence " + q(root) + " --kitti-sequence 3 --camera 1");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(lines_of(r.out), 5);
  EXPECT_NE(r.out.find("\n3," + (seq / "image_1" / "000003.png").string()), std::string::npos)
      << r.out;
  r = lsgd("run --sequence " + q(seq));  // auto: KITTI, but no image_0
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no image_0"), std::string::npos) << r.err;

  const fs::path images = kTmp / "cc" / "Images";
  for (int i = 1; i <= 6; ++i) {
    char name[16];
    std::snprintf(name, sizeof(name), "%04d.jpg", i);
    write_image(images / name, i);
  }
  r = lsgd("run --sequence " + q(images) + " --layout fabmap --side right --every 2");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(lines_of(r.out), 3);  // header + 0002.jpg, 0006.jpg
  EXPECT_NE(r.out.find("\n0," + (images / "0002.jpg").string()), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n1," + (images / "0006.jpg").string()), std::string::npos) << r.out;
}
// lsgd match whose every query image is skipped matches nothing: an error,
// no CSV of a header alone (it exited 0), and the skips listed as run lists
// them, the first 100 and then a count (it printed one line for each).
TEST(EvalCli, MatchWithNoReadableQueryImageIsAnError) {
  const fs::path dir = kTmp / "match_no_query";
  std::string refs, queries;
  for (int i = 0; i < 3; ++i) {
    write_image(dir / ("r" + std::to_string(i) + ".png"), i);
    refs += (dir / ("r" + std::to_string(i) + ".png")).string() + "\n";
  }
  for (int i = 0; i < 150; ++i) queries += (dir / ("missing" + std::to_string(i) + ".png")).string() + "\n";
  write_text(dir / "refs.txt", refs);
  write_text(dir / "queries.txt", queries);
  const CmdResult r = lsgd("match --reference " + q(dir / "refs.txt") + " --query " + q(dir / "queries.txt") +
                           " --output " + q(dir / "m.csv"));
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("no image could be read (see above); 150 skipped"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("only the first 100 are listed"), std::string::npos) << r.err;
  EXPECT_LE(lines_of(r.err), 102) << r.err;
  EXPECT_FALSE(fs::exists(dir / "m.csv"));
}

}  // namespace
