// Pieces shared by the lsgd subcommands: options from YAML plus flags, a
// progress bar, the CSV writer and the evaluation summary (text and JSON).
#pragma once

#include <cstdint>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "lsgd/detector.h"
#include "lsgd/eval/metrics.h"
#include "lsgd/eval/runner.h"
#include "lsgd/io/layouts.h"

namespace CLI {
class App;
}

namespace lsgd::cli {

// Flags every detector-running subcommand accepts on top of --config.
struct DetectorFlags {
  std::string config;                  // YAML file; empty: defaults
  std::string mode;                    // exhaustive | nodes; empty: from config
  std::optional<std::int64_t> min_gap;  // overrides search.min_gap
  std::optional<double> threshold;      // overrides decision.threshold
  std::string verify;                   // none | temporal | geometric | temporal,geometric

  void add_to(CLI::App& command);
  // Defaults, then the config file, then the flags; validated.
  DetectorOptions resolve() const;
};

// Flags choosing which images are the frames, shared by run and eval:
// --layout, --kitti-sequence, --camera, --side, --first, --last, --every.
struct SequenceFlags {
  std::string layout = "auto";  // auto | folder | list | kitti | fabmap | neu
  std::string kitti_sequence;   // KITTI: PATH is the dataset root, this is NN
  int camera = -1;              // KITTI image_<camera>; -1: 0 or PATH's image_X
  std::string side;             // FAB-MAP: left | right | both; empty: left
  std::int64_t first = 0;
  std::int64_t last = -1;
  std::int64_t every = 1;
  bool strict = false;  // stop at the first unreadable or rejected image

  void add_to(CLI::App& command);
  // Validated options. InvalidArgument for a flag that does not apply to the
  // chosen layout (--side without --layout fabmap, --camera with fabmap, ...).
  io::SequenceOptions resolve() const;
};

// A one-line progress bar on stderr, drawn only when stderr is a terminal.
class Progress {
 public:
  Progress(std::int64_t total, std::string label);
  ~Progress();
  void update(std::int64_t done, double ms_per_frame);

 private:
  std::int64_t total_;
  std::string label_;
  bool enabled_;
  std::int64_t last_draw_ns_ = 0;
};

// Writes `lsgd run` rows:
// frame,image,loop_frame,candidate_frame,score,ms,appearance,inliers.
// Each row is flushed, so an error later in the run loses nothing written.
class CsvWriter {
 public:
  explicit CsvWriter(const std::string& path);  // empty path: stdout
  void write(const Result& result, const std::string& image);
  std::int64_t loops() const { return loops_; }  // rows written with a loop

 private:
  std::int64_t loops_ = 0;
  std::unique_ptr<std::ofstream> file_;
  std::ostream* out_;
};

// Runs the detector over the source with a progress bar labelled `label`,
// writing each frame's CSV row to `csv` when given. With skip_bad_frames, an
// unreadable or rejected image is reported on stderr ("skipped frame ...")
// and the run goes on (eval::RunOptions); when no frame at all could be
// processed it throws (throw_no_frame).
std::vector<eval::FrameRecord> run_with_progress(Detector& detector,
                                                 const eval::FrameSource& source,
                                                 const std::string& label, CsvWriter* csv,
                                                 bool skip_bad_frames = false);
// A run in which every image was skipped is an error, not an empty success:
// throws lsgd::Error saying so, with the first image's error.
[[noreturn]] void throw_no_frame(std::int64_t images, const std::string& first_error);
// Frames of `records` that were skipped.
std::int64_t skipped_frames(const std::vector<eval::FrameRecord>& records);

nlohmann::json metrics_json(const eval::Metrics& m);
// Prints the headline numbers of an evaluation, one per line.
void print_metrics(const eval::Metrics& m, std::int64_t nodes, std::ostream& out);
void write_json(const nlohmann::json& json, const std::string& path);

}  // namespace lsgd::cli
