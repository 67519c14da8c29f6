// `lsgd sweep` end to end on a short synthetic sequence written by the test
// (the grid's units: sweep_test.cc).
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_util.h"
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "lsgd/error.h"
#include "lsgd/eval/groundtruth.h"
#include "lsgd/eval/sweep.h"
#include "synthetic/synthetic.h"
#include "lsgd/io/config.h"
#include "test_util.h"

namespace fs = std::filesystem;
using Strings = std::vector<std::string>;

namespace {

#ifdef LSGD_CLI

const fs::path kTmp = fs::path(LSGD_TEST_TMP) / ("sweep-" + std::to_string(getpid()));

using lsgd::test::CmdResult;
using lsgd::test::slurp;

// Runs `lsgd ARGS`, capturing stdout and stderr.
CmdResult lsgd_cli(const std::string& args) {
  return lsgd::test::run_command(LSGD_CLI, args, kTmp);
}

using lsgd::test::csv_rows;  // no quoted fields in these tables

// A short synthetic street (160x120, 218 frames, revisits from frame ~60).
class SweepCli : public ::testing::Test {
 protected:
  static constexpr int kWindow = 20;

  static void SetUpTestSuite() {
    dir_ = kTmp / "street";
    frames_ = lsgd::test::write_street(dir_, 0.2).frames();
  }
  static void TearDownTestSuite() { fs::remove_all(kTmp); }

  static std::string dataset(const std::string& name = "street") {
    return "--dataset " + name + "='" + dir_.string() + "'," + std::to_string(kWindow);
  }

