// Sweep grids (parsing, exact ranges, cross-product order, validation) and
// `lsgd sweep` end to end on a short synthetic sequence written by the test.
#include "lsgd/eval/sweep.h"

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
#include "synthetic/synthetic.h"
#include "lsgd/io/config.h"
#include "test_util.h"

namespace fs = std::filesystem;
using lsgd::InvalidArgument;
using lsgd::eval::expand_sweep;
using lsgd::eval::parse_dataset_spec;
using lsgd::eval::parse_sweep_axis;
using lsgd::eval::SweepAxis;
using lsgd::test::message_of;
using Strings = std::vector<std::string>;

namespace {

// ---------------------------------------------------------------- axes

TEST(SweepAxis, CommaList) {
  const SweepAxis a = parse_sweep_axis("search.mode=exhaustive, nodes");
  EXPECT_EQ(a.key, "search.mode");
  EXPECT_EQ(a.values, (Strings{"exhaustive", "nodes"}));
  EXPECT_EQ(a.spec, "search.mode=exhaustive, nodes");
}

TEST(SweepAxis, IntegerRangeIsInclusive) {
  EXPECT_EQ(parse_sweep_axis("segmentation.superpixel_size=10:100:10").values,
            (Strings{"10", "20", "30", "40", "50", "60", "70", "80", "90", "100"}));
  EXPECT_EQ(parse_sweep_axis("k=10:95:10").values.back(), "90");  // the end is not on the grid
  EXPECT_EQ(parse_sweep_axis("k=5:5:1").values, (Strings{"5"}));
  EXPECT_EQ(parse_sweep_axis("k=-1:1:1").values, (Strings{"-1", "0", "1"}));
}

TEST(SweepAxis, FloatRangeDoesNotDrift) {
  EXPECT_EQ(parse_sweep_axis("search.nodes.beta=0.9:1.1:0.1").values,
            (Strings{"0.9", "1.0", "1.1"}));
  // 3 * 0.1 > 0.3 in binary floating point: a naive loop would drop the end.
  EXPECT_EQ(parse_sweep_axis("k=0:0.3:0.1").values, (Strings{"0.0", "0.1", "0.2", "0.3"}));
  const Strings many = parse_sweep_axis("k=0:1:0.01").values;
  ASSERT_EQ(many.size(), 101u);
  EXPECT_EQ(many[29], "0.29");
  EXPECT_EQ(many.back(), "1.00");
  EXPECT_EQ(parse_sweep_axis("k=1:0:-0.25").values,
            (Strings{"1.00", "0.75", "0.50", "0.25", "0.00"}));
  EXPECT_EQ(parse_sweep_axis("k=-0.5:0.5:.5").values, (Strings{"-0.5", "0.0", "0.5"}));
}

TEST(SweepAxis, ItemsMayMixRangesAndValues) {
  EXPECT_EQ(parse_sweep_axis("k=10:30:10,100").values, (Strings{"10", "20", "30", "100"}));
}

TEST(SweepAxis, SemicolonSeparatesItemsHoldingCommas) {
  EXPECT_EQ(parse_sweep_axis("verification.stages=none;temporal,geometric").values,
            (Strings{"none", "temporal,geometric"}));
}

TEST(SweepAxis, BadSpecsNameTheSpec) {
  for (const char* spec :
       {"search.mode", "=1", "a..b=1", "a.b c=1", "k=", "k=1,,2", "k=1 2", "k=a:b:c", "k=1:2",
        "k=1:2:3:4", "k=1:2:0", "k=1:0:1", "k=0:1:-1", "k=0:1e6:1", "k=0:100000:1", "k=x:y",
        "k={a: 1}", "k=1#2", "k=0.1234567891:1:1"}) {
    const std::string message = message_of<InvalidArgument>([&] { parse_sweep_axis(spec); });
    EXPECT_NE(message.find(std::string("'") + spec + "'"), std::string::npos)
        << spec << " -> " << message;
  }
}

// ---------------------------------------------------------------- grids

TEST(SweepGrid, CrossProductInTheOrderGiven) {
  const auto points = expand_sweep({parse_sweep_axis("segmentation.superpixel_size=30,40"),
                                    parse_sweep_axis("search.mode=exhaustive,nodes")},
                                   {});
  ASSERT_EQ(points.size(), 4u);
  const Strings expected[] = {
      {"30", "exhaustive"}, {"30", "nodes"}, {"40", "exhaustive"}, {"40", "nodes"}};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(points[i].values, expected[i]) << i;
    EXPECT_EQ(points[i].options.segmentation.superpixel_size, i < 2 ? 30 : 40) << i;
    EXPECT_EQ(points[i].options.search.mode,
              i % 2 ? lsgd::kNodesSearch : lsgd::kExhaustiveSearch)
        << i;
  }
}

