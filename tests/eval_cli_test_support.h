// Helpers of the `lsgd eval` end-to-end tests (eval_cli_test.cc,
// eval_inputs_cli_test.cc): running the binary, small files and images.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "cli_util.h"
#include "test_util.h"

namespace lsgd::test::eval_cli {

namespace fs = std::filesystem;

inline const fs::path kTmp =
    lsgd::test::removed_at_exit(fs::path(LSGD_TEST_TMP) / ("eval-cli-" + std::to_string(getpid())));


inline std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// Runs `lsgd ARGS`, capturing stdout and stderr.
inline CmdResult lsgd(const std::string& args) { return lsgd::test::run_command(LSGD_CLI, args, kTmp); }

inline nlohmann::json read_json(const fs::path& path) { return nlohmann::json::parse(slurp(path)); }

inline int lines_of(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

inline void write_text(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

inline void write_image(const fs::path& path, int seed) {
  fs::create_directories(path.parent_path());
  cv::Mat m(48, 64, CV_8UC1);
  cv::randu(m, 0, 255);
  m.at<unsigned char>(0, 0) = static_cast<unsigned char>(seed);
  ASSERT_TRUE(cv::imwrite(path.string(), m));
}

}  // namespace lsgd::test::eval_cli