  static fs::path dir_;
  static std::int64_t frames_;
};
fs::path SweepCli::dir_;
std::int64_t SweepCli::frames_ = 0;

const Strings kHeader = {"dataset",
                         "segmentation.superpixel_size",
                         "search.mode",
                         "min_gap",
                         "frames",
                         "positives",
                         "declared_loops",
                         "declared_true",
                         "declared_false",
                         "precision_at_decision",
                         "recall_at_decision",
                         "recall_at_100_precision",
                         "threshold_at_100_precision",
                         "precision_at_100_recall",
                         "average_precision",
                         "recall_at_1",
                         "recall_at_5",
                         "recall_at_10",
                         "prt",
                         "ms_per_frame_median",
                         "ms_per_frame_p95",
                         "nodes",
                         "bytes_per_frame",
                         "skipped_frames",
                         "decision_recall_at_100_precision",
                         "decision_average_precision"};
constexpr std::size_t kFirstTimeColumn = 19;  // ms_per_frame_median, ms_per_frame_p95

TEST_F(SweepCli, FourCellsMatchDirectEvals) {
  const fs::path csv = kTmp / "grid.csv", md = kTmp / "grid.md", json = kTmp / "grid.json";
  const CmdResult r =
      lsgd_cli("sweep " + dataset() +
               " --set segmentation.superpixel_size=30,40"
               " --set search.mode=exhaustive,nodes --verify none --csv '" +
               csv.string() + "' --markdown '" + md.string() + "' --json '" + json.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = csv_rows(csv);
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_EQ(rows[0], kHeader);
  const Strings order[] = {
      {"30", "exhaustive"}, {"30", "nodes"}, {"40", "exhaustive"}, {"40", "nodes"}};
  for (std::size_t i = 1; i < 5; ++i) {
    ASSERT_EQ(rows[i].size(), kHeader.size()) << i;
    EXPECT_EQ(rows[i][0], "street");
    EXPECT_EQ((Strings{rows[i][1], rows[i][2]}), order[i - 1]);
    EXPECT_EQ(rows[i][3], std::to_string(kWindow));
    EXPECT_EQ(rows[i][4], std::to_string(frames_));
    EXPECT_GT(std::stoll(rows[i][5]), 20);                      // positives
    EXPECT_GT(std::stod(rows[i][kFirstTimeColumn]), 0.0);       // ms/frame median
    EXPECT_EQ(rows[i][kFirstTimeColumn + 2] == "0",
              rows[i][2] == "exhaustive");  // nodes only in nodes mode
  }
  // The Markdown: protocol, window, a header and 4 rows, on stdout and in the file.
  const std::string table = slurp(md);
  EXPECT_EQ(table, r.out);
  EXPECT_NE(table.find("strict protocol"), std::string::npos) << table;
  EXPECT_NE(table.find("window w = " + std::to_string(kWindow)), std::string::npos) << table;
  EXPECT_NE(table.find("| street | 40 | nodes | " + std::to_string(frames_)), std::string::npos);
  const auto j = nlohmann::json::parse(slurp(json));
  ASSERT_EQ(j["rows"].size(), 4u);
  EXPECT_NE(j["rows"][3]["config_yaml"].get<std::string>().find("superpixel_size: 40"),
            std::string::npos);

  // Cells (S_p 30, nodes) and (S_p 40, exhaustive) run alone by `lsgd eval` give the same scores.
  for (const std::size_t row : {2u, 3u}) {
    const fs::path config = kTmp / "cell.yaml", out = kTmp / "cell.json";
    std::ofstream(config) << "segmentation: {superpixel_size: " << rows[row][1] << "}\n";
    const CmdResult e =
        lsgd_cli("eval --sequence '" + (dir_ / "sequence.txt").string() + "' --gt '" +
                 (dir_ / "groundtruth.txt").string() + "' --min-gap " + std::to_string(kWindow) +
                 " --mode " + rows[row][2] + " --verify none --config '" + config.string() +
                 "' --json '" + out.string() + "'");
    ASSERT_EQ(e.code, 0) << e.err;
    const auto cell = nlohmann::json::parse(slurp(out));
    for (std::size_t c = 5; c < kHeader.size(); ++c) {
      if (c == kFirstTimeColumn || c == kFirstTimeColumn + 1 || kHeader[c] == "prt") continue;
      if (kHeader[c] == "bytes_per_frame") continue;
      EXPECT_DOUBLE_EQ(std::stod(rows[row][c]), cell[kHeader[c]].get<double>())
          << kHeader[c] << " row " << row;
    }
    EXPECT_EQ(cell["config_yaml"], j["rows"][row - 1]["config_yaml"]);
  }
}

// A ground truth in another format (LSGDDN loopinf) and every second frame:
// the sweep's row equals lsgd eval's with the same flags (one dataset module).
TEST_F(SweepCli, ReadsEveryFormatAndSelectionThatEvalReads) {
  // loopinf: line k is "k<TAB>j", j the first true match of query k or -1.
  const lsgd::eval::GroundTruth gt =
      lsgd::eval::read_pairs((dir_ / "groundtruth.txt").string(), frames_);
  const fs::path loopinf = kTmp / "loopinf.txt";
  {
    std::ofstream out(loopinf);
    for (std::int64_t q = 0; q < frames_; ++q) {
      std::int64_t match = -1;
      for (std::int64_t j = 0; j < q && match < 0; ++j) {
        if (gt.is_loop(q, j)) match = j;
      }
      out << q << "\t" << match << "\n";
    }
  }
  const fs::path csv = kTmp / "fmt.csv", json = kTmp / "fmt.json";
  const std::string seq = (dir_ / "sequence.txt").string();
  const CmdResult r = lsgd_cli("sweep --dataset 'street=" + seq + "," + loopinf.string() +
                               ",10,gt-format=loopinf,every=2' --verify none --csv '" +
                               csv.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = csv_rows(csv);
  ASSERT_EQ(rows.size(), 2u);
  ASSERT_EQ(rows[0].size(), rows[1].size());
  std::map<std::string, std::string> row;  // no --set: no key columns
  for (std::size_t c = 0; c < rows[0].size(); ++c) row[rows[0][c]] = rows[1][c];
  EXPECT_EQ(row["frames"], std::to_string((frames_ + 1) / 2));  // every second frame
  const CmdResult e = lsgd_cli("eval --sequence '" + seq + "' --gt '" + loopinf.string() +
                               "' --gt-format loopinf --every 2 --min-gap 10 --verify none --json '" +
                               json.string() + "'");
  ASSERT_EQ(e.code, 0) << e.err;
  const auto cell = nlohmann::json::parse(slurp(json));
  for (const char* metric : {"frames", "positives", "declared_loops", "declared_true",
                             "declared_false", "recall_at_100_precision", "recall_at_1"}) {
    ASSERT_EQ(row.count(metric), 1u) << metric;
    EXPECT_DOUBLE_EQ(std::stod(row[metric]), cell[metric].get<double>()) << metric;
  }
  EXPECT_GT(cell["positives"].get<double>(), 5);
}

TEST_F(SweepCli, ParallelJobsGiveTheSameScores) {
  const fs::path one = kTmp / "one.csv", two = kTmp / "two.csv";
  const std::string grid = " --set search.mode=exhaustive,nodes --set search.nodes.beta=0.9,1.1";
  const CmdResult a = lsgd_cli("sweep " + dataset() + grid + " --csv '" + one.string() + "'");
  ASSERT_EQ(a.code, 0) << a.err;
  const CmdResult b =
      lsgd_cli("sweep " + dataset() + grid + " --jobs 3 --csv '" + two.string() + "'");
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_NE(b.out.find("NOT comparable"), std::string::npos) << b.out;
  EXPECT_EQ(a.out.find("NOT comparable"), std::string::npos) << a.out;
  auto x = csv_rows(one), y = csv_rows(two);
  ASSERT_EQ(x.size(), 5u);
  ASSERT_EQ(y.size(), x.size());
  for (std::size_t i = 1; i < x.size(); ++i) {  // timing columns aside, byte-identical rows
    for (auto* row : {&x[i], &y[i]}) {
      (*row)[kFirstTimeColumn - 1] = "";  // prt: AP / (1 + 10 t), t the mean time
      (*row)[kFirstTimeColumn] = (*row)[kFirstTimeColumn + 1] = "";
    }
    EXPECT_EQ(x[i], y[i]) << i;
  }
}

TEST_F(SweepCli, BadSetFailsBeforeAnyRunOrOutput) {
  const fs::path csv = kTmp / "never.csv";
  const CmdResult r = lsgd_cli("sweep " + dataset() +
                               " --set search.mode=exhaustive --set segmentation.superpixel_sze=30"
                               " --csv '" +
                               csv.string() + "'");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("superpixel_sze"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(csv));
  EXPECT_EQ(r.out, "");
  const CmdResult gap = lsgd_cli("sweep " + dataset() + " --set search.min_gap=5");
  EXPECT_EQ(gap.code, 1);
  EXPECT_NE(gap.err.find("--dataset"), std::string::npos) << gap.err;
  // A fixed flag the grid would override, or a window the datasets replace,
  // is refused, not dropped without a word.
  for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
           {" --option search.min_gap=3", "--option search.min_gap: the window is set per dataset"},
           {" --min-gap 3", "unknown option --min-gap"},
           {" --mode nodes --set search.mode=index",
            "--set search.mode=index sweeps search.mode, which --mode also sets: give one"},
           {" --threshold 3 --set decision.threshold=5,6", "which --threshold also sets"},
           {" --option search.top_n=3 --set search.top_n=5", "which --option search.top_n also sets"}}) {
    const CmdResult refused = lsgd_cli("sweep " + dataset() + args + " --csv '" + csv.string() + "'");
    EXPECT_EQ(refused.code, 1) << args;
    EXPECT_NE(refused.err.find(expected), std::string::npos) << args << ": " << refused.err;
    EXPECT_FALSE(fs::exists(csv));
  }
  const CmdResult missing = lsgd_cli("sweep --dataset x='" + (kTmp / "nowhere").string() + "',5");
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.err.find("nowhere"), std::string::npos) << missing.err;
}

