// Geometric verification of a loop candidate (beyond the paper): ORB features
// matched between the query and the candidate frame (mutual nearest
// neighbours in Hamming distance that pass Lowe's ratio test), a fundamental
// matrix and a homography fitted with RANSAC (OpenCV's USAC), accepted on the
// inlier count of the better model. Features of every frame are computed once,
// when the frame is added, and kept (contiguously, about 40 bytes a keypoint),
// so a query never recomputes a stored frame's features.
//
// Degenerate geometry is a verdict, not an error: identical frames, pure
// rotations and planar scenes are explained by the homography (H wins ties),
// fewer than 8 matches are rejected as "too few matches (N < 8)", a model
// whose inliers lie on one line is discarded, and an OpenCV failure becomes a
// rejection with OpenCV's message in the reason.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lsgd/image.h"
#include "lsgd/options.h"
#include "lsgd/loop_geometry.h"

namespace lsgd {

// Bytes of one ORB descriptor (256 binary tests): what the verifier keeps,
// and the database stores, per keypoint.
constexpr int kOrbBytes = 32;

struct GeometricOptions {
  // ORB keypoints kept per frame, [16, 20000].
  int max_features = 500;
  // The working size: ORB runs on the image scaled so that its shorter side
  // is within [min_side, max_side]. Small frames (160x120) are upscaled
  // (bilinear) so they still yield keypoints; large ones are downscaled (area
  // average), so ORB costs about the same (1.5-5 ms) on every camera and inlier counts
  // mean the same on every camera. Pixels, [0, 4096]; min_side 0: never
  // upscale; max_side 0: never downscale; else min_side <= max_side.
  int min_side = 240;
  int max_side = 240;
  // Lowe's ratio test: a match is kept when best distance < ratio * second best; (0, 1].
  double ratio = 0.8;
  // RANSAC reprojection threshold in pixels of the working-size image; (0, 100].
  double ransac_threshold = 3.0;
  // A candidate is accepted when the better model (F or H) has at least this
  // many inliers; [8, 10000].
  int min_inliers = 20;
  // ... and when those inliers are at least this fraction of the matches, [0, 1]:
  // RANSAC's F fits ~10 % of many random matches (20 of 200) while every true
  // loop accepted on corridor has >= 69 %, so a large random match set cannot
  // pass (docs/results.md: no measured number changes).
  double min_inlier_ratio = 0.25;
  // Working-size pixels per original pixel for an image of this size.
  double working_scale(int width, int height) const;
  void check() const;
  static const OptionTable<GeometricOptions>& fields();  // lsgd/options.h
};

// What the geometric check found for one (query, candidate) pair.
struct GeometricCheck {
  bool accepted = false;
  int matches = 0;     // mutual matches that passed the ratio test
  int inliers = 0;     // inliers of the better model
  std::string model;   // "fundamental", "homography" or "" when none was fitted
  std::string reason;  // why it was accepted or rejected, for the Result
  // The matches and the better model (null when none was fitted): c^T F q = 0
  // or c ~ H q, q in `query`, c in `candidate`, original pixels.
  std::shared_ptr<const LoopGeometry> geometry;
  double ms = 0;       // time spent in verify()
};

// Thread safety: verify() and the other const members only read the stored
// features and may run concurrently with each other; add() may not run
// concurrently with anything (it appends to the stores and runs the ORB
// detector, which OpenCV does not document as thread-safe). A copy gets its
// own ORB detector; a moved-from verifier may only be assigned or destroyed.
class GeometricVerifier {
 public:
  // Validates the options (throws InvalidArgument naming the field).
  explicit GeometricVerifier(const GeometricOptions& options = {});
  ~GeometricVerifier();
  GeometricVerifier(const GeometricVerifier& other);
  GeometricVerifier& operator=(const GeometricVerifier& other);
  GeometricVerifier(GeometricVerifier&&) noexcept;
  GeometricVerifier& operator=(GeometricVerifier&&) noexcept;

  // Computes and keeps the features of the next frame (id = size()). Frames
  // must be added in order; any non-empty gray image is accepted (a flat image
  // simply has no keypoints). Throws InvalidArgument, leaving the verifier
  // unchanged, only for an empty image or one whose pixel count is not
  // width x height.
  void add(const GrayImage& image);
  // The features add() would keep for `image` (x, y per keypoint in its
  // pixels, 32 bytes of ORB descriptor per keypoint), keeping nothing: what
  // add_features() takes back (a frame described apart from the map,
  // Detector::describe_frame()). Throws as add() does.
  void compute(const GrayImage& image, std::vector<float>& points,
               std::vector<std::uint8_t>& descriptors) const;

  // Checks frames `query` and `candidate` (both added). Never throws on
  // degenerate geometry (identical images, pure rotation, planar scenes, too
  // few matches): those give an accepted or rejected check with a reason.
  // Throws InvalidArgument for ids not added yet.
  GeometricCheck verify(std::int64_t query, std::int64_t candidate) const;

  // Forgets the last frame added (a query that is not stored,
  // Detector::query()); InvalidArgument when there is none.
  void remove_last();

  std::int64_t size() const;
  const GeometricOptions& options() const { return options_; }
  // Keypoints stored for frame i; throws InvalidArgument for ids not added.
  int keypoints(std::int64_t frame) const;
  // Mean bytes of feature data held per added frame (0 before the first):
  // 8 (x, y) + 32 (descriptor) per keypoint, plus the frame's offset.
  std::size_t bytes_per_frame() const;

  // Persistence (lsgd::io::Database): copies frame i's stored features into
  // `points` (x, y per keypoint) and `descriptors` (32 bytes per keypoint);
  // throws InvalidArgument for ids not added.
  void features(std::int64_t frame, std::vector<float>& points,
                std::vector<std::uint8_t>& descriptors) const;
  // Appends the next frame's features as add() computed them from a
  // width x height image, without the image. Throws InvalidArgument, leaving
  // the verifier unchanged, when points.size() != 2 n or descriptors.size() !=
  // 32 n, a point is not finite, or the size is not positive.
  void add_features(const std::vector<float>& points, const std::vector<std::uint8_t>& descriptors,
                    int width, int height);
  // Working-size pixels per original pixel of an image of this size (the
  // scale ORB ran at).
  double working_scale(int width, int height) const;

 private:
  GeometricOptions options_;
  // Contiguous storage: frame i owns keypoints [offsets_[i], offsets_[i+1]).
  std::vector<std::int64_t> offsets_{0};
  std::vector<float> points_;              // x, y per keypoint, original image pixels
  std::vector<std::uint8_t> descriptors_;  // 32 bytes per keypoint (ORB)
  std::vector<float> scales_;              // working_scale() of each frame
  struct Orb;                              // cv::ORB, kept out of this header
  std::unique_ptr<Orb> orb_;               // created once, in the constructor
};

}  // namespace lsgd
