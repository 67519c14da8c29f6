// lsgd: the command-line front end of the LSGDDN-LCD loop-closure detector.
#include <exception>
#include <iostream>

#include <CLI/CLI.hpp>

#include "commands.h"
#include "lsgd/error.h"

int main(int argc, char** argv) {
  CLI::App app{"lsgd: training-free visual loop closure detection (LSGDDN-LCD)"};
  app.require_subcommand(1);
  lsgd::cli::register_run(app);
  lsgd::cli::register_eval(app);
  lsgd::cli::register_demo(app);
  lsgd::cli::register_sweep(app);
  lsgd::cli::register_bench(app);
  lsgd::cli::register_gt(app);
  lsgd::cli::register_db(app);
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
