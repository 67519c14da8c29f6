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
#include "lsgd/eval/results_csv.h"
#include "lsgd/io/files.h"
#include "lsgd/io/layouts.h"

#include <CLI/CLI.hpp>
#include <utility>

namespace lsgd::cli {

// Skipped frames listed one per line before the rest are only counted (a
// list of half a million missing files printed 43 MB over 30 s).
inline constexpr std::int64_t kListedSkips = 100;

// Flags every detector-running subcommand accepts on top of --config.
struct DetectorFlags {
  std::string config;                  // YAML file; empty: defaults
  std::string mode;                    // exhaustive | nodes; empty: from config
  std::optional<std::int64_t> min_gap;  // overrides search.min_gap
  std::optional<double> threshold;      // overrides decision.threshold
  std::string verify;                   // none | temporal | geometric | temporal,geometric
  std::vector<std::string> options;     // --option KEY=VALUE, any key of `lsgd options`

  void add_to(CLI::App& command);
  // Defaults, then the config file, then the flags; validated.
  DetectorOptions resolve() const;
  // The option keys the flags set, each with the flag that sets it
  // ("search.mode", "--mode"; "decision.threshold", "--option decision.threshold").
  std::vector<std::pair<std::string, std::string>> keys() const;
  // Sets the options the flags name on `options` (--option first, then the
  // shortcuts --mode, --min-gap, --threshold, --verify) and validates. A
  // shortcut and an --option of the same key is an error (one would be lost).
  void apply(DetectorOptions& options) const;
};

// Flags choosing which images are the frames, shared by run and eval:
// --layout, --kitti-sequence, --camera, --side, --first, --last, --every.
struct SequenceFlags {
  std::string layout = "auto";  // auto or a registered layout (io::layout_names())
  std::string kitti_sequence;   // KITTI: PATH is the dataset root, this is NN
  int camera = -1;              // KITTI image_<camera>; -1: 0 or PATH's image_X
  std::string side;             // FAB-MAP: left | right | both; empty: left
  std::int64_t first = 0;
  std::int64_t last = -1;
  std::int64_t every = 1;
  bool strict = false;  // stop at the first unreadable or rejected image

  // The flags on `command`; --strict only when the command can skip an image.
  void add_to(CLI::App& command, bool skips = true);
  // The flags given on the command line (--layout, --first, ...): empty when none.
  static std::vector<std::string> given(const CLI::App& command);
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
  // The bar's text after `done` frames in `elapsed_s` seconds: the bar,
  // frames done of total, frames per second, ms per frame (process() alone),
  // elapsed time and the time left at the rate so far.
  std::string line(std::int64_t done, double ms_per_frame, double elapsed_s) const;

 private:
  std::int64_t total_;
  std::string label_;
  bool enabled_;
  std::int64_t start_ns_;
  std::int64_t last_draw_ns_ = 0;
};

// "1:05" (minutes:seconds) or "1:02:03"; "--:--" for a negative or unknown time.
std::string format_duration(double seconds);

// The `lsgd run` CSV (the library's, lsgd/eval/results_csv.h).
using eval::CsvWriter;

// A CLI11 check for file arguments: an empty name ('') is an error, not
// "no file".
extern const CLI::Validator kNonEmptyPath;
// A CLI11 check for input files (--config, --gt, ...): the system's reason,
// naming the file (a link loop, a permission, a name too long), where
// CLI::ExistingFile said "File does not exist" for all but a folder.
extern const CLI::Validator kExistingFile;
// A CLI11 check for --frames N: a frame count in [1, kMaxFrames], said in
// those words (CLI::PositiveNumber printed its bound as 309 digits).
extern const CLI::Validator kFrameCount;
// CLI::IsMember's check and help ("TEXT:{a,b}") with the value shown cut
// (internal::shown_value): IsMember echoed a 300-byte value whole.
CLI::Validator one_of(const std::vector<std::string>& names);

// The registered search modes' names (lsgd::search_modes()), for --mode.
std::vector<std::string> search_mode_list();

// What run_frames did.
struct FrameRun {
  std::vector<eval::FrameRecord> records;  // empty unless the options keep records
  std::int64_t processed = 0;
  std::int64_t skipped = 0;
  double total_ms = 0;  // Detector::process wall time of the processed frames
  std::string first_error;  // why the first skipped frame was skipped
  double mean_ms() const { return processed > 0 ? total_ms / static_cast<double>(processed) : 0; }
};

// The frame loop of every command (eval::run_detector: one numbering, one way
// to skip), with a progress bar labelled `label` (when `progress`), each
// skipped frame reported on stderr ("lsgd: skipped frame I (PATH): reason")
// (unless !report_skips)
// and `on_frame` called for each processed frame (a CSV row, a database
// append). Throws (throw_no_frame) when the detector ends the run holding no
// frame at all.
FrameRun run_frames(Detector& detector, const eval::FrameSource& source, const std::string& label,
                    const eval::RunOptions& options, const eval::FrameCallback& on_frame = {},
                    bool progress = true, bool report_skips = true);
// A run in which every image was skipped is an error, not an empty success:
// throws lsgd::Error saying so, with the first image's error.
[[noreturn]] void throw_no_frame(std::int64_t images, const std::string& first_error);
// IoError "cannot write output file 'PATH': <the system's reason>" for an
// output that failed to open (errno as the open left it), saying so when a
// relative path's working folder was deleted.
using io::throw_cannot_write;  // lsgd/io/files.h

nlohmann::json metrics_json(const eval::Metrics& m);

// The command line as typed (each argument shell-quoted when it needs it),
// recorded once by main().
void set_command_line(int argc, char** argv);
const std::string& command_line();
// "lsgd 0.1.0 (commit 05e5e35a1b2c)".
std::string version_text();
// Adds what produced a JSON output: "lsgd_version", "lsgd_commit" and the
// "command" line, so that every result says how to make it again.
void stamp(nlohmann::json& j);
// Prints the headline numbers of an evaluation, one per line.
void print_metrics(const eval::Metrics& m, std::int64_t nodes, std::ostream& out);
void write_json(const nlohmann::json& json, const std::string& path);

}  // namespace lsgd::cli
