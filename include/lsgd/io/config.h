// YAML configuration of the detector. Every key is optional (defaults are the
// DetectorOptions defaults); unknown keys, wrong types and out-of-range values
// are errors naming the file and key.
//
//   segmentation:
//     superpixel_size: 40      # S_p, pixels
//     iterations: 3
//     intensity_scale: 20.0
//     distance_scale: 1.0
//   similarity:
//     metric: reference        # reference | l1 | normalized_l1
//   search:
//     mode: exhaustive         # exhaustive | nodes
//     min_gap: 50              # frames
//     top_n: 10
//     nodes: {threshold_0: 0.9, alpha: 0.8, beta: 1.0}
//   descriptor:
//     storage: exact           # exact | compact
//   verification:
//     stages: temporal,geometric  # none | temporal | geometric | temporal,geometric
//     max_candidates: 3
//     temporal: {frames: 16, long_frames: 48, tolerance: 2, agree: 0}
//     geometric: {max_features: 500, min_side: 240, max_side: 240, ratio: 0.8,
//                 ransac_threshold: 3.0, min_inliers: 20, min_inlier_ratio: 0.25}
//   decision:                  # standard deviations (decision.h)
//     threshold: 7.0
//     geometric_bonus: 3.5
//     continuity_bonus: 2.5
//     continuity_inliers: 0.2
#pragma once

#include <string>

#include "lsgd/detector.h"

namespace lsgd::io {

// Parses YAML text on top of `base` (keys not given keep base's values).
// `source` names the text in error messages (usually the file path). Throws
// FormatError for malformed YAML, unknown keys and wrong types, and
// InvalidArgument (via DetectorOptions::check) for out-of-range values, both
// naming source and key.
DetectorOptions parse_config(const std::string& yaml_text, const std::string& source,
                             const DetectorOptions& base = {});

// Reads and parses a config file. Throws IoError when it cannot be read.
DetectorOptions load_config(const std::string& path, const DetectorOptions& base = {});

// Writes every option as YAML that parse_config reads back to equal options.
std::string to_yaml(const DetectorOptions& options);

}  // namespace lsgd::io