// A second dataset whose last image is corrupt: sweep goes through the frame
// loop of lsgd eval, so it skips the image (reported once per dataset, not
// once per cell) and scores it as a frame without a report, exactly as eval
// does; under --strict the sweep fails on it, after the first dataset's rows
// were written.
TEST_F(SweepCli, ABadImageIsSkippedAsByEvalOrStopsUnderStrict) {
  const fs::path broken = kTmp / "broken";
  fs::create_directories(broken);
  std::ofstream(broken / "bad.png") << "not a png";
  std::ofstream list(broken / "sequence.txt");
  for (std::int64_t i = 0; i < 30; ++i)
    list << (dir_ / "images").string() << "/" << std::setw(6) << std::setfill('0') << i << ".png\n";
  list << "bad.png\n";
  list.close();
  std::ofstream(broken / "groundtruth.txt") << "25 1\n";
  const fs::path csv = kTmp / "partial.csv";
  const std::string args = "sweep " + dataset() + " --dataset broken='" + broken.string() +
                           "',5 --set search.mode=exhaustive,nodes --csv '" + csv.string() + "'";
  const CmdResult strict = lsgd_cli(args + " --strict");
  EXPECT_EQ(strict.code, 1);
  EXPECT_NE(strict.err.find("bad.png"), std::string::npos) << strict.err;
  EXPECT_NE(strict.err.find("broken"), std::string::npos) << strict.err;
  auto rows = csv_rows(csv);
  ASSERT_EQ(rows.size(), 3u);  // header + the two rows of the good dataset
  EXPECT_EQ(rows[1][0], "street");
  EXPECT_EQ(rows[2][0], "street");

  const CmdResult r = lsgd_cli(args);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string skip = "skipped frame 30 (" + (broken / "bad.png").string() + ")";
  const auto at = r.err.find(skip);
  EXPECT_NE(at, std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(skip, at + 1), std::string::npos) << "reported twice:\n" << r.err;
  rows = csv_rows(csv);
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_EQ(rows[3][0], "broken");
  const std::size_t skipped_column = rows[0].size() - 3;  // skipped_frames, then decision_*
  ASSERT_EQ(rows[0][skipped_column], "skipped_frames");
  EXPECT_EQ(rows[3][skipped_column], "1");
  EXPECT_EQ(rows[1][skipped_column], "0");
  const fs::path out = kTmp / "broken.json";
  const CmdResult e = lsgd_cli("eval --sequence '" + (broken / "sequence.txt").string() +
                               "' --gt '" + (broken / "groundtruth.txt").string() +
                               "' --min-gap 5 --mode exhaustive --json '" + out.string() + "'");
  ASSERT_EQ(e.code, 0) << e.err;
  const auto cell = nlohmann::json::parse(slurp(out));
  EXPECT_EQ(cell["skipped_frames"], 1);
  for (std::size_t c = 4; c < kHeader.size(); ++c) {
    if (c == kFirstTimeColumn || c == kFirstTimeColumn + 1 || kHeader[c] == "prt") continue;
    if (kHeader[c] == "bytes_per_frame" || kHeader[c] == "nodes") continue;
    EXPECT_DOUBLE_EQ(std::stod(rows[3][c - 1]), cell[kHeader[c]].get<double>()) << kHeader[c];
  }
}

#endif  // LSGD_CLI

}  // namespace
