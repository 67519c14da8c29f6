// Ground truth moved onto the frames a run actually processes: frame
// subsampling (--first/--last/--every) and the FAB-MAP side choice
// (io/layouts.h). docs/evaluation.md explains each mapping.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lsgd/eval/groundtruth.h"
#include "lsgd/io/layouts.h"

namespace lsgd::eval {

// New frame f shows what ground-truth row rows[f] shows: new frames a != b are
// a loop iff GT(rows[a], rows[b]) = 1 or rows[a] == rows[b] (the same place,
// e.g. the left and right image of one FAB-MAP pair). InvalidArgument for a
// row outside [0, gt.frames()).
GroundTruth select_rows(const GroundTruth& gt, const std::vector<std::int64_t>& rows);

// How a subsampled frame inherits loops.
enum class SubsampleMatch {
  // New frames a, b match iff old frames first + a*every and first + b*every
  // match: exactly the images processed (default).
  kExact,
  // ... iff any old frame of [first + a*every, +every) matches any of
  // [first + b*every, +every) (blocks clipped at last): for ground truth with
  // one loop index per frame (loopinf) or loops narrower than `every`, which
  // kExact thins out. Lenient by up to every - 1 frames.
  kBlock
};

// "exact", "block"; InvalidArgument naming the value otherwise.
SubsampleMatch parse_subsample_match(const std::string& name);
std::string to_string(SubsampleMatch match);

// The ground truth of the frames io::FrameSelection{first, last, every} keeps
// (last -1: the end), renumbered 0, 1, 2, ... InvalidArgument for an invalid
// selection or one beyond gt.frames(), naming the numbers.
GroundTruth subsample(const GroundTruth& gt, std::int64_t every, std::int64_t first = 0,
                      std::int64_t last = -1, SubsampleMatch match = SubsampleMatch::kExact);

// FAB-MAP ground truth comes with one row per left/right pair (City Centre's
// published 1237 x 1237 matrices, the LSGDDN loopinf files) or one row per
// image (New College's 2146 x 2146 matrix: row r = the r-th file, left and
// right alternating).
enum class GtRows { kPair, kImage };

// "pair", "image"; InvalidArgument naming the value otherwise.
GtRows parse_gt_rows(const std::string& name);
std::string to_string(GtRows rows);

// Rows a FAB-MAP ground truth has for a folder of `pairs` left/right pairs.
std::int64_t fabmap_gt_frames(std::int64_t pairs, GtRows rows);

// The ground truth of the frames io::open_layout() gives for a FAB-MAP folder
// of `pairs` pairs with `side` (before any subsampling):
//                    side left       side right      side both
//   per-pair rows    frame k = row k frame k = row k frame f = row f/2
//   per-image rows   frame k = 2k    frame k = 2k+1  frame f = row f
// The row kind follows from gt.frames() (pairs or 2 * pairs); any other count
// is a FormatError naming both counts.
GroundTruth fabmap_groundtruth(const GroundTruth& gt, std::int64_t pairs, io::Side side);

}  // namespace lsgd::eval
