// lsgd eval (--sequence PATH | --detections CSV) --gt FILE --min-gap W --json OUT
//           [--protocol strict|lsgddn-reference] [--layout L ...] [--every K ...]
// Runs the detector over a sequence, or reads another system's detections, and
// scores them against ground truth moved onto the evaluated frames.
#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>
#include <array>
#include <fstream>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <system_error>

#include "commands.h"
#include "common.h"
#include "files.h"
#include "lsgd/error.h"
#include "lsgd/eval/detections.h"
#include "lsgd/eval/groundtruth.h"
#include "lsgd/eval/gt_formats.h"
#include "lsgd/eval/gt_remap.h"
#include "lsgd/eval/dataset.h"
#include "lsgd/eval/report.h"
#include "lsgd/eval/runner.h"
#include "lsgd/io/config.h"
#include "lsgd/io/layouts.h"
#include "lsgd/limits.h"

namespace lsgd::cli {
namespace {

struct EvalArgs {
  std::string sequence;
  std::string detections;
  std::string gt;
  std::string json;
  std::string output;
  std::optional<std::int64_t> frames;
  std::string protocol = "strict";
  std::optional<std::int64_t> tolerance;
  std::string subsample_match = "exact";
  std::string gt_rows;
  std::string gt_format = "auto";
  std::string report;  // HTML report path
  std::string poses;   // KITTI poses for the report's trajectory
  std::vector<std::string> compare;  // other systems' detections: [NAME=]CSV
  DetectorFlags detector;
  SequenceFlags layout;
  CLI::App* command = nullptr;  // to tell which flags were given
};

eval::GroundTruthOptions gt_options(const EvalArgs& args) {
  eval::GroundTruthOptions gt;
  gt.format = eval::parse_gt_format(args.gt_format);
  if (!args.gt_rows.empty()) gt.rows = eval::parse_gt_rows(args.gt_rows);
  gt.match = eval::parse_subsample_match(args.subsample_match);
  return gt;
}

// Rejects flag combinations that would be silently ignored.
void check_flags(const EvalArgs& args, io::Layout layout) {
  const CLI::App& cmd = *args.command;
  if (args.sequence.empty() == args.detections.empty()) {
    throw InvalidArgument(
        "give --sequence (run the detector) or --detections (score a CSV), exactly one");
  }
  if (!args.detections.empty()) {
    for (const char* flag :
         {"--output", "--config", "--mode", "--threshold", "--verify", "--strict"}) {
      if (cmd.count(flag) > 0) {
        throw InvalidArgument(std::string(flag) +
                              " applies when the detector runs (--sequence), "
                              "not to --detections");
      }
    }
  } else if (args.frames) {
    throw InvalidArgument("--frames applies to --detections; with --sequence the sequence says");
  }
  if (args.tolerance && args.protocol != "lsgddn-reference") {
    throw InvalidArgument("--tolerance applies to --protocol lsgddn-reference only");
  }
  if (!args.poses.empty() && args.report.empty()) {
    throw InvalidArgument("--poses draws the trajectory of --report: give --report too");
  }
  if (!args.gt_rows.empty() && layout != io::kFabmapLayout) {
    throw InvalidArgument("--gt-rows applies to --layout fabmap only");
  }
}

eval::Metrics score(const EvalArgs& args, const std::vector<eval::FrameRecord>& records,
                    const eval::GroundTruth& gt, std::int64_t min_gap) {
  if (args.protocol == "strict") return eval::evaluate(records, gt, min_gap);
  eval::ReferenceProtocolOptions reference;
  reference.min_gap = min_gap;
  if (args.tolerance) reference.tolerance = *args.tolerance;
  return eval::evaluate_lsgddn_reference(records, gt, reference);
}

// --compare [NAME=]CSV: the legend's name (the file's stem unless NAME= is
// given; a file whose own name holds '=' is taken whole) and the file.
struct CompareSpec {
  std::string name, file;
};
CompareSpec parse_compare(const std::string& spec) {
  const std::size_t eq = spec.find('=');
  // error_code: a spec that is no path the system takes (a NAME= beyond the
  // name limit) is NAME=CSV, not the file system's exception ("filesystem
  // error: status: File name too long").
  std::error_code ec;
  if (eq != std::string::npos && eq > 0 && !std::filesystem::exists(spec, ec)) {
    return {spec.substr(0, eq), spec.substr(eq + 1)};
  }
  return {std::filesystem::path(spec).stem().string(), spec};
}

// Other systems' detections on the same frames, scored by the same evaluator
// (protocol, window, ground truth) as ours.
std::vector<eval::ComparedSystem> compared_systems(const EvalArgs& args, const eval::GroundTruth& gt,
                                                   std::int64_t min_gap, nlohmann::json& json) {
  std::vector<eval::ComparedSystem> out;
  nlohmann::json rows = nlohmann::json::array();
  for (const std::string& spec : args.compare) {
    const CompareSpec c = parse_compare(spec);
    const std::vector<eval::FrameRecord> records = eval::read_detections(c.file, gt.frames());
    out.push_back({c.name, score(args, records, gt, min_gap)});
    nlohmann::json row = metrics_json(out.back().metrics);
    row["name"] = c.name;
    row["detections"] = c.file;
    row.erase("curve");
    rows.push_back(row);
    const eval::Metrics& m = out.back().metrics;
    std::cout << "compared: " << c.name << " (" << c.file << "): declared " << m.declared_loops << " ("
              << m.declared_true << " true, " << m.declared_false << " false), R@100P "
              << m.recall_at_100_precision << ", AP " << m.average_precision << ", R@1 "
              << m.recall_at_1 << "\n";
  }
  if (!args.compare.empty()) json["compared"] = rows;
  return out;
}

// The file of each --compare; two systems of one name (the legend and the
// JSON's rows could not tell them apart) are refused before any work.
std::vector<std::string> compared_files(const EvalArgs& args) {
  std::vector<std::string> files;
  std::map<std::string, std::string> names;  // name -> its spec
  for (const std::string& spec : args.compare) {
    const CompareSpec c = parse_compare(spec);
    const auto [it, fresh] = names.emplace(c.name, spec);
    if (!fresh) {
      throw InvalidArgument("--compare " + spec + " and --compare " + it->second + " are both named '" + c.name +
                            "': give each its own NAME= (nothing was run)");
    }
    files.push_back(c.file);
  }
  return files;
}

void describe_inputs(const EvalArgs& args, const io::SequenceOptions& options, io::Layout layout,
                     const eval::GroundTruth& gt, nlohmann::json& json) {
  json["ground_truth"] = args.gt;
  json["ground_truth_pairs"] = gt.pairs();
  json["layout"] = layout;
  if (layout == io::kFabmapLayout) {
    json["side"] = io::to_string(options.side);
    json["gt_rows"] = args.gt_rows.empty() ? "pair" : args.gt_rows;
  }
  json["first"] = options.selection.first;
  json["last"] = options.selection.last;
  json["every"] = options.selection.every;
  if (!options.selection.keeps_all()) json["subsample_match"] = args.subsample_match;
}

// --poses, read and checked against the evaluated frames before anything
// runs (empty without --poses): x, z of each frame's camera centre.
std::vector<eval::Pose> report_poses(const EvalArgs& args, const eval::GroundTruth& gt) {
  if (args.poses.empty()) return {};
  std::vector<eval::Pose> poses = eval::read_kitti_poses(args.poses);
  if (static_cast<std::int64_t>(poses.size()) != gt.frames()) {
    throw FormatError("--poses " + args.poses + " has " + std::to_string(poses.size()) +
                      " poses but " + std::to_string(gt.frames()) +
                      " frames are evaluated (subsampled sequences: subsample the poses too)");
  }
  std::vector<std::array<double, 2>> positions;
  for (const eval::Pose& p : poses) positions.push_back({p.x, p.z});
  if (const std::string span = eval::trajectory_span_beyond_doubles(positions); !span.empty()) {
    throw FormatError("--poses " + args.poses + ": its " + span + " (the report could not draw them)");
  }
  return poses;
}

// The parts of the HTML report common to both paths; the trajectory is
// --poses' (report_poses()).
eval::ReportInput report_input(const EvalArgs& args, const eval::Metrics& metrics,
                               const std::vector<eval::FrameRecord>& records,
                               const eval::GroundTruth& gt, const std::vector<eval::Pose>& poses) {
  eval::ReportInput input;
  input.title = "lsgd eval";
  input.ground_truth = args.gt;
  input.protocol = metrics.protocol;
  input.metrics = &metrics;
  input.records = &records;
  input.gt = &gt;
  input.command = command_line();
  input.version = version_text();
  for (const eval::Pose& p : poses) input.trajectory.push_back({p.x, p.z});
  return input;
}

// Nothing the command writes may be something it reads.
void check_files(const EvalArgs& args, const io::Sequence& sequence) {
  CommandFiles files;
  files.input(args.detector.config, "--config");
  files.input(args.sequence, "--sequence");
  files.sequence(sequence, "--sequence", "input image");
  files.input(args.detections, "--detections");
  files.input(args.gt, "--gt");
  files.input(args.poses, "--poses");
  files.inputs(compared_files(args), "--compare", "detections");
  files.output(args.json, "--json");
  files.output(args.output, "--output");
  files.output(args.report, "--report");
  files.check();
}

void evaluate_detections(const EvalArgs& args, const io::SequenceOptions& options) {
  check_files(args, {});
  eval::GroundTruth gt = eval::evaluated_groundtruth(args.gt, gt_options(args), options,
                                                     options.layout, args.frames ? *args.frames : -1);
  // A pairs file only implies frames up to its largest id; when frame ids map
  // one to one, detections of later (loop-free) frames extend it.
  if (!args.frames && options.layout != io::kFabmapLayout && options.selection.keeps_all()) {
    const std::vector<eval::FrameRecord> rows = eval::read_detections(args.detections);
    const std::int64_t extent = rows.empty() ? 0 : rows.back().frame + 1;
    if (extent > gt.frames()) {
      gt = eval::evaluated_groundtruth(args.gt, gt_options(args), options, options.layout, extent);
    }
  }
  const auto records = eval::read_detections(args.detections, gt.frames());
  // What else is read is read now: a bad --compare or --poses fails before
  // anything is scored or written.
  for (const std::string& file : compared_files(args)) eval::read_detections(file, gt.frames());
  const std::vector<eval::Pose> poses = report_poses(args, gt);
  const std::int64_t min_gap = *args.detector.min_gap;
  // Revisits without a row count as missed, matches to the query itself or a
  // later frame as false loops: say so when there are any.
  const std::vector<std::string> warnings = eval::detections_warnings(records, gt, min_gap, args.detections);
  for (const std::string& w : warnings) std::cerr << "lsgd: warning: " << w << "\n";
  const eval::Metrics metrics = score(args, records, gt, min_gap);
  nlohmann::json json = metrics_json(metrics);
  json["warnings"] = warnings;
  json["detections"] = args.detections;
  describe_inputs(args, options, options.layout, gt, json);
  std::cout << args.detections << " (detections read from the file, no detector run)\n";
  print_metrics(metrics, 0, std::cout);
  const auto compared = compared_systems(args, gt, min_gap, json);
  write_json(json, args.json);
  if (!args.report.empty()) {
    eval::ReportInput input = report_input(args, metrics, records, gt, poses);
    input.compared = compared;
    input.warnings = warnings;
    input.sequence = args.detections + " (detections of another system)";
    input.declared = true;
    eval::write_report(input, args.report);
    std::cout << "report: " << args.report << "\n";
  }
}

void evaluate_sequence(const EvalArgs& args, const io::SequenceOptions& options) {
  const DetectorOptions detector_options = args.detector.resolve();
  // Reads the ground truth before the (long) run so a wrong file fails at once.
  const eval::Dataset dataset = eval::open_dataset(args.sequence, options, args.gt, gt_options(args));
  const io::Layout layout = dataset.layout;
  const io::Sequence& sequence = dataset.frames;
  const eval::GroundTruth& gt = dataset.gt;
  check_files(args, dataset.all);
  // Every --compare file is read now: a bad one fails before the (long) run.
  for (const std::string& file : compared_files(args)) eval::read_detections(file, gt.frames());
  const std::vector<eval::Pose> poses = report_poses(args, gt);  // --poses, the same
  const eval::FrameSource source = eval::sequence_source(sequence);
  std::unique_ptr<CsvWriter> csv;
  if (!args.output.empty()) csv = std::make_unique<CsvWriter>(args.output);
  Detector detector(detector_options);
  eval::RunOptions run_options;
  run_options.skip_bad_frames = !args.layout.strict;
  const FrameRun run = run_frames(detector, source, "eval", run_options,
                                  [&](const Result& r, const eval::FrameTimes&) {
                                    if (csv) csv->write(r, source.name(r.frame));
                                  });
  const std::vector<eval::FrameRecord>& records = run.records;
  const eval::Metrics metrics = score(args, records, gt, detector_options.search.min_gap);
  const std::vector<std::string> warnings = eval::setup_warnings(detector, gt);
  for (const std::string& w : warnings) std::cerr << "lsgd: warning: " << w << "\n";

  nlohmann::json json = metrics_json(metrics);
  json["warnings"] = warnings;
  json["mode"] = detector_options.search.mode;
  json["verification"] = verification_stages(detector_options.verification);
  json["nodes"] = detector.nodes();
  json["skipped_frames"] = run.skipped;
  json["bytes_per_frame"] = detector.bytes_per_frame();
  json["sequence"] = args.sequence;
  describe_inputs(args, options, layout, gt, json);
  json["config_yaml"] = io::to_yaml(detector_options);
  json["width"] = detector.width();
  json["height"] = detector.height();
  std::cout << args.sequence << " (" << detector_options.search.mode << ", verification "
            << verification_stages(detector_options.verification) << ")\n";
  print_metrics(metrics, detector.nodes(), std::cout);
  if (const std::int64_t skipped = run.skipped; skipped > 0) {
    std::cout << "  skipped " << skipped
              << " frames (unreadable or rejected images; scored as frames without a report)\n";
  }
  const auto compared = compared_systems(args, gt, detector_options.search.min_gap, json);
  write_json(json, args.json);
  if (!args.report.empty()) {
    eval::ReportInput input = report_input(args, metrics, records, gt, poses);
    input.compared = compared;
    input.width = detector.width();
    input.height = detector.height();
    input.grid_rows = detector.store().grid().rows;
    input.grid_cols = detector.store().grid().cols;
    input.image = [&sequence](std::int64_t f) {
      return io::read_image(sequence.images.at(static_cast<std::size_t>(f)));
    };
    input.sequence = args.sequence;
    input.mode = detector_options.search.mode;
    input.verification = verification_stages(detector_options.verification);
    input.config_yaml = io::to_yaml(detector_options);
    // Frames are named by their ids; a skipped frame has no descriptor (NaN).
    input.similarity = [&detector](std::int64_t a, std::int64_t b) {
      const std::int64_t fa = detector.frame_of(a), fb = detector.frame_of(b);
      return fa < 0 || fb < 0 ? std::numeric_limits<double>::quiet_NaN() : detector.similarity(fa, fb);
    };
    input.nodes = detector.nodes();
    input.bytes_per_frame = detector.bytes_per_frame();
    input.declared = true;  // the loops the detector declared; false ones show
    input.warnings = warnings;
    eval::write_report(input, args.report);
    std::cout << "report: " << args.report << "\n";
  }
}

void evaluate(const EvalArgs& args) {
  const io::SequenceOptions options = args.layout.resolve();
  check_flags(args, options.layout);
  if (args.detections.empty()) {
    evaluate_sequence(args, options);
  } else {
    evaluate_detections(args, options);
  }
}

}  // namespace

void register_eval(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "detect loops in a sequence (or read another system's detections) and score them against "
      "ground truth (strict protocol by default)");
  args->command = cmd;
  cmd->add_option("--sequence", args->sequence,
                  "folder of images (natural order), list file, or a dataset layout (--layout)")
      ->check(kNonEmptyPath);
  cmd->add_option("--detections", args->detections,
                  "score this CSV instead of running the detector: query,match,score per line "
                  "(match -1: no loop) or the CSV of `lsgd run`")
      ->check(kExistingFile);
  cmd->add_option("--gt", args->gt,
                  "ground truth: pairs text ('q m' per line, 0-based), MATLAB .mat loop matrix, "
                  "KITTI poses or LSGDDN loopinf (detected from the file)")
      ->required()
      ->check(kExistingFile);
  cmd->add_option("--gt-format", args->gt_format, [] {
        std::string help = "auto (default: by content)";
        for (const eval::GtFormatType& t : eval::gt_format_types()) {
          help += std::string(", ") + t.name + " (" + t.summary + ")";
        }
        return help + "; `lsgd gt convert` takes the KITTI poses' distances";
      }())
      ->check(one_of(eval::gt_format_names()));
  cmd->add_option("--report", args->report,
                  "write a self-contained HTML report here (PR curve, trajectory with --poses or "
                  "scores over the run, example loops as thumbnails, similarity matrix with "
                  "ground truth, timings, configuration, command line and version)")
      ->check(kNonEmptyPath);
  cmd->add_option("--poses", args->poses,
                  "KITTI poses file (12 or 13 columns) of the evaluated frames: draws the "
                  "trajectory and the loops found in the --report")
      ->check(kExistingFile);
  cmd->add_option("--compare", args->compare,
                  "[NAME=]CSV: another system's detections on the same frames (the formats "
                  "--detections reads), scored by the same evaluator; drawn on the --report's "
                  "PR plot and written to the JSON's 'compared'; repeatable")
      ->check(kNonEmptyPath);
  cmd->add_option("--json", args->json, "write the metrics here as JSON")->required()
      ->check(kNonEmptyPath);
  cmd->add_option("--output", args->output, "also write the per-frame CSV of `lsgd run` here")
      ->check(kNonEmptyPath);
  cmd->add_option("--frames", args->frames,
                  "with --detections: frames of the full sequence (ground-truth rows; default: "
                  "from the ground truth)")
      ->check(kFrameCount);
  cmd->add_option("--protocol", args->protocol,
                  "strict (default) or lsgddn-reference: the LSGDDN authors' lenient evaluator, "
                  "only to compare with their paper")
      ->check(one_of({"strict", "lsgddn-reference"}));
  cmd->add_option("--tolerance", args->tolerance,
                  "lsgddn-reference: a report j is correct when |j - g| < T for a ground-truth "
                  "loop g (default 50)")
      ->check(CLI::Range(std::int64_t{1}, lsgd::kMaxWindowFrames));
  cmd->add_option("--subsample-match", args->subsample_match,
                  "with --every/--first/--last: exact (frames a, b match iff the kept images "
                  "match; default) or block (iff any frames of their blocks of K match)")
      ->check(one_of({"exact", "block"}));
  cmd->add_option("--gt-rows", args->gt_rows,
                  "FAB-MAP ground truth: one row per left/right pair (default; City Centre's "
                  "1237 rows) or per image (New College's 2146 rows)")
      ->check(one_of({"pair", "image"}));
  args->detector.add_to(*cmd);
  args->layout.add_to(*cmd);
  cmd->get_option("--min-gap")
      ->required()
      ->description(
          "temporal window in frames (counted after --every): only frames j < i - W "
          "are candidates and ground-truth loops");
  cmd->callback([args] { evaluate(*args); });
}

}  // namespace lsgd::cli
