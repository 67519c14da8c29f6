// `lsgd bench` end to end (the real binary on tiny runs), and its helpers
// (tools/lsgd/bench_support.cc): the region size that matches OpenCV's SLIC
// to our grid and the query-growth table.
#include <gtest/gtest.h>

#include "cli_util.h"
#include "test_util.h"
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "bench_support.h"
#include "distractor.h"
#include "lsgd/error.h"
#include "lsgd/segmentation.h"

namespace fs = std::filesystem;

namespace {

const fs::path kTmp =
    lsgd::test::removed_at_exit(fs::path(LSGD_TEST_TMP) / ("bench-cli-" + std::to_string(getpid())));

using lsgd::test::CmdResult;
using lsgd::test::slurp;

// Runs `lsgd ARGS`, capturing stdout and stderr.
CmdResult lsgd(const std::string& args) {
  return lsgd::test::run_command(LSGD_CLI, args, kTmp);
}

constexpr const char* kTiny = "bench --frames 60 --width 320 --height 240 --warmup 5 --block 20 ";

void expect_positive(const nlohmann::json& j, const char* key) {
  ASSERT_TRUE(j.contains(key)) << key;
  ASSERT_TRUE(j[key].is_number()) << key << " = " << j[key].dump();
  const double v = j[key].get<double>();
  EXPECT_TRUE(std::isfinite(v)) << key;
  EXPECT_GT(v, 0.0) << key;
}

// Keys every run writes, whatever the mode and whether OpenCV's SLIC ran.
void expect_common(const nlohmann::json& j) {
  EXPECT_EQ(j["frames"].get<std::int64_t>(), 60);
  EXPECT_EQ(j["measured_frames"].get<std::int64_t>(), 55);
  EXPECT_EQ(j["width"].get<int>(), 320);
  EXPECT_EQ(j["grid"]["cells"].get<int>(), lsgd::grid_size(320, 240, 40).cells());
  for (const char* stage : {"convert", "segment", "describe", "query", "verify", "frame",
                            "frame_cpu", "segment_describe", "render", "cvtcolor"}) {
    const std::string median = std::string(stage) + "_ms_median",
                      p95 = std::string(stage) + "_ms_p95";
    expect_positive(j, median.c_str());
    expect_positive(j, p95.c_str());
    EXPECT_GE(j[p95].get<double>(), j[median].get<double>()) << stage;
  }
  // The stages are parts of the frame, so their medians cannot exceed its p95.
  EXPECT_LE(j["segment_ms_median"].get<double>(), j["frame_ms_p95"].get<double>());
  for (const char* key : {"bytes_per_frame", "store_bytes", "peak_rss_bytes"}) {
    expect_positive(j, key);
  }
  EXPECT_DOUBLE_EQ(j["store_bytes"].get<double>(), 60.0 * j["bytes_per_frame"].get<double>());
  EXPECT_GE(j["peak_rss_bytes"].get<double>(), j["store_bytes"].get<double>());
  EXPECT_NE(j["config_yaml"].get<std::string>().find("superpixel_size: 40"), std::string::npos);
  EXPECT_FALSE(j["machine"]["cpu_model"].get<std::string>().empty());
  EXPECT_GT(j["machine"]["logical_cores"].get<int>(), 0);
  EXPECT_FALSE(j["machine"]["compiler"].get<std::string>().empty());
  // Blocks of 20 over the measured frames 5..59: 5-24, 25-44, 45-59.
  const auto& rows = j["query_growth"]["rows"];
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0]["first_frame"].get<int>(), 5);
  EXPECT_EQ(rows[2]["last_frame"].get<int>(), 59);
  for (const auto& row : rows) EXPECT_GT(row["query_ms_median"].get<double>(), 0.0);
}