TEST(SweepGrid, ThreeAxesTurnLikeNestedLoops) {
  const auto points = expand_sweep(
      {parse_sweep_axis("search.top_n=1,2"), parse_sweep_axis("search.mode=exhaustive,nodes"),
       parse_sweep_axis("search.nodes.beta=0.9:1.1:0.1")},
      {});
  ASSERT_EQ(points.size(), 12u);
  EXPECT_EQ(points[0].values, (Strings{"1", "exhaustive", "0.9"}));
  EXPECT_EQ(points[2].values, (Strings{"1", "exhaustive", "1.1"}));
  EXPECT_EQ(points[3].values, (Strings{"1", "nodes", "0.9"}));
  EXPECT_EQ(points[11].values, (Strings{"2", "nodes", "1.1"}));
  EXPECT_EQ(points[11].options.search.nodes.beta, 1.1);  // the double nearest 1.1, exactly
  EXPECT_EQ(points[4].options.search.nodes.beta, 1.0);
}

TEST(SweepGrid, ValuesApplyOnTopOfTheBase) {
  lsgd::DetectorOptions base;
  base.segmentation.superpixel_size = 25;
  lsgd::parse_verification_stages("none", base.verification);
  base.search.nodes.alpha = 0.5;
  base.search.mode = "nodes";  // where search.nodes.beta applies
  const auto points = expand_sweep({parse_sweep_axis("search.nodes.beta=0.8")}, base);
  ASSERT_EQ(points.size(), 1u);
  lsgd::DetectorOptions expected = base;
  expected.search.nodes.beta = 0.8;
  EXPECT_EQ(lsgd::io::to_yaml(points[0].options), lsgd::io::to_yaml(expected));
}

// An option that applies in no configuration of the grid gave identical
// rows read as "it does not matter": refused, saying when it applies; one
// that applies in some configurations is swept.
TEST(SweepGrid, AnOptionThatAppliesNowhereIsRefused) {
  for (const auto& [spec, when] : std::vector<std::pair<std::string, std::string>>{
           {"search.nodes.beta=0.5,1.5", "in nodes mode"},
           {"descriptor.gradient.threshold=0.5,5", "with the gradient descriptor"}}) {
    const std::string m = message_of<InvalidArgument>([&] { expand_sweep({parse_sweep_axis(spec)}, {}); });
    EXPECT_NE(m.find("has no effect in any configuration of the grid (it applies " + when + ")"),
              std::string::npos) << m;
  }
  EXPECT_EQ(expand_sweep({parse_sweep_axis("search.nodes.beta=0.5,1.5"),
                          parse_sweep_axis("search.mode=exhaustive,nodes")}, {}).size(), 4u);
}

// A value given twice, or two spellings of one value, ran the same
// configuration twice and printed identical rows (issue 35, seventh pass).
TEST(SweepGrid, AValueGivenTwiceIsRefused) {
  for (const std::string spec : {"decision.threshold=5,5", "decision.threshold=5,5.0",
                                 "decision.threshold=4:6:1,5", "search.mode=index,nodes,index"}) {
    const std::string m = message_of<InvalidArgument>([&] { expand_sweep({parse_sweep_axis(spec)}, {}); });
    EXPECT_NE(m.find("(the same configuration twice, identical rows): give each value once"),
              std::string::npos) << m;
    EXPECT_NE(m.find("sweep '" + spec + "'"), std::string::npos) << m;
  }
  EXPECT_EQ(expand_sweep({parse_sweep_axis("decision.threshold=5,5.5")}, {}).size(), 2u);
}

TEST(SweepGrid, NoAxesIsTheBase) {
  lsgd::DetectorOptions base;
  base.segmentation.superpixel_size = 17;
  const auto points = expand_sweep({}, base);
  ASSERT_EQ(points.size(), 1u);
  EXPECT_TRUE(points[0].values.empty());
  EXPECT_EQ(lsgd::io::to_yaml(points[0].options), lsgd::io::to_yaml(base));
}

