// End-to-end tests of `lsgd eval` beyond the strict run: scoring detections
// files, the lenient reference protocol, subsampling and dataset layouts.
// They run the real binary on a short synthetic street and tiny layouts.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <set>
#include <string>

#include "eval_cli_test_support.h"
#include "test_util.h"
#include "lsgd/eval/groundtruth.h"
#include "lsgd/eval/gt_formats.h"
#include "lsgd/eval/gt_remap.h"
#include "lsgd/io/database.h"
#include "synthetic/synthetic.h"

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

// A short synthetic street (about 330 frames, 160x120) and the CSV `lsgd run` wrote for it.
class ShortStreet : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = kTmp / "street";
    const lsgd::eval::SyntheticWorld world = lsgd::test::write_street(dir_, 0.3);
    frames_ = world.frames();
    gt_ = world.ground_truth();
    const CmdResult r =
        lsgd("run --sequence " + q(dir_ / "sequence.txt") + " --output " + q(dir_ / "run.csv"));
    ASSERT_EQ(r.code, 0) << r.err;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static std::string common(const fs::path& json) {
    return " --gt " + q(dir_ / "groundtruth.txt") + " --min-gap 50 --json " + q(json);
  }

  static fs::path dir_;
  static std::int64_t frames_;
  static lsgd::eval::GroundTruth gt_;
};
fs::path ShortStreet::dir_;
std::int64_t ShortStreet::frames_ = 0;
lsgd::eval::GroundTruth ShortStreet::gt_;

// The street as two traverses: its first 90 frames (ref.txt) and the rest
// (query.txt), image paths absolute.
void write_traverses(const fs::path& dir) {
  std::ifstream all(dir / "sequence.txt");
  std::ofstream ref(kTmp / "ref.txt"), query(kTmp / "query.txt");
  std::string line;
  for (int i = 0; std::getline(all, line); ++i) {
    // Relative image paths are the list's own: written absolute here.
    const std::string image = fs::path(line).is_absolute() ? line : (dir / line).string();
    (i < 90 ? ref : query) << image << "\n";
  }
  ref.close();
  query.close();
}

