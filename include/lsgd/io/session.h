// Which session a run of images appends to, and from which image: the policy
// `lsgd run --database` follows, in the library so that Python and an
// application resume a database exactly as the tool does (README, "Frame ids").
//
// Frame ids: image i of the sequence is frame first_id + i, whether or not
// earlier images were skipped; first_id is 0 for a database's first session
// and one past the last stored frame for a new session. A run re-started with
// the same images continues the session it interrupted.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/io/database.h"

namespace lsgd::io {

// The name a database keeps for an image: its absolute, normal path, so that
// a re-run from another folder recognises it.
std::string stored_image_name(const std::string& image);

// True when `image` is the image a row named `stored` holds (rows of older
// lsgd hold the path as it was given).
bool same_image(const std::string& image, const std::string& stored);

// Fraction of the histogram mass in which two descriptors of one grid differ
// (0: identical; 1: nothing in common, or another grid or storage).
double descriptor_difference(const DescriptorView& a, const DescriptorView& b);

struct SessionPlan {
  std::int64_t session = 0;
  std::int64_t first_id = 0;      // id of image 0
  std::int64_t first = 0;         // first image to process
  bool resume = false;            // continues a session already holding frames
  std::int64_t last_stored = -1;  // id of the session's last stored frame (resume)
};

// The plan for running `images` (paths) into `db`, whose frames `detector`
// holds (restored from it). The last session continues when its frames are
// the images at their ids (first_id + index) and its last frame, described
// again, has the stored content; images stored elsewhere in it (another
// --first or --every, an edited list) are refused rather than stored twice.
// Else a new session: `chosen` when given, else the last + 1 (0 for an empty
// database). InvalidArgument naming the database, the image and the frame
// when the images cannot be stored as asked; and, before anything else, when
// `detector` does not hold the database's frames (its size differs: a fresh
// detector, or one that processed a frame not appended), its options are not
// ones the database takes (Database::check_compatible), or `chosen` is
// outside [0, kMaxSession]: what the run would be refused for at its first
// frame, or would store under the wrong ids.
SessionPlan plan_session(const Database& db, const Detector& detector,
                         const std::vector<std::string>& images,
                         const std::optional<std::int64_t>& chosen = std::nullopt);

// Prepares `detector` (holding the database's frames) for the run `plan`
// describes: a new session is another sequence, so no frame of it continues
// a loop of the stored frames (Detector::cut()); a resumed session goes on as
// if it had never stopped (nothing changes). Call it after plan_session(),
// before the first frame.
void begin_session(Detector& detector, const SessionPlan& plan);

}  // namespace lsgd::io
