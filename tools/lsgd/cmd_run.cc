// lsgd run --sequence PATH [--config FILE] [--output FILE]
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "commands.h"
#include "common.h"
#include "lsgd/eval/runner.h"
#include "lsgd/io/layouts.h"

namespace lsgd::cli {
namespace {

struct RunArgs {
  std::string sequence;
  std::string output;
  DetectorFlags detector;
  SequenceFlags layout;
};

void run(const RunArgs& args) {
  const DetectorOptions options = args.detector.resolve();
  const io::Sequence sequence = io::open_sequence(args.sequence, args.layout.resolve());
  const eval::FrameSource source = eval::sequence_source(sequence);
  CsvWriter csv(args.output);
  Detector detector(options);
  const auto records = run_with_progress(detector, source, "run", &csv);
  double total_ms = 0;
  for (const auto& r : records) total_ms += r.timings.total_ms;
  std::cerr << "processed " << records.size() << " frames, " << csv.loops() << " loops, "
            << total_ms / static_cast<double>(records.size()) << " ms/frame mean"
            << (args.output.empty() ? "" : ", rows in " + args.output) << "\n";
}

}  // namespace

void register_run(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("run", "detect loops in an image sequence, one CSV row per frame");
  cmd->add_option("--sequence", args->sequence,
                  "folder of images (natural order), list file, or a dataset layout (--layout)")
      ->required();
  cmd->add_option("--output", args->output, "CSV file to write (default: standard output)");
  args->detector.add_to(*cmd);
  args->layout.add_to(*cmd);
  cmd->callback([args] { run(*args); });
}

}  // namespace lsgd::cli