// lsgd match: the street's revisits (frames 90 on) as a query traverse
// against its first 90 frames; the top-k file scores with lsgd eval
// --detections, its ranks giving R@N; another frame size is refused.
TEST_F(ShortStreet, MatchOneTraverseAgainstAnother) {
  write_traverses(dir_);
  std::string line;
  const CmdResult r = lsgd("match --reference " + q(kTmp / "ref.txt") + " --query " + q(kTmp / "query.txt") +
                           " --top-k 5 --output " + q(kTmp / "match.csv"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("query ids from 90"), std::string::npos) << r.err;
  std::ifstream rows(kTmp / "match.csv");
  std::getline(rows, line);
  EXPECT_EQ(line, "query,match,score,similarity,rank");
  std::int64_t n = 0;
  for (; std::getline(rows, line); ++n) {
    if (n == 0) {
      EXPECT_EQ(line.rfind("90,", 0), 0u) << line;
    }
  }
  EXPECT_EQ(n, 5 * (frames_ - 90));
  // The ground truth between the traverses: query frames 90 on, reference frames before 90.
  {
    std::ifstream in(dir_ / "groundtruth.txt");
    std::ofstream out(kTmp / "between.txt");
    for (std::string pair; std::getline(in, pair);) {
      std::int64_t a = -1, b = -1;
      if (pair.empty() || pair[0] == '#' || !(std::istringstream(pair) >> a >> b)) continue;
      if (a >= 90 && b < 90) out << a << " " << b << "\n";
    }
  }
  const fs::path json = kTmp / "match.json";
  const CmdResult e = lsgd("eval --detections " + q(kTmp / "match.csv") + " --gt " + q(kTmp / "between.txt") +
                           " --frames " + std::to_string(frames_) + " --min-gap 0 --json " + q(json));
  ASSERT_EQ(e.code, 0) << e.err;
  const auto j = read_json(json);
  EXPECT_GT(j["recall_at_1"].get<double>(), 0.3);
  EXPECT_GT(j["recall_at_5"].get<double>(), j["recall_at_1"].get<double>());
  // Flags that would be ignored are errors.
  for (const char* flag : {" --min-gap 5", " --verify none", " --option search.top_n=3"}) {
    const CmdResult ignored = lsgd("match --reference " + q(kTmp / "ref.txt") + " --query " +
                                   q(kTmp / "query.txt") + flag);
    EXPECT_EQ(ignored.code, 1) << flag;
    EXPECT_NE(ignored.err.find("has no effect on lsgd match"), std::string::npos) << ignored.err;
  }
}

// lsgd match skips an image of another size, or one that cannot be read,
// and reports it, as lsgd run does; --strict stops there, naming it.
TEST_F(ShortStreet, MatchSkipsAnImageItCannotUseAndStrictStops) {
  write_traverses(dir_);
  const fs::path small = kTmp / "small";
  fs::create_directories(small);
  write_image(small / "a.png", 1);
  {  // and one of the traverses' size: a query with nothing read is an error (eval_inputs_cli_test)
    std::string first;
    std::getline(std::ifstream(kTmp / "ref.txt"), first);
    fs::copy_file(first, small / "b.png");
  }
  const std::string against_small = "match --reference " + q(kTmp / "ref.txt") + " --query " + q(small);
  const CmdResult other = lsgd(against_small);
  EXPECT_EQ(other.code, 0) << other.err;
  EXPECT_NE(other.err.find("skipping --query image 0: ("), std::string::npos) << other.err;
  EXPECT_NE(other.err.find("the frame is 64x48, not 160x120 as the frames before it"), std::string::npos)
      << other.err;
  EXPECT_NE(other.err.find("nothing was decoded"), std::string::npos) << other.err;  // from its header
  EXPECT_NE(other.err.find("skipped 0 reference and 1 query images"), std::string::npos) << other.err;
  EXPECT_EQ(other.out.rfind("query,match,score,similarity,rank\n", 0), 0u) << other.out;
  EXPECT_EQ(lines_of(other.out), 2) << other.out;  // the header and b.png's best match
  const CmdResult strict = lsgd(against_small + " --strict");
  EXPECT_EQ(strict.code, 1);
  EXPECT_NE(strict.err.find("--query image 0: ("), std::string::npos) << strict.err;
  EXPECT_EQ(strict.err.find("skipping"), std::string::npos) << strict.err;
}

// A reference image that cannot be read keeps every other image's number.
TEST_F(ShortStreet, MatchKeepsTheNumbersOfTheImagesAfterAMissingReference) {
  write_traverses(dir_);
  std::string line;
  {
    std::ifstream in(kTmp / "ref.txt");
    std::ofstream out(kTmp / "ref-missing.txt");
    for (int i = 0; std::getline(in, line); ++i) out << (i == 3 ? (kTmp / "missing.png").string() : line) << "\n";
  }
  const CmdResult missing = lsgd("match --reference " + q(kTmp / "ref-missing.txt") + " --query " +
                                 q(kTmp / "query.txt") + " --top-k 90 --output " + q(kTmp / "m2.csv"));
  ASSERT_EQ(missing.code, 0) << missing.err;
  EXPECT_NE(missing.err.find("skipping --reference image 3:"), std::string::npos) << missing.err;
  std::ifstream m2(kTmp / "m2.csv");
  std::getline(m2, line);
  std::int64_t rows_read = 0;
  std::set<std::int64_t> matched, queried;
  for (; std::getline(m2, line); ++rows_read) {
    std::istringstream fields(line);
    std::string query_id, match_id;
    std::getline(fields, query_id, ',');
    std::getline(fields, match_id, ',');
    queried.insert(std::stoll(query_id));
    matched.insert(std::stoll(match_id));
  }
  EXPECT_EQ(rows_read, 89 * (frames_ - 90));  // every reference read, for every query
  EXPECT_EQ(matched.count(3), 0u);
  EXPECT_EQ(matched.size(), 89u);
  EXPECT_EQ(*matched.rbegin(), 89);
  EXPECT_EQ(*queried.begin(), 90);
}

TEST_F(ShortStreet, RunCsvScoredAsDetectionsMatchesEval) {
  const fs::path online = kTmp / "online.json", offline = kTmp / "offline.json";
  const CmdResult a = lsgd("eval --sequence " + q(dir_ / "sequence.txt") + common(online));
  ASSERT_EQ(a.code, 0) << a.err;
  const CmdResult b = lsgd("eval --detections " + q(dir_ / "run.csv") + common(offline));
  ASSERT_EQ(b.code, 0) << b.err;
  const auto x = read_json(online), y = read_json(offline);
  EXPECT_EQ(y["frames"], frames_);  // the CSV's frames extend the pairs file's ids
  EXPECT_EQ(x["frames"], y["frames"]);
  EXPECT_EQ(x["positives"], y["positives"]);
  EXPECT_GT(x["positives"].get<int>(), 20);
  EXPECT_GT(x["average_precision"].get<double>(), 0.1);  // not a trivially equal zero
  EXPECT_DOUBLE_EQ(x["recall_at_100_precision"].get<double>(),
                   y["recall_at_100_precision"].get<double>());
  EXPECT_DOUBLE_EQ(x["average_precision"].get<double>(), y["average_precision"].get<double>());
  // The decision's own, from the CSV's loop scores, alike.
  for (const char* key : {"decision_recall_at_100_precision", "decision_average_precision"}) {
    EXPECT_DOUBLE_EQ(x[key].get<double>(), y[key].get<double>()) << key;
  }
  EXPECT_EQ(y["detections"], (dir_ / "run.csv").string());
  // Per-stage p95 and peak memory, as the protocol asks.
  EXPECT_GT(x["stage_ms_p95"]["segment"].get<double>(), 0.0);
  EXPECT_GE(x["stage_ms_p95"]["segment"].get<double>(),
            x["stage_ms_median"]["segment"].get<double>());
  EXPECT_GT(x["peak_rss_mb"].get<double>(), 1.0);
  EXPECT_NE(b.out.find("no detector run"), std::string::npos) << b.out;
  // The operating point: the loops lsgd declared, the same from the run and
  // from its CSV, next to R@100P everywhere.
  for (const char* key : {"declared_loops", "declared_true", "declared_false",
                          "precision_at_decision", "recall_at_decision"}) {
    ASSERT_TRUE(x.contains(key)) << key;
    EXPECT_EQ(x[key], y[key]) << key;
  }
  EXPECT_GT(x["declared_loops"].get<int>(), 5);
  EXPECT_EQ(x["declared_false"].get<int>(), 0);  // defaults: no false loop on the street
  EXPECT_EQ(x["declared_true"].get<int>() + x["declared_false"].get<int>(),
            x["declared_loops"].get<int>());
  EXPECT_NEAR(x["recall_at_decision"].get<double>(),
              x["declared_true"].get<double>() / x["positives"].get<double>(), 1e-12);
  EXPECT_NE(a.out.find("loops declared " + std::to_string(x["declared_loops"].get<int>())),
            std::string::npos)
      << a.out;
  EXPECT_TRUE(x["warnings"].empty()) << x["warnings"];
}

// R@100P, AP and the curve come from the ranking, which no decision setting
// changes (issue 32: they moved with --threshold); the decision's own are
// reported apart and do move.
TEST_F(ShortStreet, RankingMetricsDoNotMoveWithTheDecisionSettings) {
  std::vector<nlohmann::json> runs;
  for (const std::string flags :
       {"", " --threshold 5 --option decision.continuity_bonus=1 --option decision.continuity_gap=0",
        " --threshold 12 --option decision.strong_bonus=0 --option decision.track_bonus=3 "
        "--option decision.continuity_gap=10"}) {
    const fs::path json = kTmp / ("threshold-" + std::to_string(runs.size()) + ".json");
    const CmdResult r = lsgd("eval --sequence " + q(dir_ / "sequence.txt") + common(json) + flags);
    ASSERT_EQ(r.code, 0) << r.err;
    runs.push_back(read_json(json));
  }
  EXPECT_GT(runs[0]["recall_at_100_precision"].get<double>(), 0.1);
  for (const auto& j : runs) {
    for (const char* key : {"recall_at_100_precision", "average_precision", "threshold_at_100_precision",
                            "recall_at_1", "pr_curve"}) {
      EXPECT_EQ(j[key], runs[0][key]) << key;
    }
  }
  EXPECT_NE(runs[2]["declared_loops"], runs[0]["declared_loops"]);  // the decision did change
  EXPECT_NE(runs[2]["decision_average_precision"], runs[0]["decision_average_precision"]);
}

// --compare scores another system's detections with the same evaluator as
// the run: its metrics equal `lsgd eval --detections` of the same file, and
// the report draws both on one PR plot.
TEST_F(ShortStreet, CompareScoresAnotherSystemWithTheSameEvaluator) {
  const fs::path json = kTmp / "compare.json", alone = kTmp / "alone.json", html = kTmp / "compare.html";
  const CmdResult a = lsgd("eval --sequence " + q(dir_) + common(json) + " --report " + q(html) +
                           " --compare " + q(dir_ / "run.csv") + " --compare 'mine=" +
                           (dir_ / "run.csv").string() + "'");
  ASSERT_EQ(a.code, 0) << a.err;
  const CmdResult b = lsgd("eval --detections " + q(dir_ / "run.csv") + common(alone));
  ASSERT_EQ(b.code, 0) << b.err;
  const auto x = read_json(json), y = read_json(alone);
  ASSERT_EQ(x["compared"].size(), 2u);
  EXPECT_EQ(x["compared"][0]["name"], "run");
  EXPECT_EQ(x["compared"][1]["name"], "mine");
  for (const char* key : {"declared_loops", "declared_false", "recall_at_100_precision",
                          "average_precision", "recall_at_1"}) {
    EXPECT_EQ(x["compared"][0][key], y[key]) << key;
    EXPECT_EQ(x["compared"][0][key], x[key]) << key;  // the CSV is this very run's
  }
  EXPECT_NE(a.out.find("compared: mine ("), std::string::npos) << a.out;
  const std::string report = lsgd::test::slurp(html);
  EXPECT_NE(report.find("<polyline class='pr-compared'"), std::string::npos);
  EXPECT_NE(report.find("mine (AP "), std::string::npos);
  EXPECT_NE(report.find("src='data:image/jpeg;base64,"), std::string::npos);  // thumbnails
  EXPECT_NE(report.find("<svg class='timeline'"), std::string::npos);         // no poses
  EXPECT_NE(report.find("lsgd eval --sequence"), std::string::npos);          // the command
  const CmdResult missing = lsgd("eval --sequence " + q(dir_) + common(json) + " --compare " +
                                 q(kTmp / "no-such.csv"));
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.err.find("no-such.csv"), std::string::npos) << missing.err;
  // Two systems of one name: refused before the run, naming both.
  const CmdResult twice = lsgd("eval --sequence " + q(dir_) + common(json) + " --compare 'x=" +
                               (dir_ / "run.csv").string() + "' --compare 'x=" + (dir_ / "run.csv").string() + "'");
  EXPECT_EQ(twice.code, 1);
  EXPECT_NE(twice.err.find("are both named 'x'"), std::string::npos) << twice.err;
  EXPECT_EQ(twice.out, "");
}

