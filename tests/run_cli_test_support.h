// The fixture and helpers of the `lsgd run` end-to-end tests (run_cli_test,
// run_cli_output_test): 140 frames of the synthetic street in a folder (and a
// list with image 7 not an image), the lsgd command, a run CSV's rows without
// their times, a database's rows, a CSV's frame column. Header-only.
#pragma once

#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli_util.h"
#include "lsgd/decision.h"
#include "synthetic/synthetic.h"
#include "test_util.h"

namespace run_cli_test_support {

namespace fs = std::filesystem;

inline const fs::path kTmp = fs::path(LSGD_TEST_TMP) / ("run-cli-" + std::to_string(getpid()));
constexpr int kFrames = 140;  // the street's first revisit starts near frame 90

using lsgd::test::CmdResult;
using lsgd::test::slurp;

inline CmdResult lsgd(const std::string& args) {
  return lsgd::test::run_command("timeout", "120 '" + std::string(LSGD_CLI) + "' " + args, kTmp);
}

inline std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// The rows of a run CSV without the `ms` column (a time, different in every run).
inline std::vector<std::string> rows_without_time(const fs::path& csv) {
  std::vector<std::string> rows;
  for (const std::vector<std::string>& fields : lsgd::test::csv_rows(csv)) {
    std::string row;
    for (std::size_t k = 0; k < fields.size(); ++k) {
      if (k != 5) row += fields[k] + ",";
    }
    rows.push_back(row);
  }
  return rows;
}

// Every column of every frame row of a database, as text, in id order.
inline std::vector<std::string> database_rows(const fs::path& db) {
  sqlite3* handle = nullptr;
  EXPECT_EQ(sqlite3_open_v2(db.c_str(), &handle, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(handle,
                               "SELECT id, session, name, hex(histogram), hex(pixels), node, place, "
                               "hex(features), crc32, loop, loop_inliers, frame FROM frames "
                               "ORDER BY id",
                               -1, &st, nullptr),
            SQLITE_OK);
  std::vector<std::string> rows;
  while (sqlite3_step(st) == SQLITE_ROW) {
    std::string row;
    for (int c = 0; c < 12; ++c) {
      const auto* text = sqlite3_column_text(st, c);
      row += (text ? reinterpret_cast<const char*>(text) : "NULL") + std::string("|");
    }
    rows.push_back(row);
  }
  sqlite3_finalize(st);
  sqlite3_close(handle);
  return rows;
}

inline std::vector<long> frame_column(const fs::path& csv) {
  std::vector<long> frames;
  std::istringstream in(slurp(csv));
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) frames.push_back(std::stol(line.substr(0, line.find(','))));
  return frames;
}

class RunCli : public ::testing::Test {
 protected:
  // 140 frames of the synthetic street (160x120) in a folder, and a list of
  // them with image 7 replaced by a file that is not an image.
  static void SetUpTestSuite() {
    fs::remove_all(kTmp);
    dir_ = kTmp / "street";
    fs::create_directories(dir_);
    lsgd::eval::SyntheticOptions o;
    o.width = 160;
    o.height = 120;
    o.route_scale = 0.3;
    const lsgd::eval::SyntheticWorld world(o);
    std::ofstream list(kTmp / "broken.txt");
    for (int i = 0; i < kFrames; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "%04d.png", i);
      ASSERT_TRUE(cv::imwrite((dir_ / name).string(), world.render(i)));
      list << (i == 7 ? (kTmp / "not-an-image.png").string() : (dir_ / name).string()) << "\n";
    }
    std::ofstream(kTmp / "not-an-image.png") << "text";
  }
  static void TearDownTestSuite() { fs::remove_all(kTmp); }

  void SetUp() override {
    for (const char* name : {"a.db", "a.db-wal", "a.db-shm", "a.csv", "b.db", "b.csv"}) {
      fs::remove(kTmp / name);
    }
  }

  static std::string run_args(const std::string& db, const std::string& csv,
                              const std::string& extra = "") {
    return "run --sequence " + q(dir_) + " --min-gap 20 --database " + q(kTmp / db) +
           " --output " + q(kTmp / csv) + extra;
  }

  inline static fs::path dir_;
};

}  // namespace run_cli_test_support
