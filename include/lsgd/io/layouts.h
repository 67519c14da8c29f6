// Dataset layouts on disk and frame subsampling: which image is frame i.
//
// A layout is registered by name (register_layout(); the built-in ones first):
//   folder   every image of a folder, natural order ("2.png" before "10.png")
//   list     a text file listing image paths (sequence.h)
//   kitti    KITTI odometry: sequences/NN/image_<camera>/000000.png ..., one
//            frame per line of sequences/NN/times.txt
//   fabmap   FAB-MAP City Centre / New College: one folder whose files
//            alternate left, right, left, ... (0001.jpg left, 0002.jpg right)
//   neu      the LSGDDN authors' NEU indoor set: a folder ordered as their
//            code orders it (byte-wise file names), so their loopinf frame
//            numbers apply
// and "auto" detects one (detect_layout()).
//
// Ground truth has to follow the same choices; docs/evaluation.md gives the
// mapping and lsgd/eval/gt_remap.h implements it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lsgd/io/sequence.h"

namespace lsgd::io {

// A layout is its registered name, or kAutoLayout.
using Layout = std::string;
inline constexpr const char* kAutoLayout = "auto";
inline constexpr const char* kFolderLayout = "folder";
inline constexpr const char* kListLayout = "list";
inline constexpr const char* kKittiLayout = "kitti";
inline constexpr const char* kFabmapLayout = "fabmap";
inline constexpr const char* kNeuLayout = "neu";

// `name` when it is "auto" or a registered layout; InvalidArgument naming the
// value and every layout otherwise.
Layout parse_layout(const std::string& name);
// "auto" and every registered layout, in registration order (the choices of
// --layout).
std::vector<std::string> layout_names();

// FAB-MAP: which camera's images become frames.
enum class Side {
  kLeft,   // files 1, 3, 5, ... (0-based positions 0, 2, 4, ...): frame k = pair k
  kRight,  // files 2, 4, 6, ... (positions 1, 3, 5, ...): frame k = pair k
  kBoth    // every file: frames 2k and 2k+1 are the left and right image of pair k
};

// "left", "right", "both"; InvalidArgument naming the value otherwise.
Side parse_side(const std::string& name);
std::string to_string(Side side);

// Frames kept out of a sequence: first, first + every, first + 2 every, ...
// up to last. Ids afterwards are positions among the kept frames (0, 1, 2...),
// so new frame a is old frame first + a * every.
struct FrameSelection {
  std::int64_t first = 0;  // first frame kept, 0-based, [0, 1e12]
  std::int64_t last = -1;  // last frame that may be kept, inclusive, >= first; -1: the end
  std::int64_t every = 1;  // step between kept frames, [1, 1e9]

  // InvalidArgument naming the field and value.
  void check() const;
  // True when every frame is kept (first 0, last -1, every 1).
  bool keeps_all() const { return first == 0 && last < 0 && every == 1; }
  // The frames kept out of `frames`, ascending. InvalidArgument when first or
  // last is not a frame of the sequence (the message gives both numbers).
  std::vector<std::int64_t> kept(std::int64_t frames) const;
};

struct SequenceOptions {
  Layout layout = kAutoLayout;  // "auto": detect_layout()
  // KITTI: "NN" (digits; "5" means "05") when PATH is the dataset root holding
  // sequences/; empty when PATH is sequences/NN itself or its image_X folder.
  std::string kitti_sequence;
  // KITTI: camera folder image_<camera>: 0 gray left, 1 gray right, 2 colour
  // left, 3 colour right; [0, 3], or -1: 0, or X when PATH is an image_X folder.
  int camera = -1;
  Side side = Side::kLeft;   // FAB-MAP only
  FrameSelection selection;  // applied after the layout picked its frames

  // InvalidArgument naming the field and value.
  void check() const;
};

// The layout PATH has when `options.layout` is "auto" (otherwise that
// layout): kitti when options.kitti_sequence is set; else the first
// registered layout whose `detect` says so (kitti: a folder holding times.txt
// and an image_0..image_3 folder, or an image_X folder whose parent holds
// times.txt); else list for a file, and for a dataset folder: one holding
// `sequence.txt` (kDatasetList), read as that list (layout list given a
// folder does the same); folder for another folder (its images). IoError
// when PATH does not exist.
Layout detect_layout(const std::string& path, const SequenceOptions& options = {});

// The list file of a dataset folder, as lsgd's datasets and `lsgd demo
// --output` lay them out (beside groundtruth.txt).
inline constexpr const char* kDatasetList = "sequence.txt";

// The frames of PATH in its layout, before options.selection. Errors name the
// files involved: IoError for a missing path or folder; FormatError for a
// KITTI sequence without the camera's folder or times.txt, a frame count that
// differs from times.txt's lines, a missing frame number (000041.png after
// 000039.png), and for a FAB-MAP folder with an odd number of images (left
// and right would no longer alternate); InvalidArgument for options that do
// not apply to the layout (a KITTI sequence number with --layout folder).
Sequence open_layout(const std::string& path, const SequenceOptions& options);

// A dataset layout (docs/design.md, "Add a dataset layout"): how PATH lists
// its frames.
struct LayoutType {
  const char* name;     // what --layout and SequenceOptions::layout say
  const char* summary;  // one line, for help texts
  // The frames of PATH in this layout, before options.selection; errors name
  // the files involved.
  Sequence (*open)(const std::string& path, const SequenceOptions& options);
  // Whether "auto" opens PATH (it exists) in this layout; nullptr: only by
  // name. Asked in registration order, before the list and folder catch-alls.
  bool (*detect)(const std::string& path, const SequenceOptions& options) = nullptr;
};

// Every registered layout, in registration order: the built-in ones first.
std::vector<LayoutType> layout_types();
// Registers another layout, usable by name from then on (SequenceOptions,
// --layout, the `layout` key of a sweep's dataset); call it before opening
// sequences with it. InvalidArgument for a missing name, summary or open
// function, the name "auto" or one already registered. Thread-safe.
void register_layout(const LayoutType& layout);

// The frames `selection` keeps (see FrameSelection::kept for the errors).
Sequence subsample(const Sequence& sequence, const FrameSelection& selection);

// open_layout() then subsample() with options.selection.
Sequence open_sequence(const std::string& path, const SequenceOptions& options);

}  // namespace lsgd::io