TEST(BenchCli, TinyExhaustiveRunWritesEveryKey) {
  const fs::path json = kTmp / "exhaustive.json";
  const auto r = lsgd(std::string(kTiny) + "--opencv-frames 5 --json '" + json.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(json));
  expect_common(j);
  EXPECT_EQ(j["mode"], "exhaustive");
  EXPECT_EQ(j["nodes"].get<int>(), 0);
  // min_gap 50: only the last block's queries scan anything.
  const auto& rows = j["query_growth"]["rows"];
  EXPECT_EQ(rows[0]["gb_per_s"].get<double>(), 0.0);
  EXPECT_GT(rows[2]["gb_per_s"].get<double>(), 0.0);
  EXPECT_NE(r.out.find("query time vs stored frames N"), std::string::npos) << r.out;
#ifdef LSGD_HAVE_XIMGPROC
  for (const char* key :
       {"opencv_slic_ms_median", "opencv_slic_ms_p95", "opencv_slic_cpu_ms_median",
        "speedup_vs_opencv_slic", "speedup_vs_opencv_slic_incl_describe",
        "speedup_vs_opencv_slic_same_frames", "speedup_vs_opencv_slic_cpu",
        "speedup_vs_opencv_slic_cpu_incl_describe"}) {
    expect_positive(j, key);
  }
  for (const char* key : {"segment_ms_median", "segment_describe_ms_median",
                          "segment_cpu_ms_median", "segment_describe_cpu_ms_median"}) {
    expect_positive(j["opencv_slic"]["ours_same_frames"], key);
  }
  EXPECT_EQ(j["opencv_slic"]["frames"].get<int>(), 5);
  EXPECT_EQ(j["opencv_slic"]["superpixels"].get<int>(), j["grid"]["cells"].get<int>());
  EXPECT_NEAR(j["speedup_vs_opencv_slic"].get<double>(),
              j["opencv_slic_ms_median"].get<double>() / j["segment_ms_median"].get<double>(),
              1e-9);
  EXPECT_LT(j["speedup_vs_opencv_slic_incl_describe"].get<double>(),
            j["speedup_vs_opencv_slic"].get<double>());
  EXPECT_NE(r.out.find("speedup = OpenCV SLIC median / ours"), std::string::npos) << r.out;
#else
  EXPECT_TRUE(j["opencv_slic_ms_median"].is_null());
  EXPECT_TRUE(j["speedup_vs_opencv_slic"].is_null());
  EXPECT_NE(r.out.find("built without opencv_ximgproc (install libopencv-contrib-dev)"),
            std::string::npos)
      << r.out;
#endif
}

TEST(BenchCli, NodesModeWithoutOpenCvWritesNull) {
  const fs::path json = kTmp / "nodes.json";
  const auto r = lsgd(std::string(kTiny) + "--mode nodes --verify none --opencv-frames 0 --json '" +
                      json.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(json));
  expect_common(j);
  EXPECT_EQ(j["mode"], "nodes");
  EXPECT_EQ(j["verify"], "none");
  EXPECT_GT(j["nodes"].get<int>(), 0);
  for (const char* key :
       {"opencv_slic_ms_median", "opencv_slic_ms_p95", "opencv_slic_cpu_ms_median",
        "speedup_vs_opencv_slic", "speedup_vs_opencv_slic_incl_describe",
        "speedup_vs_opencv_slic_same_frames", "speedup_vs_opencv_slic_cpu"}) {
    EXPECT_TRUE(j[key].is_null()) << key;
  }
  EXPECT_EQ(j["opencv_slic"]["reason"], "--opencv-frames 0");
  for (const auto& row : j["query_growth"]["rows"]) EXPECT_EQ(row["gb_per_s"].get<double>(), 0.0);
}

