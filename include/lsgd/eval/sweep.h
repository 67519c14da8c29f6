// Parameter sweeps: a grid of detector configurations built from
// "KEY=VALUES" specs, and the datasets a sweep runs them on (`lsgd sweep`).
//
//   segmentation.superpixel_size=10:100:10   an inclusive range a:b:step
//   search.mode=exhaustive,nodes             a comma list
//   search.nodes.beta=0.9:1.1:0.1,1.5        list items may be ranges
//   verification.stages=none;temporal,geometric   ';' separates items when
//                                            any item holds a comma
//
// KEY is the dotted path of an option of the YAML config (io/config.h). Every
// value is checked by io::parse_config, so an unknown key or a bad value is an
// error naming the spec before anything runs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/eval/dataset.h"
#include "lsgd/eval/metrics.h"
#include "lsgd/eval/runner.h"

namespace lsgd::eval {

// One swept option.
struct SweepAxis {
  std::string spec;                 // the text it was parsed from, for messages
  std::string key;                  // dotted YAML path, e.g. "search.nodes.beta"
  std::vector<std::string> values;  // YAML scalar text of each value, in order
};

// Parses "KEY=VALUES". VALUES is a list of items separated by ',' (by ';'
// when it contains one); an item is a plain YAML scalar (letters, digits and
// . _ + - ,) or an inclusive range a:b:step of decimal numbers. Ranges are
// computed exactly in decimal (0.9:1.1:0.1 gives 0.9, 1.0, 1.1; 10:95:10 stops
// at 90) and written with the most decimals of a, b and step. Throws
// InvalidArgument naming the spec for a malformed key, an empty item, a
// character outside that set, a zero step, a step pointing away from b, or
// more than 10,000 values. The key itself is checked by expand_sweep().
SweepAxis parse_sweep_axis(const std::string& spec);

// One configuration of the grid.
struct SweepPoint {
  std::vector<std::string> values;  // one per axis, in axis order
  DetectorOptions options;          // base with those values applied, validated
};

// The cross product of the axes applied on top of `base`, in the order given:
// the first axis varies slowest (like nested loops). Every value is first
// parsed alone on `base` by io::parse_config, then every point as a whole (so
// options checked together are checked too). Throws InvalidArgument naming
// the spec for an unknown key, a value of the wrong type or out of range, a
// key swept twice or search.min_gap swept (each dataset has its window), and
// naming the point's values for an invalid combination;
// also when the grid exceeds 10,000 points (checked before a point is
// parsed: each is a whole run of every dataset). No axes: one point, `base`.
std::vector<SweepPoint> expand_sweep(const std::vector<SweepAxis>& axes,
                                     const DetectorOptions& base);

// YAML text that sets the dotted keys to the given scalar values, nested as
// the config expects ("search.nodes.beta" -> search: nodes: beta: ...).
// Keys sharing a prefix are merged into one section.
std::string sweep_yaml(const std::vector<std::string>& keys,
                       const std::vector<std::string>& values);

// A dataset to sweep on.
struct SweepDataset {
  std::string name;          // row label: letters, digits, . _ -
  std::string sequence;      // folder, list file or dataset layout (eval/dataset.h)
  std::string ground_truth;  // any format lsgd eval reads
  std::int64_t min_gap = 0;  // temporal window w, frames
  io::SequenceOptions sequence_options;  // layout, KITTI, FAB-MAP side, first/last/every
  GroundTruthOptions gt_options;         // format, FAB-MAP rows, subsample match
};

// Parses "NAME=SEQUENCE,GT,MIN_GAP", or "NAME=DIR,MIN_GAP" for a folder DIR
// holding sequence.txt and groundtruth.txt (the layout of the shared datasets
// and of `lsgd demo --output`), each optionally followed by ",KEY=VALUE"
// dataset options (set_dataset_option: layout=kitti, gt-format=mat, every=2,
// ...). Throws InvalidArgument naming the spec for a missing part, a bad
// name, a window that is not an integer >= 0 or a bad option. Files are not
// opened here.
SweepDataset parse_dataset_spec(const std::string& spec);

// ---- running a sweep (lsgd sweep, and any program that sweeps)

// A dataset opened for a sweep: its frames and ground truth are read before
// any run, so that a wrong path fails first (images are read by the runs,
// which skip bad ones as lsgd eval does).
struct SweepData {
  SweepDataset spec;
  FrameSource source;
  GroundTruth gt;
  std::int64_t positives = 0;       // queries with a loop outside the window
  io::Sequence all;  // every image of its layout and its list (inputs no output may overwrite)
};
// Opens spec's sequence and ground truth (eval::open_dataset: every layout
// and format lsgd eval reads); the errors name the file.
SweepData open_sweep_dataset(const SweepDataset& spec);

// One run of a sweep: a configuration of the grid on one dataset.
struct SweepCell {
  const SweepData* dataset = nullptr;
  const SweepPoint* point = nullptr;
  DetectorOptions options;        // the point's options with the dataset's window, checked
  std::string label;              // "[k/n] NAME KEY=VALUE ...": for progress and messages
  bool first_of_dataset = false;  // the first cell of its dataset (reports its skipped frames)
};
// Every point on every dataset, the datasets varying slowest; `keys` are the
// swept keys, for the labels. InvalidArgument naming the cell when a point
// is invalid with a dataset's window, or when two datasets share a name.
std::vector<SweepCell> sweep_cells(const std::vector<SweepData>& datasets,
                                   const std::vector<SweepPoint>& points,
                                   const std::vector<std::string>& keys);

// What one cell measured.
struct SweepRow {
  Metrics metrics;
  std::int64_t nodes = 0;
  std::size_t bytes_per_frame = 0;
  std::int64_t skipped = 0;  // frames skipped (unreadable or rejected images)
  bool done = false;         // false: the cell did not run (an earlier one failed)
};

// Runs one cell through the frame loop of every command (run_detector):
// a bad frame is skipped (`on_skip` told) unless `strict`, where it stops the
// run; `on_frame` is called for each processed frame. Throws lsgd::Error when
// every image was skipped.
SweepRow run_sweep_cell(const SweepCell& cell, bool strict, const FrameCallback& on_frame = {},
                        const SkipCallback& on_skip = {});

// Runs the cells on `jobs` threads (1: the calling thread), each with
// `run_cell` (run_sweep_cell when empty); `on_row(i, row)` is called for cell
// i as it finishes, one call at a time. After a failure no new cell starts;
// running ones finish and are reported. The first failure is rethrown as an
// lsgd::Error naming its cell. InvalidArgument for jobs < 1.
using SweepCellRunner = std::function<SweepRow(const SweepCell& cell)>;
void run_sweep(const std::vector<SweepCell>& cells, int jobs,
               const std::function<void(std::size_t index, const SweepRow& row)>& on_row,
               const SweepCellRunner& run_cell = {}, bool strict = false);

}  // namespace lsgd::eval
