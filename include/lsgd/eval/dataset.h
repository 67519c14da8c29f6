// A dataset as an evaluation reads it: the frames of a sequence in any
// layout (folder, list, KITTI, FAB-MAP, NEU; io/layouts.h), the frames kept
// by first/last/every, and the ground truth in any format (gt_formats.h)
// moved onto exactly those frames (gt_remap.h). `lsgd eval` and `lsgd sweep`
// read datasets only through here, so both accept the same layouts and
// formats.
#pragma once

#include <cstdint>
#include <string>

#include "lsgd/eval/groundtruth.h"
#include "lsgd/eval/gt_formats.h"
#include "lsgd/eval/gt_remap.h"
#include "lsgd/io/layouts.h"
#include "lsgd/io/sequence.h"

namespace lsgd::eval {

struct GroundTruthOptions {
  GtFormat format = kAutoGtFormat;  // detected from the file unless given
  GtRows rows = GtRows::kPair;        // FAB-MAP: a row per left/right pair or per image
  SubsampleMatch match = SubsampleMatch::kExact;  // with first/last/every
};

// The ground truth of the evaluated frames: the file's `rows` rows in the
// dataset's own numbering (-1: as many as the file says), moved through the
// layout's choice of images (FAB-MAP sides), then through first/last/every.
// A FAB-MAP ground truth with the wrong number of rows says which --gt-rows
// would fit.
GroundTruth evaluated_groundtruth(const std::string& path, const GroundTruthOptions& gt,
                                  const io::SequenceOptions& sequence, io::Layout layout,
                                  std::int64_t rows);

struct Dataset {
  io::Layout layout = io::kAutoLayout;  // the layout found (never "auto")
  io::Sequence all;     // every image of the layout, before first/last/every
  io::Sequence frames;  // the evaluated frames
  GroundTruth gt;       // of `frames`
};

// Opens the sequence and reads its ground truth (no image is decoded), so a
// wrong path or format fails before any run. Throws as io::open_layout and
// the ground-truth readers do.
Dataset open_dataset(const std::string& sequence, const io::SequenceOptions& options,
                     const std::string& ground_truth, const GroundTruthOptions& gt = {});

// Sets one dataset option from text, as `lsgd sweep --dataset ...,KEY=VALUE`
// spells them (the names of lsgd eval's flags without "--"): layout,
// kitti-sequence, camera, side, first, last, every, gt-format, gt-rows,
// subsample-match. InvalidArgument naming the key and value.
void set_dataset_option(io::SequenceOptions& sequence, GroundTruthOptions& gt,
                        const std::string& key, const std::string& value);

}  // namespace lsgd::eval
