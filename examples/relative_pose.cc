// The relative pose of each declared loop, from the geometry the detector
// returns (Result::geometry: the matched points, the inlier mask and the
// fitted F or H), with OpenCV and no second feature matching.
//
//   lsgd_example_relative_pose FOLDER [MIN_GAP [FOCAL_PX]]
//
// The camera matrix is a guess unless FOCAL_PX is given: focal length = the
// image width (a 53-degree horizontal field of view), principal point at the
// centre. A fundamental matrix gives E = K^T F K and cv::recoverPose keeps the
// solution with the matches in front of both cameras; a homography is
// decomposed and its solutions filtered by the same test. A pose is valid when
// at least half of the model's inliers (and 8) lie in front of both cameras.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <lsgd/detector.h>
#include <lsgd/error.h>
#include <lsgd/io/sequence.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <vector>

namespace {

struct Pose {
  bool valid = false;
  cv::Mat R, t;    // the query camera in the candidate's frame: x_c = R x_q + t (t up to scale)
  int support = 0;  // inliers in front of both cameras
};

Pose relative_pose(const lsgd::LoopGeometry& g, const cv::Matx33d& K) {
  std::vector<cv::Point2f> q, c;  // the model's inliers
  for (std::size_t k = 0; k < g.matches(); ++k) {
    if (!g.inliers[k]) continue;
    q.emplace_back(g.query_points[2 * k], g.query_points[2 * k + 1]);
    c.emplace_back(g.candidate_points[2 * k], g.candidate_points[2 * k + 1]);
  }
  const cv::Mat M = cv::Mat(3, 3, CV_64F, const_cast<double*>(g.matrix.data())).clone();
  Pose pose;
  if (g.model == "fundamental") {
    const cv::Mat E = cv::Mat(K.t()) * M * cv::Mat(K);
    pose.support = cv::recoverPose(E, q, c, cv::Mat(K), pose.R, pose.t);
  } else {
    std::vector<cv::Mat> Rs, ts, normals;
    cv::decomposeHomographyMat(M, K, Rs, ts, normals);
    std::vector<int> kept;
    cv::filterHomographyDecompByVisibleRefpoints(Rs, normals, q, c, kept);
    if (!kept.empty()) {
      pose.R = Rs[static_cast<std::size_t>(kept[0])];
      pose.t = ts[static_cast<std::size_t>(kept[0])];
      pose.support = static_cast<int>(q.size());
    }
  }
  pose.valid = pose.support >= 8 && 2 * pose.support >= static_cast<int>(q.size());
  return pose;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s FOLDER [MIN_GAP [FOCAL_PX]]\n", argv[0]);
    return 2;
  }
  try {
    lsgd::DetectorOptions options;  // the shipped defaults: the geometric stage is on
    options.search.min_gap = argc > 2 ? std::atoll(argv[2]) : 50;
    lsgd::Detector detector(options);
    const lsgd::io::Sequence sequence = lsgd::io::open_sequence(argv[1]);
    int loops = 0, with_geometry = 0, valid = 0;
    double pose_ms = 0;
    for (const std::string& path : sequence.images) {
      const cv::Mat image = lsgd::io::read_image(path);
      const lsgd::Result r = detector.process(image);
      if (!r.loop) continue;
      ++loops;
      if (!r.geometry) continue;  // a loop the geometric stage did not fit (it is off)
      ++with_geometry;
      const double f = argc > 3 ? std::atof(argv[3]) : image.cols;
      const cv::Matx33d K(f, 0, image.cols / 2.0, 0, f, image.rows / 2.0, 0, 0, 1);
      const auto start = std::chrono::steady_clock::now();
      const lsgd::LoopGeometry& g = *r.geometry;  // r.loop: a loop with the default stages
      const Pose pose = relative_pose(g, K);
      pose_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      if (!pose.valid) continue;
      ++valid;
      const double angle = std::acos(std::max(-1.0, std::min(1.0, (cv::trace(pose.R)[0] - 1) / 2))) * 180 / M_PI;
      const double n = std::max(cv::norm(pose.t), 1e-12);  // a pure rotation has no direction
      std::printf("frame %lld -> %lld: %s, %d inliers, rotation %.1f deg, direction (%.2f, %.2f, %.2f)\n",
                  static_cast<long long>(r.frame), static_cast<long long>(r.best.frame),
                  g.model.c_str(), pose.support, angle, pose.t.at<double>(0) / n,
                  pose.t.at<double>(1) / n, pose.t.at<double>(2) / n);
    }
    std::printf("%d loops, %d with geometry, %d with a valid relative pose; %.3f ms per pose\n", loops,
                with_geometry, valid, with_geometry > 0 ? pose_ms / with_geometry : 0.0);
    return 0;
  } catch (const lsgd::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
