// lsgd sweep --dataset NAME=SEQUENCE,GT,MIN_GAP ... [--set KEY=VALUES ...] [--config FILE]
//            [--mode M] [--threshold T] [--verify S] [--csv F] [--markdown F] [--json F] [--jobs N]
// Runs every configuration of the grid on every dataset and scores it (strict
// protocol): one table row per (dataset, configuration).
#include <algorithm>
#include <atomic>
#include <charconv>
#include <exception>
#include <iomanip>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>

#include "commands.h"
#include "internal/check.h"
#include "common.h"
#include "files.h"
#include "lsgd/error.h"
#include "lsgd/eval/dataset.h"
#include "lsgd/eval/groundtruth.h"
#include "lsgd/eval/sweep.h"
#include "lsgd/io/config.h"
#include "lsgd/io/sequence.h"

namespace lsgd::cli {
namespace {

struct SweepArgs {
  std::vector<std::string> datasets;
  std::vector<std::string> sets;
  std::string csv;
  std::string markdown;
  std::string json;
  int jobs = 1;
  bool strict = false;
  DetectorFlags detector;
};

using Dataset = eval::SweepData;
using Cell = eval::SweepCell;
using Row = eval::SweepRow;

// Shortest text that reads back to exactly `value`.
std::string exact(double value) { return shortest_text(value); }

std::string fixed(double value, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}

using eval::csv_field;

// A table written row by row: held against a second writer (io::OutputLock)
// before it is truncated.
std::unique_ptr<std::ofstream> open_output(const std::string& path, const std::string& what,
                                           std::vector<io::OutputLock>& locks) {
  locks.emplace_back(path, what);
  auto out = std::make_unique<std::ofstream>(path);
  if (!*out) throw_cannot_write(path);
  return out;
}

// The table: Markdown on stdout (and --markdown), CSV (--csv), JSON (--json).
// Rows are written in grid order as soon as they and every row before them
// are done, each flushed; rows after a failure are written by finish().
class SweepOutput {
 public:
  SweepOutput(const SweepArgs& args, std::vector<std::string> keys,
              const std::vector<Dataset>& datasets, const std::vector<Cell>& cells)
      : args_(args),
        keys_(std::move(keys)),
        datasets_(datasets),
        cells_(cells),
        rows_(cells.size()) {
    if (!args.csv.empty()) csv_ = open_output(args.csv, "--csv", locks_);
    if (!args.markdown.empty()) markdown_ = open_output(args.markdown, "--markdown", locks_);
    // Checked now, not after the runs, and written whole at the end: opening
    // it here emptied a previous sweep's JSON, lost when this one failed or
    // was interrupted.
    if (!args.json.empty()) io::check_output_file(args.json, "--json");
  }

  void write_headers(const DetectorOptions& base) {
    if (csv_) {
      *csv_ << "dataset";
      for (const auto& k : keys_) *csv_ << ',' << csv_field(k);
      *csv_ << ",min_gap,frames,positives,declared_loops,declared_true,declared_false,"
               "precision_at_decision,recall_at_decision,recall_at_100_precision,"
               "threshold_at_100_precision,"
               "precision_at_100_recall,average_precision,recall_at_1,recall_at_5,recall_at_10,"
               "prt,ms_per_frame_median,ms_per_frame_p95,nodes,bytes_per_frame,skipped_frames,"
               "decision_recall_at_100_precision,decision_average_precision\n"
            << std::flush;
    }
    std::ostringstream md;
    md << "Sweep, strict protocol (docs/evaluation.md): each configuration runs online on each "
          "dataset; one row per (dataset, configuration).\n\n";
    for (const Dataset& d : datasets_) {
      md << "- " << d.spec.name << ": " << d.spec.sequence << ", " << d.source.frames << " frames, "
         << d.positives << " positives, window w = " << d.spec.min_gap << "\n";
    }
    md << "\nBase configuration: " << describe_base(base) << ".\n\n"
       << (args_.jobs == 1
               ? "Times: Detector::process() per frame (image decoding excluded), one cell at a "
                 "time (--jobs 1).\n\n"
               : "Times: --jobs " + std::to_string(args_.jobs) +
                     ": cells ran in parallel threads, so ms/frame is NOT comparable between "
                     "rows or with single-thread runs (use --jobs 1 for timings).\n\n")
       << "| dataset |";
    for (const auto& k : keys_) md << ' ' << k << " |";
    md << " frames | positives | declared (TP / FP) | recall at decision | R@100P | P@100R | AP |"
          " R@1 | R@5 | R@10 | PRT | ms/frame median | ms/frame p95 | nodes | bytes/frame |\n|---|";
    for (std::size_t i = 0; i < keys_.size(); ++i) md << "---|";
    md << "---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    markdown(md.str());
  }