TEST(SweepGrid, BadKeysAndValuesNameTheSpec) {
  struct Case {
    const char* spec;
    const char* detail;  // also in the message
  };
  for (const Case& c : {Case{"segmentation.superpixel_sze=30,40", "superpixel_sze"},
                        Case{"segmentation.superpixel_size=1,40", "out of range"},
                        Case{"segmentation.superpixel_size=3.5", "integer"},
                        Case{"search.mode=exhaustive,bogus", "bogus"},
                        Case{"search.nodes=1", "map"}, Case{"nothing.at_all=1", "nothing"},
                        Case{"verification.stages=none;temporal,bogus", "bogus"}}) {
    const std::string message = message_of<InvalidArgument>([&] {
      expand_sweep({parse_sweep_axis("search.top_n=5"), parse_sweep_axis(c.spec)}, {});
    });
    EXPECT_NE(message.find(std::string("'") + c.spec + "'"), std::string::npos)
        << c.spec << " -> " << message;
    EXPECT_NE(message.find(c.detail), std::string::npos) << c.spec << " -> " << message;
    EXPECT_EQ(message.find("(line "), std::string::npos) << message;  // no line of hidden YAML
  }
}

// Each dataset has its own window (sweep_cells sets it): a swept one would be
// dropped without a word, so it is refused naming the spec.
TEST(SweepGrid, TheWindowIsNotSwept) {
  const std::string message =
      message_of<InvalidArgument>([] { expand_sweep({parse_sweep_axis("search.min_gap=5,10")}, {}); });
  EXPECT_NE(message.find("sweep 'search.min_gap=5,10': the window is set per dataset"), std::string::npos)
      << message;
}

// The same for a window in the options the grid is applied on (Python's
// lsgd.sweep(options=...), a --config).
TEST(SweepGrid, AWindowInTheOptionsIsRefused) {
  lsgd::DetectorOptions base;
  base.search.min_gap = 3;
  const std::string message = message_of<InvalidArgument>([&] { expand_sweep({}, base); });
  EXPECT_NE(message.find("the sweep's options set search.min_gap = 3: the window is set per dataset"),
            std::string::npos)
      << message;
}

TEST(SweepGrid, KeySweptTwiceIsAnError) {
  const std::string message = message_of<InvalidArgument>([] {
    expand_sweep({parse_sweep_axis("search.top_n=1"), parse_sweep_axis("search.top_n=2")}, {});
  });
  EXPECT_NE(message.find("already swept"), std::string::npos) << message;
}

// A grid of more than 10,000 configurations is refused before any point is
// parsed (a million took minutes and gigabytes before the first run); 10,000
// are built.
TEST(SweepGrid, MoreThanTenThousandPointsAreRefusedAtOnce) {
  const std::string message = message_of<InvalidArgument>([] {
    expand_sweep({parse_sweep_axis("segmentation.superpixel_size=10:109:1"),
                  parse_sweep_axis("decision.threshold=1:100:1"), parse_sweep_axis("search.top_n=1:100:1")},
                 {});
  });
  EXPECT_NE(message.find("sweep: 1000000 configurations, more than the 10000 a sweep runs"), std::string::npos)
      << message;
  // A grid far beyond 2^64 points is named too.
  std::vector<SweepAxis> huge;
  for (const char* key : {"decision.threshold", "decision.geometric_bonus", "decision.continuity_bonus",
                          "decision.strong_bonus", "decision.track_bonus", "decision.continuity_min_z"}) {
    huge.push_back(parse_sweep_axis(std::string(key) + "=1:10000:1"));
  }
  EXPECT_NE(message_of<InvalidArgument>([&] { expand_sweep(huge, {}); }).find("sweep: 1e+24 configurations"),
            std::string::npos);
  EXPECT_EQ(expand_sweep({parse_sweep_axis("decision.threshold=1:100:1"), parse_sweep_axis("search.top_n=1:100:1")},
                         {})
                .size(),
            10000u);
}

TEST(SweepGrid, YamlMergesSectionsSharingAPrefix) {
  EXPECT_EQ(lsgd::eval::sweep_yaml({"search.mode", "segmentation.superpixel_size",
                                    "search.nodes.beta", "search.nodes.alpha"},
                                   {"nodes", "30", "0.9", "0.7"}),
            "search:\n"
            "  mode: nodes\n"
            "  nodes:\n"
            "    beta: 0.9\n"
            "    alpha: 0.7\n"
            "segmentation:\n"
            "  superpixel_size: 30\n");
  EXPECT_THROW(lsgd::eval::sweep_yaml({"search.nodes", "search.nodes.beta"}, {"1", "2"}),
               InvalidArgument);
  EXPECT_THROW(lsgd::eval::sweep_yaml({"search.mode"}, {"a: b"}), InvalidArgument);
}

