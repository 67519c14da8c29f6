// A deterministic synthetic image sequence with exact loop ground truth, for
// the `lsgd demo` command and for tests (no image data ships with lsgd).
//
// The world is a long straight street seen by a forward-facing pinhole camera:
// buildings on both sides (facades with per-building height, shade, colour,
// windows, shop fronts, signs and surface detail), a road with markings,
// crosswalks and patches, tiled sidewalks and a sky. Everything is a
// procedural function of the world coordinates, so a place looks the same
// whenever it is seen again. The camera's place is its coordinate s (world
// units, about metres) along the street; the route (see route()) is a list of
// stretches that either show new parts of the street or drive again, in the
// same direction, over parts already seen. Revisits differ from the first
// traverse by speed (frames fall at other places), lateral offset and yaw of
// the camera, and on some stretches by lighting and by moving pedestrians and
// vehicles. A jump of s between stretches stands for an unrecorded drive.
//
// The default route (frame ranges at route_scale 1):
//     0- 179  A    new street
//   180- 299  B    new street
//   300- 432  A'   revisit of A, dim lighting
//   433- 527  C    new street, moving objects
//   528- 618  B'   revisit of B, moving objects
//   619- 698  D    new street
//   699- 793  A''  revisit of A, bright lighting, moving objects
//   794- 853  E    new street
//   854- 933  F    new street, dim lighting (that of A')
//   934-1004  G    new street, bright lighting (that of A''), moving objects
//  1005-1089  H    new street, dense moving objects (more, larger, nearer)
// F, G and H were appended later (frames 0-853 and their ground truth are
// those of the earlier 854-frame route): they are new places under the
// conditions of the revisits, where an accepted loop can only be a false
// positive. Every facade of the street draws its look from the same
// distributions (style, shade, tint, windows, shops, signs), so a new place
// has the colour and texture statistics of the places seen before: only its
// layout differs, the hard case for histogram-like descriptors.
//
// Ground truth: frames i != j are a loop iff |place(i) - place(j)| <=
// loop_radius. All traverses have the same heading, so no opposite-direction
// pair exists. Temporal neighbours on one traverse are also within the
// radius; an evaluation removes them with its temporal window (min gap).
//
// All randomness comes from an integer hash of the seed and all geometry from
// plain arithmetic (no <random> distributions, no libm transcendentals), so a
// seed gives the same frames on every run and platform.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lsgd/eval/groundtruth.h"

namespace cv {
class Mat;
}

namespace lsgd::eval {

struct SyntheticOptions {
  int width = 320;         // image width, pixels, in [32, 4096]
  int height = 240;        // image height, pixels, in [32, 4096]
  std::uint64_t seed = 1;  // world and route randomness, any value
  // Multiplies every stretch's length, so the frame count (1090 at 1), in [0.1, 10]; the first
  // revisit starts at frame ~300 * route_scale.
  double route_scale = 1.0;
  double loop_radius = 2.5;  // loop iff places differ by <= this, world units, (0, 30]
  // Two revisits (A', A'') and two new stretches (F, G) under other lighting;
  // false: all frames in the same daylight.
  bool lighting_change = true;
  // Pedestrians and vehicles on five stretches (C, B', A'', G; dense on H);
  // false: none anywhere.
  bool moving_objects = true;
  double sensor_noise = 2.0;    // per-pixel noise amplitude, gray levels, [0, 64]
  double field_of_view = 90.0;  // horizontal field of view, degrees, [30, 150]

  // Throws InvalidArgument naming the first invalid field, its value and range.
  void check() const;
};

// One stretch of the route, for printing and for tests. Its frames
// first_frame .. last_frame (inclusive) are evenly spaced from place s_begin
// to place s_end (s_end > s_begin: the camera always moves towards larger s).
struct RouteSegment {
  std::int64_t first_frame = 0;
  std::int64_t last_frame = 0;
  double s_begin = 0;
  double s_end = 0;
  bool revisit = false;         // drives over places an earlier stretch showed
  double light_gain = 1;        // nominal global gain (frames flicker by +-2 %)
  double light_offset = 0;      // global offset, gray levels
  bool moving_objects = false;  // pedestrians and vehicles appear
  std::string label;            // e.g. "A': revisit of A, dim lighting"
  double step = 1;              // world units between consecutive frames
  double light_gradient_x = 0;  // gray levels added at the right edge minus the left edge
  double light_gradient_y = 0;  // gray levels added at the bottom edge minus the top edge
  // More, larger and nearer pedestrians and vehicles than on other stretches
  // (only with moving_objects).
  bool dense_objects = false;
};

class SyntheticWorld;

// Writes every frame of `world` as DIR/images/NNNNNN.png (6 digits), the list
// DIR/sequence.txt and the ground truth DIR/groundtruth.txt (pairs text), so
// that `lsgd eval --sequence DIR/sequence.txt --gt DIR/groundtruth.txt` runs on
// it. Creates DIR; throws IoError naming the file that cannot be written.
void write_synthetic_dataset(const SyntheticWorld& world, const std::string& dir);

class SyntheticWorld {
 public:
  // Validates the options (throws InvalidArgument) and lays out world and route.
  explicit SyntheticWorld(const SyntheticOptions& options = {});

  std::int64_t frames() const { return static_cast<std::int64_t>(places_.size()); }
  // Frame i as CV_8UC3 BGR (OpenCV channel order), width x height. Throws
  // InvalidArgument for i outside [0, frames()). Thread-safe (const, no state).
  cv::Mat render(std::int64_t frame) const;
  const GroundTruth& ground_truth() const { return ground_truth_; }
  const std::vector<RouteSegment>& route() const { return route_; }
  // s coordinate (world units) of the camera in frame i; throws
  // InvalidArgument for i outside [0, frames()).
  double place(std::int64_t frame) const;
  // Index into route() of the stretch holding frame i; throws like place().
  int segment_of(std::int64_t frame) const;
  const SyntheticOptions& options() const { return options_; }

  // One facade of the street (public only so the .cc can use it freely).
  struct Building {
    double s0 = 0, s1 = 0;  // extent along the street, world units
    double top = 0;         // roof height, world units
    std::uint64_t key = 0;  // hash of seed, side and index: drives its look
  };

 private:
  void build_route();
  void build_world();
  void build_ground_truth();
  void check_frame(std::int64_t frame) const;

  SyntheticOptions options_;
  std::vector<RouteSegment> route_;
  std::vector<double> places_;          // per frame
  std::vector<int> segment_index_;      // per frame
  std::vector<Building> buildings_[2];  // left (x < 0) and right facades, by s
  GroundTruth ground_truth_;
};

}  // namespace lsgd::eval
