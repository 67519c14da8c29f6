// Running the built `lsgd` binary from a test: its exit code, standard output
// and standard error. Header-only; shared by the tests of the subcommands.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "synthetic/synthetic.h"

namespace lsgd::test {

struct CmdResult {
  int code = -1;  // exit status; -1 when the process did not exit normally
  std::string out;
  std::string err;
};

// The whole content of a file ("" when it cannot be read).
inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs `binary ARGS` (ARGS already quoted for the shell) with no standard
// input, capturing stdout and stderr through files in `scratch` (created;
// use one folder per test process: CTest runs tests in parallel).
inline CmdResult run_command(const std::string& binary, const std::string& args,
                             const std::filesystem::path& scratch) {
  std::filesystem::create_directories(scratch);
  const std::filesystem::path out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  const std::string cmd = "'" + binary + "' " + args + " >'" + out.string() + "' 2>'" +
                          err.string() + "' </dev/null";
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

// The synthetic street at 160 x 120 (its length: route_scale) written as a
// dataset folder at `dir`, emptied first (write_synthetic_dataset); its world,
// for its frames and ground truth.
inline lsgd::eval::SyntheticWorld write_street(const std::filesystem::path& dir, double route_scale) {
  std::filesystem::remove_all(dir);
  lsgd::eval::SyntheticOptions options;
  options.width = 160;
  options.height = 120;
  options.route_scale = route_scale;
  lsgd::eval::SyntheticWorld world(options);
  lsgd::eval::write_synthetic_dataset(world, dir.string());
  return world;
}

}  // namespace lsgd::test
