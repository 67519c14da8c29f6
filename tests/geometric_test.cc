// Tests of the geometric verification stage (include/lsgd/geometric.h): ORB
// features kept per frame, ratio-test matching, F / H fitted with RANSAC.
// Every image is generated here: random rectangles, circles and lines of random
// gray levels plus noise, from a fixed-seed cv::RNG, then warped to make a
// second view of the same "place".
#include "lsgd/geometric.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "test_util.h"

namespace lsgd {

namespace {

// The stored keypoint coordinates of one frame (features(), as persisted).
std::vector<cv::Point2f> stored_points(const GeometricVerifier& v, std::int64_t frame) {
  std::vector<float> xy;
  std::vector<std::uint8_t> orb;
  v.features(frame, xy, orb);
  std::vector<cv::Point2f> out;
  for (std::size_t i = 0; i + 1 < xy.size(); i += 2) out.emplace_back(xy[i], xy[i + 1]);
  return out;
}


using test::message_of;

// A textured scene: random filled rectangles and circles, a few lines, noise.
cv::Mat texture(int width, int height, std::uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat m(height, width, CV_8UC1, cv::Scalar(rng.uniform(60, 200)));
  const int shapes = width * height / 600;
  for (int i = 0; i < shapes; ++i) {
    const cv::Point p(rng.uniform(0, width), rng.uniform(0, height));
    const cv::Scalar gray(rng.uniform(0, 256));
    const int size = rng.uniform(3, 25);
    switch (rng.uniform(0, 3)) {
      case 0:
        cv::rectangle(m, p, p + cv::Point(size, rng.uniform(3, 25)), gray, cv::FILLED);
        break;
      case 1:
        cv::circle(m, p, size / 2, gray, cv::FILLED);
        break;
      default:
        cv::line(m, p, p + cv::Point(rng.uniform(-30, 30), rng.uniform(-30, 30)), gray, 2);
    }
  }
  cv::Mat noise(height, width, CV_8UC1);
  rng.fill(noise, cv::RNG::NORMAL, 0, 4);
  cv::add(m, noise, m);  // saturating
  return m;
}

GrayImage gray_of(const cv::Mat& m) {
  CV_Assert(m.type() == CV_8UC1);
  GrayImage g;
  g.width = m.cols;
  g.height = m.rows;
  g.pixels.resize(static_cast<std::size_t>(m.cols) * m.rows);
  for (int y = 0; y < m.rows; ++y) {
    std::copy(m.ptr<std::uint8_t>(y), m.ptr<std::uint8_t>(y) + m.cols,
              g.pixels.begin() + static_cast<std::ptrdiff_t>(y) * m.cols);
  }
  return g;
}

// The w x h window of `scene` at (x, y).
cv::Mat crop(const cv::Mat& scene, int x, int y, int w, int h) {
  return scene(cv::Rect(x, y, w, h)).clone();
}

// Adds both images (ids 0 and 1) to a fresh verifier and checks 1 against 0.
GeometricCheck check_pair(const cv::Mat& a, const cv::Mat& b, const GeometricOptions& o = {}) {
  GeometricVerifier v(o);
  v.add(gray_of(a));
  v.add(gray_of(b));
  return v.verify(1, 0);
}

// ---- options ----------------------------------------------------------------------

TEST(GeometricOptions, DefaultsAreValid) {
  EXPECT_NO_THROW(GeometricOptions{}.check());
  EXPECT_NO_THROW(GeometricVerifier{});
}

TEST(GeometricOptions, EachFieldIsRangeChecked) {
  struct Case {
    const char* field;
    void (*set)(GeometricOptions&);
  };
  const Case cases[] = {
      {"geometric.max_features = 15", [](GeometricOptions& o) { o.max_features = 15; }},
      {"geometric.max_features = 20001", [](GeometricOptions& o) { o.max_features = 20001; }},
      {"geometric.min_side = -1", [](GeometricOptions& o) { o.min_side = -1; }},
      {"geometric.min_side = 4097", [](GeometricOptions& o) { o.min_side = 4097; }},
      {"geometric.ratio = 0 ", [](GeometricOptions& o) { o.ratio = 0; }},
      {"geometric.ratio = 1.5", [](GeometricOptions& o) { o.ratio = 1.5; }},
      {"geometric.ratio = nan", [](GeometricOptions& o) { o.ratio = std::nan(""); }},
      {"geometric.ransac_threshold = 0 ", [](GeometricOptions& o) { o.ransac_threshold = 0; }},
      {"geometric.ransac_threshold = 101", [](GeometricOptions& o) { o.ransac_threshold = 101; }},
      {"geometric.min_inliers = 7", [](GeometricOptions& o) { o.min_inliers = 7; }},
      {"geometric.min_inliers = 10001", [](GeometricOptions& o) { o.min_inliers = 10001; }},
      {"geometric.min_inlier_ratio = -0.1",
       [](GeometricOptions& o) { o.min_inlier_ratio = -0.1; }},
      {"geometric.min_inlier_ratio = 1.1", [](GeometricOptions& o) { o.min_inlier_ratio = 1.1; }},
  };
  for (const Case& c : cases) {
    GeometricOptions o;
    c.set(o);
    const std::string message = message_of<InvalidArgument>([&] { o.check(); });
    EXPECT_NE(message.find(c.field), std::string::npos) << message;
    EXPECT_NE(message.find("out of range"), std::string::npos) << message;
    EXPECT_THROW(GeometricVerifier{o}, InvalidArgument) << c.field;
  }
  // Range ends are valid.
  GeometricOptions o;
  o.max_features = 16;
  o.min_side = 0;
  o.ratio = 1.0;
  o.ransac_threshold = 100;
  o.min_inliers = 8;
  EXPECT_NO_THROW(o.check());
}

// ---- accepted: the same place -------------------------------------------------------

TEST(GeometricVerifier, IdenticalImagesAreAcceptedByTheHomography) {
  const cv::Mat a = texture(320, 240, 1);
  const GeometricCheck c = check_pair(a, a);
  EXPECT_TRUE(c.accepted) << c.reason;
  EXPECT_GE(c.inliers, GeometricOptions{}.min_inliers);
  EXPECT_GE(c.matches, c.inliers);
  // Zero displacement makes F degenerate; H = I explains every match.
  EXPECT_EQ(c.model, "homography") << c.reason;
  EXPECT_EQ(c.inliers, c.matches) << c.reason;
  EXPECT_NE(c.reason.find("homography: "), std::string::npos) << c.reason;
  EXPECT_NE(c.reason.find(">= 20"), std::string::npos) << c.reason;
  EXPECT_GE(c.ms, 0.0);
}

TEST(GeometricVerifier, ShiftedSceneIsAccepted) {
  const cv::Mat scene = texture(400, 300, 2);
  const GeometricCheck c = check_pair(crop(scene, 40, 30, 320, 240), crop(scene, 45, 27, 320, 240));
  EXPECT_TRUE(c.accepted) << c.reason;
  EXPECT_GE(c.inliers, 100) << c.reason;
}

TEST(GeometricVerifier, SlightlyScaledSceneIsAccepted) {
  const cv::Mat scene = texture(400, 300, 3);
  cv::Mat zoomed;
  cv::resize(scene, zoomed, cv::Size(), 1.1, 1.1, cv::INTER_LINEAR);
  // The same centre: (200, 150) in scene, (220, 165) in zoomed.
  const GeometricCheck c =
      check_pair(crop(scene, 40, 30, 320, 240), crop(zoomed, 60, 45, 320, 240));
  EXPECT_TRUE(c.accepted) << c.reason;
  EXPECT_GE(c.inliers, 50) << c.reason;
}

TEST(GeometricVerifier, InPlaneRotationIsAccepted) {
  const cv::Mat a = texture(320, 240, 4);
  cv::Mat b;
  const cv::Mat r = cv::getRotationMatrix2D(cv::Point2f(160, 120), 10, 1.0);
  cv::warpAffine(a, b, r, a.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  const GeometricCheck c = check_pair(a, b);
  EXPECT_TRUE(c.accepted) << c.reason;
  EXPECT_GE(c.inliers, 50) << c.reason;
}

TEST(GeometricVerifier, PerspectiveViewOfAPlaneIsAccepted) {
  const cv::Mat a = texture(320, 240, 5);
  const cv::Point2f from[] = {{0, 0}, {319, 0}, {319, 239}, {0, 239}};
  const cv::Point2f to[] = {{20, 10}, {300, 0}, {319, 239}, {10, 220}};
  cv::Mat b;
  cv::warpPerspective(a, b, cv::getPerspectiveTransform(from, to), a.size(), cv::INTER_LINEAR,
                      cv::BORDER_REFLECT);
  const GeometricCheck c = check_pair(a, b);
  EXPECT_TRUE(c.accepted) << c.reason;
  EXPECT_GE(c.inliers, 50) << c.reason;
  EXPECT_FALSE(c.model.empty());
}

// The geometry returned with the check: every match, the inlier mask the
// count comes from, and the model itself (here the warp that made the view).
TEST(GeometricVerifier, TheGeometryIsTheMatchesAndTheModelThatWasFitted) {
  const cv::Mat a = texture(320, 240, 5);
  const cv::Point2f from[] = {{0, 0}, {319, 0}, {319, 239}, {0, 239}};
  const cv::Point2f to[] = {{20, 10}, {300, 0}, {319, 239}, {10, 220}};
  const cv::Mat warp = cv::getPerspectiveTransform(from, to);
  cv::Mat b;
  cv::warpPerspective(a, b, warp, a.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  const GeometricCheck c = check_pair(a, b);  // query b, candidate a
  ASSERT_TRUE(c.accepted) << c.reason;
  ASSERT_NE(c.geometry, nullptr);
  const LoopGeometry& g = *c.geometry;
  EXPECT_EQ(g.model, c.model);
  ASSERT_EQ(g.matches(), static_cast<std::size_t>(c.matches));
  ASSERT_EQ(g.query_points.size(), 2 * g.matches());
  ASSERT_EQ(g.candidate_points.size(), 2 * g.matches());
  EXPECT_EQ(std::count(g.inliers.begin(), g.inliers.end(), 1), c.inliers);
  const cv::Matx33d m(g.matrix.data());
  // A point of the query (b) is warp^-1 of it in the candidate (a).
  const cv::Matx33d truth = cv::Matx33d(warp).inv();
  const auto apply = [](const cv::Matx33d& h, double x, double y) {
    const cv::Vec3d p = h * cv::Vec3d(x, y, 1);
    return cv::Point2d(p[0] / p[2], p[1] / p[2]);
  };
  // The model explains its inliers (H within RANSAC's 3 px, at this size the
  // working size; F by USAC's Sampson error, a little more one-sided), and
  // they are the true correspondences, but for a few that F lets slide along
  // their epipolar line.
  int true_matches = 0;
  for (std::size_t k = 0; k < g.matches(); ++k) {
    if (!g.inliers[k]) continue;
    const double qx = g.query_points[2 * k], qy = g.query_points[2 * k + 1];
    const cv::Point2d matched(g.candidate_points[2 * k], g.candidate_points[2 * k + 1]);
    true_matches += cv::norm(apply(truth, qx, qy) - matched) < 3.0 ? 1 : 0;
    if (g.model == "homography") {
      EXPECT_LT(cv::norm(apply(m, qx, qy) - matched), 3.01) << "inlier " << k;
    } else {
      // c^T F q = 0: c lies on the epipolar line F q.
      const cv::Vec3d line = m * cv::Vec3d(qx, qy, 1);
      EXPECT_LT(std::abs(line.dot(cv::Vec3d(matched.x, matched.y, 1))) / std::hypot(line[0], line[1]), 5.0)
          << "inlier " << k;
    }
  }
  EXPECT_GE(true_matches, 0.95 * c.inliers) << g.model;
  // No model, no geometry.
  const GeometricCheck none = check_pair(texture(320, 240, 10), cv::Mat(240, 320, CV_8UC1, cv::Scalar(7)));
  EXPECT_EQ(none.geometry, nullptr) << none.reason;
}

// ---- rejected: other places, nothing to match ------------------------------------------

TEST(GeometricVerifier, UnrelatedImagesAreRejected) {
  for (std::uint64_t seed = 10; seed < 14; ++seed) {
    const GeometricCheck c = check_pair(texture(320, 240, seed), texture(320, 240, seed + 100));
    EXPECT_FALSE(c.accepted) << c.reason;
    EXPECT_LT(c.inliers, GeometricOptions{}.min_inliers) << c.reason;
    EXPECT_FALSE(c.reason.empty());
  }
}

// With the ratio test relaxed, unrelated images give many matches, and RANSAC
// finds a model for a small fraction of them: the inlier-fraction guard must
// reject what the inlier count alone would accept.
TEST(GeometricVerifier, SparseInliersAmongManyMatchesAreRejected) {
  GeometricOptions loose;
  loose.ratio = 1.0;
  loose.min_inliers = 8;
  loose.min_inlier_ratio = 0.0;
  GeometricOptions guarded = loose;
  guarded.min_inlier_ratio = 0.5;
  int sparse = 0;
  for (std::uint64_t seed = 20; seed < 26; ++seed) {
    const cv::Mat a = texture(320, 240, seed), b = texture(320, 240, seed + 100);
    const GeometricCheck unguarded = check_pair(a, b, loose);
    const GeometricCheck c = check_pair(a, b, guarded);
    EXPECT_EQ(c.inliers, unguarded.inliers);  // same fit, only the decision differs
    if (unguarded.inliers >= 8 && unguarded.inliers < 0.5 * unguarded.matches) {
      ++sparse;
      EXPECT_TRUE(unguarded.accepted) << unguarded.reason;
      EXPECT_FALSE(c.accepted) << c.reason;
      EXPECT_NE(c.reason.find("below 0.5 of the matches"), std::string::npos) << c.reason;
    }
  }
  EXPECT_GT(sparse, 0) << "no unrelated pair produced a sparse model: the test checks nothing";
  // The same place keeps almost every match as an inlier and passes the guard.
  const cv::Mat a = texture(320, 240, 30);
  EXPECT_TRUE(check_pair(a, a, guarded).accepted);
}

TEST(GeometricVerifier, FlatImageHasNoKeypointsAndIsRejected) {
  GeometricVerifier v;
  v.add(test::uniform_image(320, 240, 128));
  v.add(gray_of(texture(320, 240, 6)));
  EXPECT_EQ(v.keypoints(0), 0);
  EXPECT_GT(v.keypoints(1), 100);
  for (const auto& [q, c] : {std::pair<int, int>{0, 1}, {1, 0}, {0, 0}}) {
    GeometricCheck check;
    ASSERT_NO_THROW(check = v.verify(q, c));
    EXPECT_FALSE(check.accepted);
    EXPECT_EQ(check.matches, 0);
    EXPECT_EQ(check.inliers, 0);
    EXPECT_EQ(check.model, "");
    EXPECT_EQ(check.reason, "too few matches (0 < 8)");
  }
}

TEST(GeometricVerifier, MatchesAreOneToOne) {
  // The query shows the candidate's scene twice, side by side: every candidate
  // keypoint has two equally good partners, and may be matched only once.
  const cv::Mat c = texture(320, 240, 25);
  cv::Mat q;
  cv::hconcat(c, c, q);
  GeometricOptions o;
  o.max_features = 5000;  // no cap: the query has about twice the candidate's keypoints
  GeometricVerifier v(o);
  v.add(gray_of(c));
  v.add(gray_of(q));
  const GeometricCheck check = v.verify(1, 0);
  EXPECT_GT(v.keypoints(1), v.keypoints(0) * 3 / 2);
  EXPECT_GT(check.matches, v.keypoints(0) / 2) << check.reason;
  EXPECT_LE(check.matches, v.keypoints(0)) << check.reason;
  EXPECT_LE(check.inliers, check.matches);
}

// ---- small frames ---------------------------------------------------------------------

TEST(GeometricVerifier, SmallImagesAreUpscaledBeforeOrb) {
  const cv::Mat scene = texture(200, 150, 7);
  const cv::Mat a = crop(scene, 20, 15, 160, 120);
  const cv::Mat b = crop(scene, 23, 13, 160, 120);

  GeometricVerifier v;  // min_side 240: 160x120 is ORB'd at 320x240
  v.add(gray_of(a));
  v.add(gray_of(b));
  v.add(gray_of(texture(160, 120, 8)));
  EXPECT_GT(v.keypoints(0), 50);
  const GeometricCheck same = v.verify(1, 0);
  EXPECT_TRUE(same.accepted) << same.reason;
  const GeometricCheck other = v.verify(2, 0);
  EXPECT_FALSE(other.accepted) << other.reason;

  GeometricOptions native;
  native.min_side = 0;  // never upscale: the 31-pixel ORB border eats most of the frame
  GeometricVerifier w(native);
  w.add(gray_of(a));
  EXPECT_LT(w.keypoints(0), v.keypoints(0));
}

// Keypoints found on the upscaled image are stored in original pixels (the
// RANSAC threshold is in original pixels): texture only inside a window of a
// flat 160x120 frame (ORB'd at 320x240) must give keypoints inside that window.
TEST(GeometricVerifier, KeypointsAreStoredInOriginalPixels) {
  const cv::Rect window(50, 30, 60, 50);
  cv::Mat a(120, 160, CV_8UC1, cv::Scalar(128));
  texture(window.width, window.height, 9).copyTo(a(window));
  GeometricVerifier v;
  v.add(gray_of(a));
  const std::vector<cv::Point2f> points = stored_points(v, 0);
  ASSERT_GT(points.size(), 20u);
  const float slack = 4;  // coarse pyramid levels localise to a few pixels
  for (const cv::Point2f& p : points) {
    EXPECT_GE(p.x, window.x - slack);
    EXPECT_LE(p.x, window.x + window.width + slack);
    EXPECT_GE(p.y, window.y - slack);
    EXPECT_LE(p.y, window.y + window.height + slack);
  }
}

// ---- ids, storage, determinism ------------------------------------------------------------

TEST(GeometricVerifier, IdsNotAddedAreInvalid) {
  GeometricVerifier v;
  EXPECT_THROW(v.verify(0, 0), InvalidArgument);
  EXPECT_THROW(v.keypoints(0), InvalidArgument);
  v.add(gray_of(texture(320, 240, 11)));
  v.add(gray_of(texture(320, 240, 12)));
  EXPECT_THROW(v.verify(2, 0), InvalidArgument);
  EXPECT_THROW(v.verify(0, 2), InvalidArgument);
  EXPECT_THROW(v.verify(-1, 0), InvalidArgument);
  EXPECT_THROW(v.keypoints(-1), InvalidArgument);
  const std::string message = message_of<InvalidArgument>([&] { v.verify(5, 0); });
  EXPECT_NE(message.find("frame 5"), std::string::npos) << message;
  EXPECT_NO_THROW(v.verify(1, 0));
}

TEST(GeometricVerifier, MalformedImagesAreInvalidAndLeaveTheVerifierUnchanged) {
  GeometricVerifier v;
  v.add(gray_of(texture(320, 240, 13)));
  const std::size_t bytes = v.bytes_per_frame();
  EXPECT_THROW(v.add(GrayImage{}), InvalidArgument);
  GrayImage bad = test::uniform_image(32, 32, 9);
  bad.pixels.pop_back();
  EXPECT_THROW(v.add(bad), InvalidArgument);
  EXPECT_EQ(v.size(), 1);
  EXPECT_EQ(v.bytes_per_frame(), bytes);
}

TEST(GeometricVerifier, FeaturesAreComputedOnceAndChecksAreDeterministic) {
  const cv::Mat scene = texture(400, 300, 14);
  GeometricVerifier v;
  EXPECT_EQ(v.size(), 0);
  EXPECT_EQ(v.bytes_per_frame(), 0u);
  v.add(gray_of(crop(scene, 40, 30, 320, 240)));
  v.add(gray_of(crop(scene, 44, 33, 320, 240)));
  v.add(gray_of(texture(320, 240, 15)));
  ASSERT_EQ(v.size(), 3);
  const int k[] = {v.keypoints(0), v.keypoints(1), v.keypoints(2)};
  const GeometricCheck first = v.verify(1, 0);
  EXPECT_TRUE(first.accepted) << first.reason;
  for (int round = 0; round < 5; ++round) {
    for (int q = 0; q < 3; ++q) {
      for (int c = 0; c < 3; ++c) EXPECT_NO_THROW(v.verify(q, c));
    }
    const GeometricCheck again = v.verify(1, 0);
    EXPECT_EQ(again.accepted, first.accepted);
    EXPECT_EQ(again.matches, first.matches);
    EXPECT_EQ(again.inliers, first.inliers);
    EXPECT_EQ(again.reason, first.reason);
  }
  EXPECT_EQ(v.size(), 3);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(v.keypoints(i), k[i]);
  EXPECT_LE(k[0], GeometricOptions{}.max_features);
  // x, y floats and a 32-byte descriptor per keypoint, plus the offset.
  const std::size_t mean = (k[0] + k[1] + k[2]) / 3;
  EXPECT_GE(v.bytes_per_frame(), mean * 40);
  EXPECT_LE(v.bytes_per_frame(), mean * 40 + 64);
}

TEST(GeometricVerifier, CopiesShareNothing) {
  GeometricVerifier v;
  v.add(gray_of(texture(320, 240, 16)));
  GeometricVerifier copy = v;
  copy.add(gray_of(texture(320, 240, 16)));
  EXPECT_EQ(v.size(), 1);
  EXPECT_EQ(copy.size(), 2);
  EXPECT_EQ(copy.keypoints(0), v.keypoints(0));
  EXPECT_TRUE(copy.verify(1, 0).accepted);
  GeometricVerifier moved = std::move(copy);
  EXPECT_EQ(moved.size(), 2);
  moved.add(gray_of(texture(320, 240, 17)));
  EXPECT_EQ(moved.size(), 3);
}

TEST(GeometricVerifier, MaxFeaturesCapsKeypoints) {
  GeometricOptions o;
  o.max_features = 100;
  GeometricVerifier v(o);
  v.add(gray_of(texture(640, 480, 18)));
  EXPECT_GT(v.keypoints(0), 50);
  EXPECT_LE(v.keypoints(0), 100);
}

// ---- degenerate geometry never throws ------------------------------------------------------

TEST(GeometricVerifier, CollinearKeypointsAreNotEvidence) {
  // Blobs along one horizontal line: every keypoint lies on (nearly) one line,
  // where H and F are undetermined (OpenCV's USAC still returns an F with every
  // match an inlier). Never thrown, never accepted.
  cv::Mat a(240, 320, CV_8UC1, cv::Scalar(128));
  cv::RNG rng(19);
  for (int x = 20; x < 300; x += 9) {
    cv::rectangle(a, cv::Point(x, 119), cv::Point(x + 3, 121), cv::Scalar(rng.uniform(0, 60)),
                  cv::FILLED);
  }
  cv::Mat b;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, 4, 0, 1, 0);
  cv::warpAffine(a, b, shift, a.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  GeometricOptions o;
  o.min_inliers = 8;
  GeometricVerifier v(o);
  v.add(gray_of(a));
  v.add(gray_of(b));
  EXPECT_GT(v.keypoints(0), 20);
  GeometricCheck c;
  ASSERT_NO_THROW(c = v.verify(1, 0));
  EXPECT_GE(c.matches, 8) << c.reason;
  EXPECT_FALSE(c.accepted) << c.reason;
  EXPECT_EQ(c.inliers, 0) << c.reason;
  EXPECT_NE(c.reason.find("lie on a line"), std::string::npos) << c.reason;
  for (int q = 0; q < 2; ++q) {
    for (int k = 0; k < 2; ++k) EXPECT_NO_THROW(v.verify(q, k));
  }
}

TEST(GeometricVerifier, VeryFewKeypointsDoNotThrow) {
  cv::Mat a(240, 320, CV_8UC1, cv::Scalar(100));
  cv::rectangle(a, cv::Point(100, 80), cv::Point(140, 120), cv::Scalar(220), cv::FILLED);
  cv::circle(a, cv::Point(220, 160), 15, cv::Scalar(20), cv::FILLED);
  GeometricVerifier v;
  v.add(gray_of(a));
  v.add(gray_of(a));
  v.add(gray_of(texture(320, 240, 20)));
  EXPECT_LT(v.keypoints(0), 200);
  for (int q = 0; q < 3; ++q) {
    for (int c = 0; c < 3; ++c) EXPECT_NO_THROW(v.verify(q, c));
  }
  const GeometricCheck c = v.verify(2, 0);
  EXPECT_FALSE(c.accepted) << c.reason;
}

TEST(GeometricVerifier, RepeatedTextureDoesNotThrow) {
  // One tile repeated: many keypoints share a descriptor (duplicate matches,
  // ambiguous ratio test).
  const cv::Mat tile = texture(40, 40, 21);
  cv::Mat a;
  cv::repeat(tile, 6, 8, a);
  GeometricVerifier v;
  v.add(gray_of(a));
  v.add(gray_of(crop(a, 40, 0, 200, 240)));
  GeometricCheck c;
  EXPECT_NO_THROW(c = v.verify(1, 0));
  EXPECT_NO_THROW(c = v.verify(0, 1));
  EXPECT_FALSE(c.reason.empty());
}

TEST(GeometricVerifier, TinyAndThinImagesAreAccepted) {
  GeometricOptions native;
  native.min_side = 0;
  GeometricVerifier v(native);
  EXPECT_NO_THROW(v.add(test::uniform_image(1, 1, 7)));
  EXPECT_NO_THROW(v.add(gray_of(texture(10, 10, 22))));
  EXPECT_EQ(v.keypoints(0), 0);
  EXPECT_EQ(v.keypoints(1), 0);  // smaller than ORB's border
  GeometricVerifier up;          // upscaled, the longer side capped at kMaxImageSide
  EXPECT_NO_THROW(up.add(gray_of(texture(2000, 2, 23))));
  EXPECT_NO_THROW(up.add(test::uniform_image(1, 1, 7)));
  EXPECT_EQ(up.size(), 2);
  EXPECT_NO_THROW(up.verify(0, 1));
}

}  // namespace
}  // namespace lsgd