// --distractors: the sequence hidden among N perturbed frames, every mode
// but nodes compared with exhaustive search on the same map.
TEST(BenchCli, DistractorsCompareTheModesOnOneMap) {
  const fs::path json = kTmp / "distractors.json";
  // The graph from the first query (the default scores every frame of a map
  // this small: below).
  const auto r = lsgd("bench --distractors 300 --frames 120 --width 160 --height 120 --min-gap 10 "
                      "--verify temporal --mode index --option search.index.exhaustive_up_to=0 "
                      "--json '" + json.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(json));
  EXPECT_EQ(j["mode"], "index");
  EXPECT_EQ(j["distractors"], 300);
  EXPECT_EQ(j["frames"], 420);
  for (const char* key : {"query_ms_median", "query_ms_p95", "insert_ms_median", "bytes_per_frame",
                          "build_s"}) {
    EXPECT_GT(j[key].get<double>(), 0.0) << key;
  }
  EXPECT_GE(j["recall_vs_exhaustive"].get<double>(), 0.5);
  EXPECT_LE(j["recall_vs_exhaustive"].get<double>(), 1.0);
  ASSERT_EQ(j["modes"].size(), 2u);
  EXPECT_EQ(j["modes"][0]["mode"], "exhaustive");
  EXPECT_EQ(j["modes"][0]["recall_vs_exhaustive"], 1.0);
  EXPECT_EQ(j["modes"][0]["insert_ms_median"], 0.0);  // no index
  EXPECT_GT(j["modes"][0]["compared_queries"].get<int>(), 20);
  // The recall apart for queries whose exhaustive candidate is a sequence
  // frame and a distractor: the two parts add up to the whole.
  for (const auto& m : j["modes"]) {
    const int seq = m["compared_queries_sequence"], dis = m["compared_queries_distractor"];
    EXPECT_EQ(seq + dis, m["compared_queries"].get<int>());
    EXPECT_NEAR(m["recall_vs_exhaustive_sequence"].get<double>() * seq +
                    m["recall_vs_exhaustive_distractor"].get<double>() * dis,
                m["recall_vs_exhaustive"].get<double>() * (seq + dis), 1e-9);
    EXPECT_GE(m["evidence_ms_median"].get<double>(), 0.0);
    EXPECT_GE(m["candidates_ms_median"].get<double>(), 0.0);
  }
  EXPECT_EQ(j["modes"][0]["recall_vs_exhaustive_sequence"], 1.0);
  EXPECT_GT(j["evidence_ms_median"].get<double>(), 0.0);
  // Memory, the saved graph's size, and the loops declared, judged by the
  // street's ground truth (a loop to a distractor is false).
  for (const auto& m : j["modes"]) {
    EXPECT_GT(m["peak_rss_mb"].get<double>(), 0.0);
    EXPECT_GE(m["declared_false"].get<int>(), 0);
    EXPECT_LE(m["declared_false"].get<int>(), m["declared"].get<int>());
  }
  EXPECT_EQ(j["modes"][0]["index_bytes_per_frame"], 0.0);
  EXPECT_GT(j["index_bytes_per_frame"].get<double>(), 0.0);
  EXPECT_GT(j["index_restore_s"].get<double>(), 0.0);
  EXPECT_EQ(j["distractor_run"], 1);  // one distractor at a time unless --distractor-run
}

// With the defaults a map of 420 frames is searched exhaustively: the same
// candidate for every query and the same loops, the graph built all the same.
TEST(BenchCli, ASmallMapWithDistractorsIsSearchedAsExhaustiveSearchDoes) {
  const fs::path small_json = kTmp / "distractors-default.json";
  const auto small = lsgd("bench --distractors 300 --frames 120 --width 160 --height 120 --min-gap 10 "
                          "--verify temporal --mode index --json '" + small_json.string() + "'");
  ASSERT_EQ(small.code, 0) << small.err;
  const auto d = nlohmann::json::parse(slurp(small_json));
  EXPECT_EQ(d["recall_vs_exhaustive"], 1.0);
  EXPECT_EQ(d["modes"][1]["declared_vs_exhaustive"], 1.0);
  EXPECT_EQ(d["modes"][1]["declared"], d["modes"][0]["declared"]);
  EXPECT_GT(d["index_bytes_per_frame"].get<double>(), 0.0);
}

