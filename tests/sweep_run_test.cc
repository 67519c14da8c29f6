// Running a sweep from the library (include/lsgd/eval/sweep.h): the datasets
// opened before any run, the grid's cells and their labels, one cell through
// the frame loop of every command, and the cells on several threads, which
// `lsgd sweep` (tests/sweep_test.cc) and any other program call alike.
#include "lsgd/eval/sweep.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "synthetic/synthetic.h"
#include "test_util.h"

namespace lsgd::eval {
namespace {

namespace fs = std::filesystem;
using test::message_of;

const fs::path kTmp = fs::path(LSGD_TEST_TMP) / ("sweep-run-" + std::to_string(getpid()));

// A short synthetic street (160x120, revisits from frame ~60), once per process.
const std::string& street() {
  static const std::string dir = [] {
    const fs::path d = kTmp / "street";
    fs::remove_all(d);
    SyntheticOptions options;
    options.width = 160;
    options.height = 120;
    options.route_scale = 0.2;
    write_synthetic_dataset(SyntheticWorld(options), d.string());
    return d.string();
  }();
  return dir;
}

// A dataset whose every image is unreadable: each run of it fails.
const std::string& broken() {
  static const std::string dir = [] {
    const fs::path d = kTmp / "broken";
    fs::create_directories(d);
    std::ofstream list(d / "sequence.txt");
    for (int i = 0; i < 3; ++i) {
      const fs::path image = d / ("f" + std::to_string(i) + ".png");
      std::ofstream(image) << "not an image";
      list << image.string() << "\n";
    }
    std::ofstream(d / "groundtruth.txt") << "2 0\n";
    return d.string();
  }();
  return dir;
}

std::vector<SweepPoint> grid(const std::string& set = "segmentation.superpixel_size=30,40") {
  DetectorOptions base;
  parse_verification_stages("none", base.verification);
  return expand_sweep({parse_sweep_axis(set)}, base);
}

// Every metric but the times.
void expect_same_row(const SweepRow& a, const SweepRow& b) {
  EXPECT_TRUE(a.done && b.done);
  EXPECT_EQ(a.metrics.declared_loops, b.metrics.declared_loops);
  EXPECT_EQ(a.metrics.recall_at_1, b.metrics.recall_at_1);
  EXPECT_EQ(a.metrics.recall_at_100_precision, b.metrics.recall_at_100_precision);
  EXPECT_EQ(a.metrics.average_precision, b.metrics.average_precision);
  EXPECT_EQ(a.nodes, b.nodes);
  EXPECT_EQ(a.bytes_per_frame, b.bytes_per_frame);
  EXPECT_EQ(a.skipped, b.skipped);
}

TEST(SweepRun, CellsAreEveryPointOnEveryDatasetLabelledAndChecked) {
  const std::vector<SweepData> data = {open_sweep_dataset(parse_dataset_spec("a=" + street() + ",20")),
                                       open_sweep_dataset(parse_dataset_spec("b=" + street() + ",150"))};
  EXPECT_GT(data[0].positives, data[1].positives);  // the wider window leaves fewer
  const std::vector<SweepPoint> points = grid();
  const std::vector<SweepCell> cells = sweep_cells(data, points, {"segmentation.superpixel_size"});
  ASSERT_EQ(cells.size(), 4u);
  EXPECT_EQ(cells[0].label, "[1/4] a segmentation.superpixel_size=30");
  EXPECT_EQ(cells[3].label, "[4/4] b segmentation.superpixel_size=40");
  EXPECT_EQ(cells[2].options.search.min_gap, 150);
  EXPECT_EQ(cells[2].options.segmentation.superpixel_size, 30);
  EXPECT_TRUE(cells[0].first_of_dataset && cells[2].first_of_dataset);
  EXPECT_FALSE(cells[1].first_of_dataset);
  // Two datasets of one name.
  const std::vector<SweepData> twice = {data[0], data[0]};
  EXPECT_NE(message_of<InvalidArgument>([&] { sweep_cells(twice, points, {}); }).find("used twice"),
            std::string::npos);
  // A missing file is found when the dataset is opened, before any run.
  EXPECT_THROW(open_sweep_dataset(parse_dataset_spec("c=/no/such/folder,20")), Error);
}

TEST(SweepRun, AnyNumberOfThreadsGivesTheRowsOfOneCellAtATime) {
  const std::vector<SweepData> data = {open_sweep_dataset(parse_dataset_spec("street=" + street() + ",20"))};
  const std::vector<SweepPoint> points = grid("segmentation.superpixel_size=25,30,40");
  const std::vector<SweepCell> cells = sweep_cells(data, points, {"segmentation.superpixel_size"});
  std::vector<SweepRow> alone;
  for (const SweepCell& c : cells) alone.push_back(run_sweep_cell(c, false));
  EXPECT_GT(alone[0].metrics.declared_loops + alone[1].metrics.recall_at_1, 0);
  EXPECT_NE(alone[0].nodes + alone[0].metrics.average_precision,
            alone[2].nodes + alone[2].metrics.average_precision);  // the points differ
  for (const int jobs : {1, 2, 3}) {
    SCOPED_TRACE(jobs);
    std::map<std::size_t, SweepRow> rows;
    run_sweep(cells, jobs, [&](std::size_t i, const SweepRow& row) { rows[i] = row; });
    ASSERT_EQ(rows.size(), cells.size());
    for (std::size_t i = 0; i < cells.size(); ++i) expect_same_row(rows[i], alone[i]);
  }
  EXPECT_THROW(run_sweep(cells, 0, {}), InvalidArgument);
}

TEST(SweepRun, AFailedCellStopsNewOnesAndIsNamed) {
  const std::vector<SweepData> data = {
      open_sweep_dataset(parse_dataset_spec("broken=" + broken() + ",1")),
      open_sweep_dataset(parse_dataset_spec("street=" + street() + ",20"))};
  const std::vector<SweepCell> cells = sweep_cells(data, grid(), {"segmentation.superpixel_size"});
  int reported = 0, skipped = 0;
  const std::string message = message_of<Error>([&] {
    run_sweep(cells, 1, [&](std::size_t, const SweepRow&) { ++reported; },
              [&](const SweepCell& c) {
                return run_sweep_cell(c, false, {},
                                      [&](std::int64_t, const std::string&, const std::string&) {
                                        ++skipped;
                                      });
              });
  });
  EXPECT_NE(message.find("[1/4] broken segmentation.superpixel_size=30: no frame was processed: all 3 "
                         "images were skipped"),
            std::string::npos)
      << message;
  EXPECT_EQ(reported, 0);  // no cell started after the failure
  EXPECT_EQ(skipped, 3);
  // Under strict the first bad frame stops the cell.
  EXPECT_THROW(run_sweep_cell(cells[0], true), Error);
}

}  // namespace
}  // namespace lsgd::eval