// A setup the method cannot work in is said on stderr and in the JSON: frames
// of 64x32 give one grid cell at the default superpixel size, are too small
// for geometry, and the ground-truth loop comes before any candidate is scored.
TEST(EvalCli, DegenerateSetupIsWarnedAbout) {
  const fs::path dir = kTmp / "tiny";
  fs::remove_all(dir);
  std::string list;
  for (int i = 0; i < 50; ++i) {
    const std::string name = std::to_string(i) + ".png";
    fs::create_directories(dir);
    cv::Mat m(32, 64, CV_8UC1);
    cv::randu(m, 0, 255);
    ASSERT_TRUE(cv::imwrite((dir / name).string(), m));
    list += name + "\n";
  }
  write_text(dir / "sequence.txt", list);
  write_text(dir / "gt.txt", "15 2\n");  // before frame 18, the first scored (min gap 10)
  const fs::path json = kTmp / "tiny.json";
  const CmdResult r = lsgd("eval --sequence " + q(dir / "sequence.txt") + " --gt " +
                           q(dir / "gt.txt") + " --min-gap 10 --json " + q(json));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = read_json(json);
  ASSERT_EQ(j["warnings"].size(), 3u) << j["warnings"];
  EXPECT_NE(j["warnings"][0].get<std::string>().find("1x1 grid"), std::string::npos)
      << j["warnings"][0];
  EXPECT_NE(j["warnings"][0].get<std::string>().find("superpixel_size <= 16"), std::string::npos);
  EXPECT_NE(j["warnings"][1].get<std::string>().find("too small for geometric"),
            std::string::npos);
  EXPECT_NE(j["warnings"][2].get<std::string>().find("1 of 1 ground-truth loop queries"),
            std::string::npos)
      << j["warnings"][2];
  EXPECT_NE(r.err.find("lsgd: warning: frames of 64x32 give a 1x1 grid"), std::string::npos)
      << r.err;
}

