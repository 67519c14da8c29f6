#include "lsgd/eval/dataset.h"

#include <charconv>
#include <limits>

#include "internal/check.h"
#include "internal/numbers.h"
#include "lsgd/error.h"

namespace lsgd::eval {

using internal::concat;

GroundTruth evaluated_groundtruth(const std::string& path, const GroundTruthOptions& gt,
                                  const io::SequenceOptions& sequence, io::Layout layout,
                                  std::int64_t rows) {
  GtOptions read;
  read.format = gt.format;
  read.frames = rows;
  GroundTruth truth;
  try {
    truth = load_groundtruth(path, read);
  } catch (const FormatError& e) {
    if (layout != io::kFabmapLayout || rows < 0) throw;
    throw FormatError(concat(e.what(), " (FAB-MAP with --gt-rows ", to_string(gt.rows),
                             " expects ", rows, " rows; is the ground truth given per ",
                             gt.rows == GtRows::kPair ? "image? --gt-rows image)"
                                                      : "pair? --gt-rows pair)"));
  }
  if (layout == io::kFabmapLayout) {
    const std::int64_t pairs = gt.rows == GtRows::kPair ? truth.frames() : truth.frames() / 2;
    truth = fabmap_groundtruth(truth, pairs, sequence.side);
  }
  const io::FrameSelection& s = sequence.selection;
  if (!s.keeps_all()) truth = subsample(truth, s.every, s.first, s.last, gt.match);
  return truth;
}

Dataset open_dataset(const std::string& sequence, const io::SequenceOptions& options,
                     const std::string& ground_truth, const GroundTruthOptions& gt) {
  Dataset d;
  d.layout = io::detect_layout(sequence, options);
  d.all = io::open_layout(sequence, options);
  d.frames = io::subsample(d.all, options.selection);
  const auto images = static_cast<std::int64_t>(d.all.images.size());
  std::int64_t rows = images;
  if (d.layout == io::kFabmapLayout) {
    rows = fabmap_gt_frames(options.side == io::Side::kBoth ? images / 2 : images, gt.rows);
  }
  d.gt = evaluated_groundtruth(ground_truth, gt, options, d.layout, rows);
  return d;
}

namespace {

template <typename T>
T parse_integer(const std::string& key, const std::string& value) {
  T v{};
  if (!internal::parses_as(value, v)) {
    internal::throw_invalid("dataset option ", internal::shown_value(key), "=", internal::shown_value(value), ": not an integer");
  }
  return v;
}

}  // namespace

void set_dataset_option(io::SequenceOptions& sequence, GroundTruthOptions& gt,
                        const std::string& key, const std::string& value) {
  try {
    if (key == "layout") {
      sequence.layout = io::parse_layout(value);
    } else if (key == "kitti-sequence") {
      sequence.kitti_sequence = value;
    } else if (key == "camera") {
      sequence.camera = parse_integer<int>(key, value);
    } else if (key == "side") {
      sequence.side = io::parse_side(value);
    } else if (key == "first") {
      sequence.selection.first = parse_integer<std::int64_t>(key, value);
    } else if (key == "last") {
      sequence.selection.last = parse_integer<std::int64_t>(key, value);
    } else if (key == "every") {
      sequence.selection.every = parse_integer<std::int64_t>(key, value);
    } else if (key == "gt-format") {
      gt.format = parse_gt_format(value);
    } else if (key == "gt-rows") {
      gt.rows = parse_gt_rows(value);
    } else if (key == "subsample-match") {
      gt.match = parse_subsample_match(value);
    } else {
      internal::throw_invalid("unknown dataset option '", internal::shown_value(key),
                              "' (known: layout, kitti-sequence, camera, side, first, last, every, "
                              "gt-format, gt-rows, subsample-match)");
    }
  } catch (const InvalidArgument& e) {
    const std::string message = e.what();
    if (message.find(key) != std::string::npos) throw;
    internal::throw_invalid("dataset option ", internal::shown_value(key), "=", internal::shown_value(value), ": ", message);
  }
}

}  // namespace lsgd::eval