// What --distractors cannot take, said before anything runs; runs of
// distractors, said in the JSON.
TEST(BenchCli, DistractorArgumentsAreCheckedFirst) {
  const auto nodes = lsgd("bench --distractors 10 --frames 20 --width 160 --height 120 --mode nodes");
  EXPECT_EQ(nodes.code, 1);
  EXPECT_NE(nodes.err.find("nodes cannot take distractors"), std::string::npos) << nodes.err;
  // --json never lands on an image of --sequence.
  const fs::path dir = kTmp / "distractor-sequence";
  fs::create_directories(dir);
  cv::Mat image(48, 64, CV_8UC1);
  for (int i = 0; i < 3; ++i) {
    cv::randu(image, 0, 255);
    ASSERT_TRUE(cv::imwrite((dir / (std::to_string(i) + ".png")).string(), image));
  }
  const std::string before = slurp(dir / "1.png");
  const auto onto = lsgd("bench --distractors 5 --sequence '" + dir.string() + "' --json '" +
                         (dir / "1.png").string() + "'");
  EXPECT_EQ(onto.code, 1);
  EXPECT_NE(onto.err.find("1.png"), std::string::npos) << onto.err;
  EXPECT_EQ(slurp(dir / "1.png"), before);
  for (const char* args : {"bench --sequence x --frames 30", "bench --distractor-run 10 --frames 30"}) {
    const auto alone = lsgd(args);
    EXPECT_EQ(alone.code, 1) << args;
    EXPECT_NE(alone.err.find("are about --distractors: give --distractors N too"), std::string::npos)
        << args << ": " << alone.err;
  }
  // Runs of distractors: the JSON says how they were made.
  const fs::path runs_json = kTmp / "distractor-runs.json";
  const auto runs = lsgd("bench --distractors 40 --distractor-run 20 --frames 60 --width 160 --height 120 "
                         "--min-gap 10 --verify none --mode index --json '" + runs_json.string() + "'");
  ASSERT_EQ(runs.code, 0) << runs.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(runs_json))["distractor_run"], 20);
  const auto street_gt = lsgd("bench --distractors 5 --frames 30 --gt x");
  EXPECT_EQ(street_gt.code, 1);
  EXPECT_NE(street_gt.err.find("the synthetic street has its own"), std::string::npos) << street_gt.err;
}

// A map larger than the machine's memory fails at once, naming the storage
// that would fit more, before any map is built.
TEST(BenchCli, AMapLargerThanTheMemoryIsRefusedAtOnce) {
  if (lsgd::cli::bench::available_memory_bytes() >= 0) {
    const auto huge = lsgd("bench --distractors 1000000000 --frames 30 --width 160 --height 120 --mode index");
    EXPECT_EQ(huge.code, 1);
    EXPECT_NE(huge.err.find("--distractors 1000000000: a map of 1000000030 frames"), std::string::npos)
        << huge.err;
    EXPECT_NE(huge.err.find("use --option descriptor.storage=compact"), std::string::npos) << huge.err;
    EXPECT_EQ(huge.out.find("exhaustive ..."), std::string::npos) << huge.out;
    // The same for a plain bench of too many frames, in every storage and
    // mode, before the first frame is rendered.
    for (const char* extra : {"", " --mode index", " --mode nodes --option descriptor.storage=compact"}) {
      const auto frames = lsgd(std::string("bench --frames 1000000000 --width 160 --height 120") + extra);
      EXPECT_EQ(frames.code, 1) << extra;
      EXPECT_NE(frames.err.find("--frames 1000000000: a map of 1000000000 frames of 6 cells"),
                std::string::npos) << extra << ": " << frames.err;
      // Exact storage names the compact storage's size; compact only fewer frames.
      const bool compact = std::string(extra).find("compact") != std::string::npos;
      const std::string advice = compact ? "; use fewer frames"
                                         : "; use --option descriptor.storage=compact (768 descriptor "
                                           "bytes a frame instead of 3096) or fewer frames";
      EXPECT_NE(frames.err.find(advice), std::string::npos) << extra << ": " << frames.err;
      EXPECT_TRUE(frames.out.empty()) << frames.out;
    }
  }
}