TEST_F(ShortStreet, LenientProtocolSaysSoAndIsNeverStricter) {
  const fs::path strict = kTmp / "strict.json", lenient = kTmp / "lenient.json";
  ASSERT_EQ(lsgd("eval --detections " + q(dir_ / "run.csv") + common(strict)).code, 0);
  const CmdResult r = lsgd("eval --detections " + q(dir_ / "run.csv") + common(lenient) +
                           " --protocol lsgddn-reference");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("protocol: lsgddn-reference (lenient"), std::string::npos) << r.out;
  const auto s = read_json(strict), l = read_json(lenient);
  EXPECT_EQ(s["protocol"], "strict");
  EXPECT_EQ(l["protocol"], "lsgddn-reference");
  EXPECT_EQ(l["tolerance"], 50);
  EXPECT_NE(l["protocol_note"].get<std::string>().find("lenient"), std::string::npos);
  // Same positives; every strict hit is a lenient hit and lenient hides false positives.
  EXPECT_EQ(s["positives"], l["positives"]);
  EXPECT_GE(l["recall_at_100_precision"].get<double>(), s["recall_at_100_precision"].get<double>());
}

TEST_F(ShortStreet, EveryKeepsEveryKthFrameAndRemapsTheGroundTruth) {
  const fs::path json = kTmp / "every.json", csv = kTmp / "every.csv";
  const CmdResult r =
      lsgd("eval --sequence " + q(dir_ / "sequence.txt") + " --gt " + q(dir_ / "groundtruth.txt") +
           " --min-gap 16 --every 3 --json " + q(json) + " --output " + q(csv));
  ASSERT_EQ(r.code, 0) << r.err;
  const lsgd::eval::GroundTruth sub = lsgd::eval::subsample(gt_, 3);
  std::int64_t positives = 0;
  for (std::int64_t i = 0; i < sub.frames(); ++i) positives += sub.has_loop(i, 16) ? 1 : 0;
  const auto j = read_json(json);
  EXPECT_EQ(j["frames"], (frames_ + 2) / 3);
  EXPECT_EQ(j["every"], 3);
  EXPECT_EQ(j["ground_truth_pairs"], sub.pairs());
  EXPECT_EQ(j["positives"], positives);
  EXPECT_GT(positives, 10);
  const std::string rows = slurp(csv);
  // Frame 1 is image 3, frame 2 image 6.
  EXPECT_NE(rows.find("\n1," + (dir_ / "images/000003.png").string() + ","), std::string::npos);
  EXPECT_NE(rows.find("\n2," + (dir_ / "images/000006.png").string() + ","), std::string::npos);
}

