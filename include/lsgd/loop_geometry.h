// The geometry of a loop: what a verification stage fitted between a query
// and a candidate (StageCheck::geometry, Result::geometry).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace lsgd {

// The geometry a stage fitted between the query and a candidate (the
// geometric stage: its ORB matches and the better of F and H), for a SLAM
// system to recover the relative pose without matching again (examples/relative_pose.cc).
// Points are in pixels of each frame's original image.
struct LoopGeometry {
  std::string model;               // "fundamental" or "homography"
  // Row-major 3x3. Fundamental: c^T F q = 0 for a match (q in the query,
  // c in the candidate, homogeneous); homography: c ~ H q.
  std::array<double, 9> matrix{};
  std::vector<float> query_points;      // x, y per match
  std::vector<float> candidate_points;  // x, y per match, in the same order
  std::vector<std::uint8_t> inliers;    // per match: 1 when it is an inlier of the model
  std::size_t matches() const { return inliers.size(); }
};

}  // namespace lsgd