  void add(std::size_t index, const Row& row) {
    std::lock_guard<std::mutex> lock(mutex_);
    rows_[index] = row;
    while (next_ < rows_.size() && rows_[next_].done) write_row(next_++);
  }

  // Writes the rows still held back (after a failure) and the JSON.
  void finish() {
    std::lock_guard<std::mutex> lock(mutex_);
    for (; next_ < rows_.size(); ++next_) {
      if (rows_[next_].done) write_row(next_);
    }
    if (args_.json.empty()) return;
    nlohmann::json json;
    json["protocol"] = "strict";
    json["jobs"] = args_.jobs;
    json["times_comparable"] = args_.jobs == 1;
    json["keys"] = keys_;
    json["datasets"] = nlohmann::json::array();
    for (const Dataset& d : datasets_) {
      json["datasets"].push_back({{"name", d.spec.name},
                                  {"sequence", d.spec.sequence},
                                  {"ground_truth", d.spec.ground_truth},
                                  {"min_gap", d.spec.min_gap},
                                  {"frames", d.source.frames},
                                  {"positives", d.positives}});
    }
    json["rows"] = nlohmann::json::array();
    for (std::size_t i = 0; i < rows_.size(); ++i) {
      if (rows_[i].done) json["rows"].push_back(row_json(i));
    }
    write_json(json, args_.json);
  }

 private:
  std::string describe_base(const DetectorOptions& base) const {
    const DetectorFlags& f = args_.detector;
    std::string text = f.config.empty() ? "defaults" : "--config " + f.config;
    if (!f.mode.empty()) text += ", --mode " + f.mode;
    if (f.threshold) text += ", --threshold " + exact(*f.threshold);
    if (!f.verify.empty()) text += ", --verify " + f.verify;
    const std::pair<std::string, std::string> shown[] = {
        {"segmentation.superpixel_size", std::to_string(base.segmentation.superpixel_size)},
        {"segmentation.intensity_scale", exact(base.segmentation.intensity_scale)},
        {"similarity.metric", to_string(base.similarity.metric)},
        {"search.mode", base.search.mode},
        {"verification.stages", verification_stages(base.verification)}};
    std::string fixed_keys;
    for (const auto& [key, value] : shown) {
      if (std::find(keys_.begin(), keys_.end(), key) != keys_.end()) continue;
      fixed_keys += (fixed_keys.empty() ? "" : ", ") + key + " " + value;
    }
    if (!fixed_keys.empty()) text += " (" + fixed_keys + ")";
    return text + "; the window comes from each dataset; --json holds every row's full config";
  }

  void markdown(const std::string& text) {
    std::cout << text << std::flush;
    if (!std::cout) throw IoError("error while writing the table to standard output");
    if (markdown_) {
      *markdown_ << text << std::flush;
      if (!*markdown_) {
        throw IoError("error while writing Markdown file '" + args_.markdown + "': is the disk full?");
      }
    }
  }