TEST_F(ShortStreet, ReportWithPosesAndLoopinfGroundTruth) {
  // The LSGDDN authors' loopinf format (one GT index per frame, -1 for none),
  // written from the street's ground truth and read back by format detection.
  std::ostringstream loopinf;
  for (std::int64_t i = 0; i < frames_; ++i) {
    const auto& m = gt_.matches(i);
    loopinf << i << "\t" << (m.empty() ? -1 : m.front()) << "\n";
  }
  write_text(kTmp / "loopinf.txt", loopinf.str());
  std::ostringstream poses;  // 12-column KITTI poses: frame i at x = i, z = i % 40
  for (std::int64_t i = 0; i < frames_; ++i) {
    poses << "1 0 0 " << i << " 0 1 0 0 0 0 1 " << i % 40 << "\n";
  }
  write_text(kTmp / "poses.txt", poses.str());
  const fs::path json = kTmp / "report.json", html = kTmp / "report.html";
  const CmdResult r = lsgd("eval --sequence " + q(dir_ / "sequence.txt") + " --gt " +
                           q(kTmp / "loopinf.txt") + " --min-gap 50 --json " + q(json) +
                           " --report " + q(html) + " --poses " + q(kTmp / "poses.txt"));
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string text = slurp(html);
  EXPECT_NE(text.find("<svg"), std::string::npos);
  EXPECT_NE(text.find("data:image/png;base64,"), std::string::npos);  // the similarity matrix
  EXPECT_NE(text.find("Trajectory"), std::string::npos);
  EXPECT_EQ(text.find("http://"), std::string::npos);
  std::int64_t positives = 0;  // one GT index per frame: the first match only
  for (std::int64_t i = 0; i < frames_; ++i) {
    const auto& m = gt_.matches(i);
    positives += !m.empty() && m.front() < i - 50 ? 1 : 0;
  }
  EXPECT_EQ(read_json(json)["positives"], positives);
  // --poses needs --report; poses of another length are an error naming the file.
  const CmdResult lone = lsgd("eval --sequence " + q(dir_ / "sequence.txt") + common(json) +
                              " --poses " + q(kTmp / "poses.txt"));
  EXPECT_NE(lone.code, 0);
  EXPECT_NE(lone.err.find("--report"), std::string::npos) << lone.err;
  write_text(kTmp / "short-poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
  const CmdResult shorter =
      lsgd("eval --detections " + q(dir_ / "run.csv") + common(json) + " --report " + q(html) +
           " --poses " + q(kTmp / "short-poses.txt"));
  EXPECT_NE(shorter.code, 0);
  EXPECT_NE(shorter.err.find("short-poses.txt"), std::string::npos) << shorter.err;
}

// The KITTI commands of docs/results.md on a KITTI-layout copy of the street:
// images in sequences/00/image_0, times.txt, ground truth derived from poses.
TEST_F(ShortStreet, KittiLayoutWithGroundTruthFromPoses) {
  lsgd::eval::SyntheticOptions options;
  options.width = 160;
  options.height = 120;
  options.route_scale = 0.3;
  const lsgd::eval::SyntheticWorld world(options);
  const fs::path seq = kTmp / "kitti" / "sequences" / "00";
  fs::create_directories(seq / "image_0");
  std::ostringstream times, poses;
  std::vector<lsgd::eval::Pose> truth;
  for (std::int64_t i = 0; i < frames_; ++i) {
    std::ostringstream name;
    name << std::setw(6) << std::setfill('0') << i << ".png";
    std::ostringstream source;
    source << std::setw(6) << std::setfill('0') << i << ".png";
    fs::create_symlink(dir_ / "images" / source.str(), seq / "image_0" / name.str());
    times << 0.1 * static_cast<double>(i) << "\n";
    // 13 columns (timestamp first): the camera moves along x by the street's s.
    poses << 0.1 * static_cast<double>(i) << " 1 0 0 " << world.place(i) << " 0 1 0 0 0 0 1 0\n";
    truth.push_back({world.place(i), 0, 0});
  }
  write_text(seq / "times.txt", times.str());
  write_text(kTmp / "poses00.txt", poses.str());
  const fs::path json = kTmp / "kitti.json";
  const CmdResult r =
      lsgd("eval --sequence " + q(kTmp / "kitti") + " --layout kitti --kitti-sequence 0 --gt " +
           q(kTmp / "poses00.txt") + " --gt-format kitti-poses --min-gap 50 --json " + q(json));
  ASSERT_EQ(r.code, 0) << r.err;
  const lsgd::eval::GroundTruth gt = lsgd::eval::groundtruth_from_poses(truth, 10.0, 100);
  std::int64_t positives = 0;
  for (std::int64_t i = 0; i < gt.frames(); ++i) positives += gt.has_loop(i, 50) ? 1 : 0;
  const auto j = read_json(json);
  EXPECT_EQ(j["frames"], frames_);
  EXPECT_EQ(j["layout"], "kitti");
  EXPECT_EQ(j["positives"], positives);
  EXPECT_EQ(j["ground_truth_pairs"], gt.pairs());
  EXPECT_GT(positives, 20);
  EXPECT_GT(j["recall_at_1"].get<double>(), 0.2);  // the detector finds the revisits

  // lsgd run gives every frame its times.txt stamp: in the CSV's stamp
  // column and in the database, a selection keeping its frames' stamps; the
  // CSV is read back by eval --detections.
  const fs::path csv = kTmp / "kitti-run.csv", db = kTmp / "kitti-run.lsgd";
  fs::remove(db);
  const CmdResult run = lsgd("run --sequence " + q(kTmp / "kitti") +
                             " --layout kitti --kitti-sequence 0 --first 3 --every 2 --output " +
                             q(csv) + " --database " + q(db));
  ASSERT_EQ(run.code, 0) << run.err;
  std::istringstream rows(slurp(csv));
  std::string row;
  std::getline(rows, row);
  EXPECT_EQ(row.substr(row.rfind(',') + 1), "stamp");
  std::int64_t checked = 0;
  for (std::int64_t i = 3; std::getline(rows, row); i += 2, ++checked) {
    std::ostringstream stamp;
    stamp << 0.1 * static_cast<double>(i);  // as times.txt was written
    EXPECT_EQ(std::stod(row.substr(row.rfind(',') + 1)), std::stod(stamp.str())) << row;
    EXPECT_EQ(row.substr(0, row.find(',')), std::to_string((i - 3) / 2)) << row;
  }
  EXPECT_EQ(checked, (frames_ - 3 + 1) / 2);
  const CmdResult read = lsgd("eval --detections " + q(csv) + " --gt " + q(kTmp / "poses00.txt") +
                              " --gt-format kitti-poses --first 3 --every 2 --min-gap 50 --json " + q(kTmp / "kitti-run.json"));
  EXPECT_EQ(read.code, 0) << read.err;
  const lsgd::io::Database stored = lsgd::io::Database::open(db.string(), lsgd::io::Database::Mode::kReadOnly);
  lsgd::Detector restored(stored.options());
  stored.restore(restored);
  ASSERT_EQ(restored.size(), checked);
  EXPECT_EQ(restored.stamp_of(1), std::stod([] {
              std::ostringstream s;
              s << 0.1 * 5.0;
              return s.str();
            }()));
}

}  // namespace
