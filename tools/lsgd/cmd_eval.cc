// lsgd eval --sequence PATH --gt FILE --min-gap W [--mode M] [--config FILE] --json OUT
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "commands.h"
#include "common.h"
#include "lsgd/eval/groundtruth.h"
#include "lsgd/eval/runner.h"
#include "lsgd/io/config.h"
#include "lsgd/io/sequence.h"

namespace lsgd::cli {
namespace {

struct EvalArgs {
  std::string sequence;
  std::string gt;
  std::string json;
  std::string output;
  DetectorFlags detector;
};

void evaluate(const EvalArgs& args) {
  const DetectorOptions options = args.detector.resolve();
  const io::Sequence sequence = io::open_sequence(args.sequence);
  const auto frames = static_cast<std::int64_t>(sequence.images.size());
  // Read the ground truth before the (long) run so a wrong file fails at once.
  const eval::GroundTruth gt = eval::read_pairs(args.gt, frames);
  const eval::FrameSource source = eval::sequence_source(sequence);
  std::unique_ptr<CsvWriter> csv;
  if (!args.output.empty()) csv = std::make_unique<CsvWriter>(args.output);
  Detector detector(options);
  const auto records = run_with_progress(detector, source, "eval", csv.get());
  const eval::Metrics metrics = eval::evaluate(records, gt, options.search.min_gap);

  nlohmann::json json = metrics_json(metrics);
  json["mode"] = to_string(options.search.mode);
  json["verification"] = verification_stages(options.verification);
  json["nodes"] = detector.nodes();
  json["bytes_per_frame"] = detector.bytes_per_frame();
  json["sequence"] = args.sequence;
  json["ground_truth"] = args.gt;
  json["config_yaml"] = io::to_yaml(options);
  write_json(json, args.json);
  std::cout << args.sequence << " (" << to_string(options.search.mode) << ", verification "
            << verification_stages(options.verification) << ")\n";
  print_metrics(metrics, detector.nodes(), std::cout);
}

}  // namespace

void register_eval(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* cmd = app.add_subcommand(
      "eval", "detect loops in a sequence and score them against ground truth (strict protocol)");
  cmd->add_option("--sequence", args->sequence,
                  "folder of images (natural order) or a text file listing image paths")
      ->required();
  cmd->add_option("--gt", args->gt, "ground truth, pairs text format: 'q m' per line, 0-based")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--json", args->json, "write the metrics here as JSON")->required();
  cmd->add_option("--output", args->output, "also write the per-frame CSV of `lsgd run` here");
  args->detector.add_to(*cmd);
  cmd->get_option("--min-gap")->required();
  cmd->callback([args] { evaluate(*args); });
}

}  // namespace lsgd::cli
