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

#include <cstdint>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/eval/dataset.h"

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
// key swept twice, and naming the point's values for an invalid combination;
// also when the grid exceeds 1,000,000 points. No axes: one point, `base`.
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

}  // namespace lsgd::eval