// ---------------------------------------------------------------- datasets

TEST(SweepDataset, BothForms) {
  const auto full = parse_dataset_spec("corridor=/d/seq.txt,/d/gt.txt,50");
  EXPECT_EQ(full.name, "corridor");
  EXPECT_EQ(full.sequence, "/d/seq.txt");
  EXPECT_EQ(full.ground_truth, "/d/gt.txt");
  EXPECT_EQ(full.min_gap, 50);
  const auto dir = parse_dataset_spec("nordland-trimmed=/data/nordland,100");
  EXPECT_EQ(dir.name, "nordland-trimmed");
  EXPECT_EQ(dir.sequence, "/data/nordland/sequence.txt");
  EXPECT_EQ(dir.ground_truth, "/data/nordland/groundtruth.txt");
  EXPECT_EQ(dir.min_gap, 100);
}

TEST(SweepDataset, BadSpecsNameTheSpec) {
  for (const char* spec :
       {"/d/seq.txt,/d/gt.txt,50", "=/d,50", "a b=/d,50", "a|b=/d,50", "x=/d", "x=/d,/g,/h,50",
        "x=/d,-1", "x=/d,5.5", "x=/d,fifty", "x=,/g,50", "x=/d,"}) {
    const std::string message = message_of<InvalidArgument>([&] { parse_dataset_spec(spec); });
    EXPECT_NE(message.find(std::string("'") + spec + "'"), std::string::npos)
        << spec << " -> " << message;
  }
}

// A dataset option given twice kept the last without a word.
TEST(SweepDataset, AnOptionGivenTwiceIsRefused) {
  const std::string message =
      message_of<InvalidArgument>([] { parse_dataset_spec("c=/d,50,every=2,every=3"); });
  EXPECT_NE(message.find("every is given twice: give it once"), std::string::npos) << message;
}

// Dataset options after the parts: lsgd eval's layout and ground-truth flags.
TEST(SweepDataset, OptionsAfterThePartsAreEvalsDatasetFlags) {
  const auto k = parse_dataset_spec(
      "kitti05=/kitti,/poses/05.txt,100,layout=kitti,kitti-sequence=5,camera=2,gt-format=kitti-poses,"
      "first=10,every=2,subsample-match=block");
  EXPECT_EQ(k.sequence, "/kitti");
  EXPECT_EQ(k.ground_truth, "/poses/05.txt");
  EXPECT_EQ(k.min_gap, 100);
  EXPECT_EQ(k.sequence_options.layout, lsgd::io::kKittiLayout);
  EXPECT_EQ(k.sequence_options.kitti_sequence, "5");
  EXPECT_EQ(k.sequence_options.camera, 2);
  EXPECT_EQ(k.sequence_options.selection.first, 10);
  EXPECT_EQ(k.sequence_options.selection.every, 2);
  EXPECT_EQ(k.gt_options.format, std::string(lsgd::eval::kKittiPosesGtFormat));
  EXPECT_EQ(k.gt_options.match, lsgd::eval::SubsampleMatch::kBlock);
  const auto f = parse_dataset_spec("cc=/cc,20,layout=fabmap,side=both,gt-rows=image");
  EXPECT_EQ(f.sequence, "/cc/sequence.txt");
  EXPECT_EQ(f.sequence_options.side, lsgd::io::Side::kBoth);
  EXPECT_EQ(f.gt_options.rows, lsgd::eval::GtRows::kImage);
  for (const char* spec : {"x=/d,50,every=0", "x=/d,50,colour=2", "x=/d,50,every=two",
                           "x=/d,50,layout=tree", "x=/d,50,gt-format=csv", "x=/d,50,every=2,/g",
                           "x=/d,50,=3"}) {
    const std::string message = message_of<InvalidArgument>([&] { parse_dataset_spec(spec); });
    EXPECT_NE(message.find(std::string("'") + spec + "'"), std::string::npos)
        << spec << " -> " << message;
  }
}

// ---------------------------------------------------------------- lsgd sweep, end to end

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
    fs::remove_all(dir_);
    lsgd::eval::SyntheticOptions options;
    options.width = 160;
    options.height = 120;
    options.route_scale = 0.2;
    const lsgd::eval::SyntheticWorld world(options);
    frames_ = world.frames();
    lsgd::eval::write_synthetic_dataset(world, dir_.string());
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