  void write_row(std::size_t i) {
    const Cell& cell = cells_[i];
    const eval::Metrics& m = rows_[i].metrics;
    std::ostringstream md;
    md << "| " << cell.dataset->spec.name << " |";
    for (const auto& v : cell.point->values) md << ' ' << v << " |";
    md << ' ' << m.frames << " | " << m.positives << " | " << m.declared_loops << " ("
       << m.declared_true << " / " << m.declared_false << ") | " << fixed(m.recall_at_decision, 3)
       << " | " << fixed(m.recall_at_100_precision, 3)
       << " | " << fixed(m.precision_at_100_recall, 3) << " | " << fixed(m.average_precision, 3)
       << " | " << fixed(m.recall_at_1, 3) << " | " << fixed(m.recall_at_5, 3) << " | "
       << fixed(m.recall_at_10, 3) << " | " << fixed(m.prt, 3) << " | "
       << fixed(m.ms_per_frame_median, 2) << " | " << fixed(m.ms_per_frame_p95, 2) << " | "
       << rows_[i].nodes << " | " << rows_[i].bytes_per_frame << " |\n";
    markdown(md.str());
    if (!csv_) return;
    *csv_ << csv_field(cell.dataset->spec.name);
    for (const auto& v : cell.point->values) *csv_ << ',' << csv_field(v);
    *csv_ << ',' << m.min_gap << ',' << m.frames << ',' << m.positives << ','
          << m.declared_loops << ',' << m.declared_true << ',' << m.declared_false << ','
          << exact(m.precision_at_decision) << ',' << exact(m.recall_at_decision) << ','
          << exact(m.recall_at_100_precision) << ',' << exact(m.threshold_at_100_precision) << ','
          << exact(m.precision_at_100_recall) << ',' << exact(m.average_precision) << ','
          << exact(m.recall_at_1) << ',' << exact(m.recall_at_5) << ',' << exact(m.recall_at_10)
          << ',' << exact(m.prt) << ',' << exact(m.ms_per_frame_median) << ','
          << exact(m.ms_per_frame_p95) << ',' << rows_[i].nodes << ',' << rows_[i].bytes_per_frame
          << ',' << rows_[i].skipped << ',' << exact(m.decision_recall_at_100_precision) << ','
          << exact(m.decision_average_precision) << '\n'
          << std::flush;
    if (!*csv_) throw IoError("error while writing CSV file '" + args_.csv + "': is the disk full?");
  }

  nlohmann::json row_json(std::size_t i) const {
    const Cell& cell = cells_[i];
    nlohmann::json values = nlohmann::json::object();
    for (std::size_t k = 0; k < keys_.size(); ++k) values[keys_[k]] = cell.point->values[k];
    nlohmann::json row = metrics_json(rows_[i].metrics);
    row["dataset"] = cell.dataset->spec.name;
    row["values"] = values;
    row["mode"] = cell.options.search.mode;
    row["verification"] = verification_stages(cell.options.verification);
    row["nodes"] = rows_[i].nodes;
    row["bytes_per_frame"] = rows_[i].bytes_per_frame;
    row["skipped_frames"] = rows_[i].skipped;
    row["config_yaml"] = io::to_yaml(cell.options);
    return row;
  }