// --sequence is read as lsgd eval reads a dataset: its ground truth in the
// dataset's own numbering, moved onto the frames --first and --every keep;
// every frame must be readable; the flags that choose frames need it.
TEST(BenchCli, ASequenceAndItsGroundTruthAreReadAsLsgdEvalReadsThem) {
  const fs::path dir = kTmp / "bench-gt";
  fs::create_directories(dir / "images");
  cv::Mat image(48, 64, CV_8UC1);
  std::string list;
  for (int i = 0; i < 30; ++i) {
    cv::randu(image, 0, 255);
    const fs::path file = dir / "images" / (std::to_string(100 + i) + ".png");
    ASSERT_TRUE(cv::imwrite(file.string(), image));
    list += file.string() + "\n";
  }
  std::ofstream(dir / "list.txt") << list;
  // Pairs in the sequence's numbering: (25, 12) and (28, 4) lie beyond the
  // 20 frames --first 10 keeps, and beyond the 15 --every 2 keeps.
  std::ofstream(dir / "gt.txt") << "25 12\n28 4\n";
  const std::string base = "bench --distractors 3 --min-gap 2 --verify none --sequence '" +
                           (dir / "list.txt").string() + "' --gt '" + (dir / "gt.txt").string() + "'";
  for (const char* keep : {" --first 10", " --every 2", ""}) {
    const auto r = lsgd(base + keep);
    EXPECT_EQ(r.code, 0) << keep << ": " << r.err;
  }
  // A pair beyond the whole sequence is still refused, in its own numbering.
  std::ofstream(dir / "far.txt") << "35 2\n";
  const auto far = lsgd("bench --distractors 3 --min-gap 2 --sequence '" + (dir / "list.txt").string() +
                        "' --gt '" + (dir / "far.txt").string() + "' --first 10");
  EXPECT_EQ(far.code, 1);
  EXPECT_NE(far.err.find("30 frames"), std::string::npos) << far.err;

  // A frame that cannot be read stops the bench, naming it and its frame.
  std::ofstream(dir / "bad.png") << "junk";
  std::ofstream(dir / "with-bad.txt") << list << (dir / "bad.png").string() << "\n";
  const auto bad = lsgd("bench --distractors 3 --min-gap 2 --sequence '" + (dir / "with-bad.txt").string() + "'");
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.err.find("frame 30"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("bad.png"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("needs every frame"), std::string::npos) << bad.err;
  // It cannot skip one, so it has no --strict.
  EXPECT_NE(lsgd(base + " --strict").code, 0);
  // The flags that choose the frames of --sequence do nothing without one.
  for (const char* args : {"bench --frames 40 --width 64 --height 48 --every 4 --first 3",
                           "bench --distractors 2 --frames 40 --width 64 --height 48 --every 4",
                           "bench --frames 40 --width 64 --height 48 --layout folder"}) {
    const auto r = lsgd(args);
    EXPECT_EQ(r.code, 1) << args;
    EXPECT_NE(r.err.find("the frames of --sequence: give --distractors N --sequence PATH too"),
              std::string::npos)
        << args << ": " << r.err;
  }
}

TEST(BenchCli, BadArgumentsFailNamingTheFlag) {
  const std::pair<const char*, const char*> cases[] = {
      {"bench --frames 0", "--frames"},           {"bench --width 10", "--width"},
      {"bench --height 5000", "--height"},        {"bench --frames 10 --warmup 10", "--warmup"},
      {"bench --frames 10 --block 0", "--block"}, {"bench --frames 10 --mode fast", "--mode"},
      {"bench --distractors 10 --distractor-run 0", "--distractor-run"}};
  for (const auto& [args, flag] : cases) {
    const auto r = lsgd(args);
    EXPECT_NE(r.code, 0) << args;
    EXPECT_NE(r.err.find(flag), std::string::npos) << args << ": " << r.err;
  }
}

// Twelve cells, each a spike at its own intensity with its own pixel count,
// so a distractor's layout (the permutation) and lighting (the shift) can be
// read back from it.
TEST(Distractor, MapMemoryIsEstimatedAndCheckedAgainstTheMachine) {
  using namespace lsgd::cli::bench;
  lsgd::DetectorOptions options;
  options.descriptor.storage = lsgd::HistogramStorage::kCompact;
  // KITTI size (80 cells), compact: 10,240 descriptor bytes; the index adds
  // its key (16 a cell), 2 M links of 4 bytes and 64 of bookkeeping; every
  // frame its place signature (lsgd::kPlaceBytesPerFrame).
  const std::int64_t places = lsgd::kPlaceBytesPerFrame;
  EXPECT_EQ(map_bytes("index", 1000, 80, options), 1000 * (10240 + 1280 + 128 + 64 + places));
  EXPECT_EQ(map_bytes("exhaustive", 1000, 80, options), 1000 * (10240 + 8 * 48 + places));
  options.descriptor.storage = lsgd::HistogramStorage::kExact;
  EXPECT_EQ(map_bytes("exhaustive", 1000, 80, options), 1000 * (41280 + 8 * 48 + places));
  options.verification.stages = {};
  EXPECT_EQ(map_bytes("exhaustive", 2, 80, options), 2 * (41280 + 8));

  std::istringstream meminfo("MemTotal:       24000000 kB\nMemFree:        1000 kB\nMemAvailable:   2048 kB\n");
  EXPECT_EQ(mem_available_bytes(meminfo), 2048 * 1024);
  std::istringstream none("MemTotal: 1 kB\n"), odd("MemAvailable: 12 pages\n");
  EXPECT_EQ(mem_available_bytes(none), -1);
  EXPECT_EQ(mem_available_bytes(odd), -1);
  const auto room = [](const char* max, const char* current) {
    std::istringstream m(max), c(current);
    return cgroup_room_bytes(m, c);
  };
  EXPECT_EQ(room("1000000\n", "250000\n"), 750000);
  EXPECT_EQ(room("max\n", "250000\n"), -1);
  EXPECT_EQ(room("1000\n", "2000\n"), 0);
  EXPECT_EQ(room("", "2000\n"), -1);
  EXPECT_EQ(room("lots\n", "2000\n"), -1);
  // The machine running the test says something (Linux) or nothing (-1).
  EXPECT_GE(available_memory_bytes(), -1);
}

TEST(BenchSupport, SlicRegionSizeMatchesOurGrid) {
  using lsgd::cli::bench::slic_region_size;
  using lsgd::cli::bench::slic_seed_count;
  // KITTI at S_p 40: 5 x 16 = 80 cells; r = 76 seeds round(1241/76) x round(376/76) = 16 x 5.
  EXPECT_EQ(slic_region_size(1241, 376, 80), 76);
  EXPECT_EQ(slic_seed_count(1241, 376, 76), 80);
  EXPECT_EQ(slic_region_size(320, 240, 20), 62);
  EXPECT_EQ(slic_seed_count(320, 240, 62), 20);
  // Never larger than the shorter side (OpenCV would drop seeds off the image).
  EXPECT_EQ(slic_region_size(32, 32, 1), 32);
  EXPECT_EQ(slic_seed_count(32, 32, 32), 1);
  EXPECT_THROW(slic_region_size(320, 240, 0), lsgd::InvalidArgument);
}

#ifdef LSGD_HAVE_XIMGPROC
// slic_seed_count must predict the count OpenCV actually makes.
TEST(BenchSupport, SlicSeedCountIsWhatOpenCvMakes) {
  for (const auto& [w, h, sp] : {std::tuple{320, 240, 40}, {200, 120, 10}, {97, 61, 7}}) {
    const int cells = lsgd::grid_size(w, h, sp).cells();
    lsgd::cli::bench::OpenCvSlic slic(w, h, cells, 2);
    cv::Mat gray(h, w, CV_8UC1);
    cv::randu(gray, 0, 256);
    EXPECT_GT(slic.time(gray).wall_ms, 0.0);
    EXPECT_EQ(slic.superpixels(), lsgd::cli::bench::slic_seed_count(w, h, slic.region_size()))
        << w << "x" << h;
  }
}
#endif

TEST(BenchSupport, QueryGrowthCutsBlocksAndCountsScannedBytes) {
  // Frames 10..16 queried in 2 ms each; min_gap 2, 100 bytes per frame.
  const std::vector<double> ms(7, 2.0);
  const auto rows = lsgd::cli::bench::query_growth(ms, 10, 3, true, 2, 100);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].first_frame, 10);
  EXPECT_EQ(rows[0].last_frame, 12);
  EXPECT_EQ(rows[0].stored_frames, 11);
  EXPECT_DOUBLE_EQ(rows[0].scanned_bytes, 900.0);  // frame 11 scans frames 0..8
  // Block 0 scans (8 + 9 + 10) * 100 bytes in 6 ms.
  EXPECT_DOUBLE_EQ(rows[0].gb_per_s, 2700.0 / 6e-3 * 1e-9);
  EXPECT_EQ(rows[2].first_frame, 16);
  EXPECT_EQ(rows[2].last_frame, 16);
  EXPECT_DOUBLE_EQ(rows[2].query_ms_median, 2.0);
  const auto nodes = lsgd::cli::bench::query_growth(ms, 10, 3, false, 2, 100);
  EXPECT_EQ(nodes[0].gb_per_s, 0.0);
  EXPECT_EQ(nodes[0].scanned_bytes, 0.0);
}

}  // namespace
