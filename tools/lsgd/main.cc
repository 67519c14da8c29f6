// lsgd: the command-line front end of the LSGDDN-LCD loop-closure detector.
#include <cstdlib>
#include <exception>
#include <iostream>

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>

#include "commands.h"
#include "lsgd/error.h"

int main(int argc, char** argv) {
  // The tool computes on the CPU: OpenCV must not load an OpenCL runtime for
  // ORB (the ICD loader it may dlopen brings dynamic TLS that crashed
  // LeakSanitizer's exit check, and nothing here runs on a GPU). A value the
  // user set is kept.
  ::setenv("OPENCV_OPENCL_RUNTIME", "disabled", 0);
  CLI::App app{"lsgd: training-free visual loop closure detection (LSGDDN-LCD)"};
  app.require_subcommand(1);
  lsgd::cli::register_run(app);
  lsgd::cli::register_eval(app);
  lsgd::cli::register_demo(app);
  lsgd::cli::register_sweep(app);
  lsgd::cli::register_bench(app);
  lsgd::cli::register_gt(app);
  lsgd::cli::register_db(app);
  lsgd::cli::register_options(app);
  // The detector runs on the calling thread; OpenCV's own thread pool (ORB,
  // RANSAC and resizing in the geometric stage) is off too, so that every
  // time the tool reports is single-thread and runs are repeatable. `lsgd
  // sweep --jobs N` runs cells on its own threads.
  cv::setNumThreads(0);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "lsgd: error: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