  const SweepArgs& args_;
  std::vector<std::string> keys_;
  const std::vector<Dataset>& datasets_;
  const std::vector<Cell>& cells_;
  std::vector<Row> rows_;
  std::size_t next_ = 0;  // first row not yet written
  std::mutex mutex_;
  std::vector<io::OutputLock> locks_;  // declared first: released after the files close
  std::unique_ptr<std::ofstream> csv_;
  std::unique_ptr<std::ofstream> markdown_;
};

// One cell through the frame loop of every command (run_frames: its progress
// bar when `progress`, skipped frames reported once per dataset); bad frames
// are skipped as by lsgd eval unless --strict.
Row run_cell(const Cell& cell, bool progress, bool strict) {
  Detector detector(cell.options);
  eval::RunOptions options;
  options.skip_bad_frames = !strict;
  const FrameRun run = run_frames(detector, cell.dataset->source, cell.label, options, {},
                                  progress, cell.first_of_dataset);
  return {eval::evaluate(run.records, cell.dataset->gt, cell.options.search.min_gap),
          detector.nodes(), detector.bytes_per_frame(), run.skipped, true};
}

// The cells on --jobs threads (eval::run_sweep); rows after a failure are
// written too, then the failure is rethrown.
void run_cells(const std::vector<Cell>& cells, int jobs, bool strict, SweepOutput& output) {
  std::exception_ptr failure;
  try {
    eval::run_sweep(
        cells, jobs, [&output](std::size_t i, const Row& row) { output.add(i, row); },
        [jobs, strict](const Cell& cell) { return run_cell(cell, jobs == 1, strict); });
  } catch (...) {
    failure = std::current_exception();
  }
  output.finish();
  if (failure) std::rethrow_exception(failure);
}

void sweep(const SweepArgs& args) {
  // Everything is validated before the first run: grid, configs, datasets, outputs.
  const DetectorOptions base = args.detector.resolve();
  const std::vector<std::pair<std::string, std::string>> fixed = args.detector.keys();
  std::vector<eval::SweepAxis> axes;
  std::vector<std::string> keys;
  for (const std::string& spec : args.sets) {
    axes.push_back(eval::parse_sweep_axis(spec));
    keys.push_back(axes.back().key);
    for (const auto& [key, flag] : fixed) {  // the swept values would replace it without a word
      if (key == axes.back().key) {
        throw InvalidArgument("--set " + internal::shown_value(spec) + " sweeps " + key + ", which " + internal::shown_value(flag) +
                              " also sets: give one");
      }
    }
  }
  for (const auto& [key, flag] : fixed) {
    if (key == "search.min_gap") {
      throw InvalidArgument(flag + ": the window is set per dataset, by its spec NAME=...,MIN_GAP "
                            "(--dataset), so it would be ignored");
    }
  }
  const std::vector<eval::SweepPoint> points = eval::expand_sweep(axes, base);
  std::vector<Dataset> datasets;
  for (const std::string& spec : args.datasets) {
    datasets.push_back(eval::open_sweep_dataset(eval::parse_dataset_spec(spec)));
    for (std::size_t i = 0; i + 1 < datasets.size(); ++i) {
      if (datasets[i].spec.name == datasets.back().spec.name) {
        throw InvalidArgument("--dataset " + internal::shown_value(spec) + ": the name '" + internal::shown_value(datasets[i].spec.name) +
                              "' is used twice");
      }
    }
  }
  CommandFiles files;
  files.input(args.detector.config, "--config");
  for (const Dataset& d : datasets) {
    files.input(d.spec.sequence, "--dataset " + d.spec.name);
    files.sequence(d.all, "--dataset " + d.spec.name, "input image");
    files.input(d.spec.ground_truth, "--dataset " + d.spec.name);
  }
  files.output(args.csv, "--csv");
  files.output(args.markdown, "--markdown");
  files.output(args.json, "--json");
  files.check();
  const std::vector<Cell> cells = eval::sweep_cells(datasets, points, keys);
  SweepOutput output(args, keys, datasets, cells);
  output.write_headers(base);
  run_cells(cells, args.jobs, args.strict, output);
}

}  // namespace

void register_sweep(CLI::App& app) {
  auto args = std::make_shared<SweepArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sweep", "run a grid of detector configurations on datasets and tabulate the scores");
  cmd->add_option("--dataset", args->datasets,
                  "NAME=SEQUENCE,GT,MIN_GAP or NAME=DIR,MIN_GAP (DIR holds sequence.txt and "
                  "groundtruth.txt); repeat for several datasets")
      ->required()
      ->take_all();
  cmd->add_option("--set", args->sets,
                  "KEY=VALUES: a config key (e.g. search.nodes.beta) and a comma list or an "
                  "inclusive range a:b:step; repeat for a cross product, first --set slowest")
      ->take_all();
  cmd->add_option("--csv", args->csv, "write the table as CSV here (rows flushed as they finish)")
      ->check(kNonEmptyPath);
  cmd->add_option("--markdown", args->markdown, "also write the Markdown table here")
      ->check(kNonEmptyPath);
  cmd->add_option("--json", args->json, "write every row's metrics, PR curve and config here")
      ->check(kNonEmptyPath);
  cmd->add_option("--jobs", args->jobs,
                  "cells run in parallel threads (default 1; times only comparable with 1)")
      ->check(CLI::Range(1, 256));
  cmd->add_flag("--strict", args->strict,
                "stop at the first image that cannot be read or is rejected; default: skip it "
                "as lsgd eval does (reported once per dataset, counted in skipped_frames)");
  args->detector.add_to(*cmd);
  // The window is a property of each dataset here (--dataset ...,MIN_GAP).
  if (CLI::Option* gap = cmd->get_option_no_throw("--min-gap")) cmd->remove_option(gap);
  cmd->callback([args] { sweep(*args); });
}

}  // namespace lsgd::cli
