// lsgd demo [--output DIR]: the main job on a built-in default. No image data
// ships with lsgd, so the demo generates a deterministic synthetic street
// (eval/synthetic.h) whose route revisits earlier places, some under other
// lighting and with moving objects, runs the detector on it online in both
// search modes and prints the strict evaluation against its exact ground truth.
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include "commands.h"
#include "common.h"
#include "files.h"
#include "lsgd/error.h"
#include "lsgd/eval/runner.h"
#include "synthetic/synthetic.h"
#include "lsgd/io/config.h"

namespace lsgd::cli {
namespace {

namespace fs = std::filesystem;

struct DemoArgs {
  std::string output;
  std::uint64_t seed = 1;
  DetectorFlags detector;
};

void print_route(const eval::SyntheticWorld& world) {
  std::cout << "synthetic street " << world.options().width << "x" << world.options().height
            << ", " << world.frames() << " frames, " << world.ground_truth().pairs()
            << " ground-truth pairs (places within " << world.options().loop_radius
            << " m), seed " << world.options().seed << "\n";
  for (const auto& s : world.route()) {
    std::cout << "  frames " << std::setw(4) << s.first_frame << "-" << std::setw(4)
              << s.last_frame << "  " << s.label << "\n";
  }
}

void demo(const DemoArgs& args) {
  DetectorOptions options = args.detector.resolve();
  // --output DIR: a new or empty folder, or one this command wrote before.
  CommandFiles files;
  files.input(args.detector.config, "--config");
  // Its own files: results-MODE.csv for every registered search mode.
  std::vector<std::string> own = {"images", "sequence.txt", "groundtruth.txt", "metrics.json"};
  for (const std::string& mode : search_mode_list()) own.push_back("results-" + mode + ".csv");
  files.output_folder(args.output, "--output", own, "metrics.json");
  files.check();
  eval::SyntheticOptions world_options;
  world_options.seed = args.seed;
  const eval::SyntheticWorld world(world_options);
  print_route(world);
  const fs::path dir(args.output);
  if (!args.output.empty()) eval::write_synthetic_dataset(world, dir);

  eval::FrameSource source;
  source.frames = world.frames();
  source.load = [&world](std::int64_t i) { return world.render(i); };
  source.name = [](std::int64_t i) { return "synthetic frame " + std::to_string(i); };

  // Every registered search mode, unless --mode names one.
  const std::vector<std::string> modes =
      args.detector.mode.empty() ? search_mode_list() : std::vector<std::string>{options.search.mode};
  nlohmann::json results = nlohmann::json::object();
  for (const std::string& mode : modes) {
    options.search.mode = mode;
    Detector detector(options);
    std::unique_ptr<CsvWriter> csv;
    if (!args.output.empty()) {
      csv = std::make_unique<CsvWriter>((dir / ("results-" + mode + ".csv")).string());
    }
    const FrameRun run = run_frames(
        detector, source, "demo " + mode, {},
        [&](const Result& r, const eval::FrameTimes&) {
          if (csv) csv->write(r, source.name(r.frame));
        });
    const auto metrics = eval::evaluate(run.records, world.ground_truth(), options.search.min_gap);
    std::cout << "\n" << mode << " search:\n";
    print_metrics(metrics, detector.nodes(), std::cout);
    results[mode] = metrics_json(metrics);
    results[mode]["nodes"] = detector.nodes();
  }
  if (!args.output.empty()) {
    results["config_yaml"] = io::to_yaml(options);
    write_json(results, (dir / "metrics.json").string());
    std::cout << "\nwrote " << dir.string() << "/{images/,sequence.txt,groundtruth.txt,"
              << "results-*.csv,metrics.json}\n";
  }
}

}  // namespace

void register_demo(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  CLI::App* cmd = app.add_subcommand(
      "demo", "run and evaluate the detector on a built-in synthetic street with revisits");
  cmd->add_option("--output", args->output,
                  "also write the frames, ground truth, per-frame CSV and metrics JSON here")
      ->check(kNonEmptyPath);
  cmd->add_option("--seed", args->seed, "seed of the synthetic world");
  args->detector.add_to(*cmd);
  cmd->callback([args] { demo(*args); });
}

}  // namespace lsgd::cli
