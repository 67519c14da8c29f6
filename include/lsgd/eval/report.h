// A self-contained HTML report of one evaluation run (`lsgd eval --report`):
// one file with inline CSS, inline SVG charts and the similarity matrix as a
// PNG data: URI; no JavaScript and no external resource, so it opens offline
// and can be mailed or archived as is.
//
// Sections: a header (sequence, ground truth, protocol, window, mode,
// verification, image size and grid, the command line and version, counts
// and the headline metrics), the precision-recall curve (with other systems'
// when compared), the trajectory with the loops found (when poses are given)
// or else the score of every frame over time, example loops as thumbnails
// (declared true, declared false, missed revisits), the similarity matrix
// with the ground-truth loops outlined and the reported loops marked,
// per-stage timings and resources, and the exact configuration.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "lsgd/eval/groundtruth.h"
#include "lsgd/eval/metrics.h"

namespace cv {
class Mat;
}

namespace lsgd::eval {

// Another system's results on the same frames, scored by the same evaluator,
// drawn beside ours on the precision-recall plot (lsgd eval --compare).
struct ComparedSystem {
  std::string name;  // as the legend shows it
  Metrics metrics;
};

struct ReportInput {
  std::string title;                // page title; empty: "lsgd evaluation: <sequence>"
  std::string sequence;             // sequence path or name, shown as given
  std::string ground_truth;         // ground-truth file, shown as given
  std::string protocol = "strict";  // evaluation protocol the metrics were computed with
  std::string mode;                 // search mode, e.g. "exhaustive" or "nodes"
  std::string verification;         // verification stages, e.g. "temporal"
  std::string config_yaml;          // the exact configuration (io::to_yaml); empty: omitted
  std::string command;              // the command line that made the run; empty: omitted
  std::string version;              // e.g. "lsgd 0.1.0 (commit 05e5e35a1b2c)"; empty: omitted
  int width = 0, height = 0;        // frame size; 0: unknown (detections), not shown
  int grid_rows = 0, grid_cols = 0; // the descriptor grid; 0: not shown

  // Required (not owned; must outlive the call). The temporal window is metrics->min_gap.
  const Metrics* metrics = nullptr;
  const std::vector<FrameRecord>* records = nullptr;
  const GroundTruth* gt = nullptr;

  // Similarity of two frames in [0, frames), e.g. Detector::similarity; empty
  // (detections from another system): the report has no similarity matrix.
  std::function<double(std::int64_t, std::int64_t)> similarity;
  // The similarity matrix samples at most this many frames uniformly, in [2, 4000]
  // (n^2 / 2 similarity calls: 600 frames take ~1.5 s at ~8 us per call).
  int max_matrix_frames = 600;

  std::int64_t nodes = 0;           // dynamic nodes at the end of the run (0: exhaustive)
  std::size_t bytes_per_frame = 0;  // descriptor storage per frame (0: unknown, not shown)
  // Camera position (x, z) per frame, any unit (e.g. KITTI metres); empty: no
  // trajectory; otherwise exactly gt->frames() entries.
  std::vector<std::array<double, 2>> trajectory;

  // The loops marked on the matrix and the trajectory. `declared`: the loops
  // the system declared (FrameRecord::loop, the operating point of the
  // metrics). Else the reported loops with score >= threshold; an empty
  // threshold is the R@100P threshold (metrics->threshold_at_100_precision),
  // where every marked loop is a true positive by construction; no loop is
  // marked when R@100P is 0.
  bool declared = false;
  std::optional<double> threshold;
  std::string threshold_name = "decision threshold";  // what `threshold` is, when given
  // Warnings about the setup (eval::setup_warnings), shown at the top.
  std::vector<std::string> warnings;

  // The image of frame f (8-bit gray or BGR; throws lsgd::Error for one that
  // cannot be read), for thumbnails of example loops: declared true and false
  // ones and missed revisits, query and match side by side. Empty: no
  // thumbnails. At most `max_examples` of each kind, [0, 50].
  std::function<cv::Mat(std::int64_t)> image;
  int max_examples = 4;

  // Other systems on the same frames, on the same PR plot.
  std::vector<ComparedSystem> compared;

  // Throws InvalidArgument naming the first missing or inconsistent field.
  void check() const;
};

// Why a trajectory's positions cannot be drawn to scale: "positions span x
// from LO to HI, more than a double holds" when an axis's span overflows
// (finite positions of +-1e308), "" otherwise. ReportInput::check() refuses
// such a trajectory; lsgd eval --poses checks it before the run.
std::string trajectory_span_beyond_doubles(const std::vector<std::array<double, 2>>& positions);

// The HTML text of the report. Validates the input (InvalidArgument) and
// calls input.similarity for the sampled pairs.
std::string render_report(const ReportInput& input);

// Renders and writes the report to `path` atomically (a temporary file beside
// it, then rename): a failed write never leaves a truncated report. Throws
// IoError naming the path when it cannot be written.
void write_report(const ReportInput& input, const std::string& path);

}  // namespace lsgd::eval
