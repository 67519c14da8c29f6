#include "lsgd/geometric.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "internal/check.h"

namespace lsgd {

namespace {

constexpr int kDescriptorBytes = 32;  // ORB: 256 binary tests
constexpr int kNoMatch = -1;
constexpr int kMinMatches = 8;        // the 8-point fundamental matrix needs 8
// ORB on the (possibly upscaled) image: OpenCV's pyramid (8 levels, x1.2)
// and 31-pixel patch, which fit images whose shorter side is >= 240 after
// upscaling. FAST threshold 10 instead of OpenCV's 20: low-contrast indoor
// frames (corridor, 160x120) get 468 instead of 418 keypoints and slightly more
// true loops pass at the same false-accept rate; textured frames are capped by
// max_features either way.
constexpr float kScaleFactor = 1.2f;
constexpr int kLevels = 8;
constexpr int kEdgeThreshold = 31;
constexpr int kPatchSize = 31;
constexpr int kFastThreshold = 10;
// RANSAC settings; the confidence of F is the one the design asks for.
constexpr double kConfidence = 0.99;
constexpr int kMaxIters = 2000;

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

// ---- Hamming matching on the contiguous descriptors --------------------------------
// For every query descriptor: the best and second-best candidate distances
// (for Lowe's ratio test); for every candidate descriptor: the query nearest
// to it (for the mutual check). One pass over the qn x cn distance matrix.
struct NearestTable {
  std::vector<int> best, best_dist, second_dist;  // per query
  std::vector<int> col_best, col_dist;            // per candidate
};

inline void load4(const std::uint8_t* d, std::uint64_t w[4]) { std::memcpy(w, d, 32); }

// The kernel is written once and compiled twice: with the POPCNT instruction
// (chosen at run time when the CPU has it: every x86-64 CPU since 2008) and
// portable (libgcc's bit-twiddling popcount), the scalar reference.
#define LSGD_NEAREST_BODY                                                                  \
  for (int i = 0; i < qn; ++i) {                                                           \
    std::uint64_t a[4];                                                                    \
    load4(q + static_cast<std::size_t>(i) * kDescriptorBytes, a);                          \
    int b1 = std::numeric_limits<int>::max(), b2 = b1, bi = kNoMatch;                      \
    for (int j = 0; j < cn; ++j) {                                                         \
      std::uint64_t b[4];                                                                  \
      load4(c + static_cast<std::size_t>(j) * kDescriptorBytes, b);                        \
      const int d = __builtin_popcountll(a[0] ^ b[0]) + __builtin_popcountll(a[1] ^ b[1]) + \
                    __builtin_popcountll(a[2] ^ b[2]) + __builtin_popcountll(a[3] ^ b[3]); \
      if (d < b1) {                                                                        \
        b2 = b1, b1 = d, bi = j;                                                           \
      } else if (d < b2) {                                                                 \
        b2 = d;                                                                            \
      }                                                                                    \
      if (d < t.col_dist[j]) t.col_dist[j] = d, t.col_best[j] = i;                         \
    }                                                                                      \
    t.best[i] = bi, t.best_dist[i] = b1, t.second_dist[i] = b2;                            \
  }

void nearest_portable(const std::uint8_t* q, int qn, const std::uint8_t* c, int cn,
                      NearestTable& t) {
  LSGD_NEAREST_BODY
}

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
__attribute__((target("popcnt"))) void nearest_popcnt(const std::uint8_t* q, int qn,
                                                      const std::uint8_t* c, int cn,
                                                      NearestTable& t) {
  LSGD_NEAREST_BODY
}
#endif
#undef LSGD_NEAREST_BODY

using NearestKernel = void (*)(const std::uint8_t*, int, const std::uint8_t*, int, NearestTable&);

NearestKernel choose_kernel() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  __builtin_cpu_init();
  if (__builtin_cpu_supports("popcnt")) return nearest_popcnt;
#endif
  return nearest_portable;
}

void nearest(const std::uint8_t* q, int qn, const std::uint8_t* c, int cn, NearestTable& t) {
  static const NearestKernel kernel = choose_kernel();  // chosen once
  t.best.assign(qn, kNoMatch);
  t.best_dist.assign(qn, 0);
  t.second_dist.assign(qn, 0);
  t.col_best.assign(cn, kNoMatch);
  t.col_dist.assign(cn, std::numeric_limits<int>::max());
  kernel(q, qn, c, cn, t);
}

// ---- Model fitting ------------------------------------------------------------------
struct ModelFit {
  int inliers = 0;
  std::string error;  // a cv::Exception's message when OpenCV refused the points
};

int count_mask(const cv::Mat& mask) { return mask.empty() ? 0 : cv::countNonZero(mask); }

bool finite(const cv::Mat& m) { return !m.empty() && cv::checkRange(m, true, nullptr); }

ModelFit fit_homography(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b,
                        double threshold) {
  ModelFit fit;
  try {
    cv::Mat mask;
    const cv::Mat h = cv::findHomography(a, b, cv::RANSAC, threshold, mask, kMaxIters, 0.995);
    // An empty H means RANSAC found no non-degenerate sample (e.g. every
    // point on one line); a near-singular H folds the plane onto a line or a
    // point and its "inliers" are coincidences, not a view of the same place.
    if (finite(h) && std::abs(cv::determinant(h)) > 1e-8 * std::pow(cv::norm(h), 3)) {
      fit.inliers = count_mask(mask);
    }
  } catch (const cv::Exception& e) {
    fit.error = e.err;
  }
  return fit;
}

ModelFit fit_fundamental(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b,
                         double threshold) {
  ModelFit fit;
  try {
    cv::Mat mask;
    const cv::Mat f =
        cv::findFundamentalMat(a, b, cv::FM_RANSAC, threshold, kConfidence, kMaxIters, mask);
    // 7-point solutions stack up to three 3x3 matrices: only a single 3x3 F
    // (the RANSAC result for >= 8 points) comes with a meaningful mask.
    if (finite(f) && f.rows == 3 && f.cols == 3) fit.inliers = count_mask(mask);
  } catch (const cv::Exception& e) {
    fit.error = e.err;
  }
  return fit;
}

}  // namespace

// ---- GeometricOptions -----------------------------------------------------------------
void GeometricOptions::check() const {
  internal::check_range("geometric.max_features", max_features, 16, 20000);
  internal::check_range("geometric.min_side", min_side, 0, 4096, "pixels");
  internal::check_range_open_low("geometric.ratio", ratio, 0.0, 1.0);
  internal::check_range_open_low("geometric.ransac_threshold", ransac_threshold, 0.0, 100.0,
                                 "pixels");
  internal::check_range("geometric.min_inliers", min_inliers, 8, 10000);
}

// ---- GeometricVerifier ---------------------------------------------------------------
struct GeometricVerifier::Orb {
  cv::Ptr<cv::ORB> orb;
  explicit Orb(const GeometricOptions& o)
      : orb(cv::ORB::create(o.max_features, kScaleFactor, kLevels, kEdgeThreshold, 0, 2,
                            cv::ORB::HARRIS_SCORE, kPatchSize, kFastThreshold)) {}
};

GeometricVerifier::GeometricVerifier(const GeometricOptions& options) : options_(options) {
  options_.check();
  orb_ = std::make_unique<Orb>(options_);
}

GeometricVerifier::~GeometricVerifier() = default;
GeometricVerifier::GeometricVerifier(GeometricVerifier&&) noexcept = default;
GeometricVerifier& GeometricVerifier::operator=(GeometricVerifier&&) noexcept = default;

GeometricVerifier::GeometricVerifier(const GeometricVerifier& other)
    : options_(other.options_),
      offsets_(other.offsets_),
      points_(other.points_),
      descriptors_(other.descriptors_),
      orb_(std::make_unique<Orb>(other.options_)) {}

GeometricVerifier& GeometricVerifier::operator=(const GeometricVerifier& other) {
  if (this != &other) *this = GeometricVerifier(other);
  return *this;
}

void GeometricVerifier::add(const GrayImage& image) {
  if (image.empty() || image.width < 0 || image.height < 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * image.height) {
    internal::throw_invalid("GeometricVerifier::add: image ", image.width, "x", image.height,
                            " with ", image.pixels.size(), " pixels is empty or inconsistent");
  }
  // A header on the caller's pixels: OpenCV only reads them.
  const cv::Mat gray(image.height, image.width, CV_8UC1,
                     const_cast<std::uint8_t*>(image.pixels.data()));
  cv::Mat work = gray;
  double sx = 1, sy = 1;  // upscaled pixels per original pixel, per axis
  const int shorter = std::min(image.width, image.height);
  const int longer = std::max(image.width, image.height);
  if (shorter < options_.min_side) {
    // Cap the longer side so that a thin strip is not blown up to gigabytes.
    const double scale = std::min(static_cast<double>(options_.min_side) / shorter,
                                  static_cast<double>(kMaxImageSide) / longer);
    if (scale > 1) {
      const int w = std::max(1, static_cast<int>(std::lround(image.width * scale)));
      const int h = std::max(1, static_cast<int>(std::lround(image.height * scale)));
      cv::resize(gray, work, cv::Size(w, h), 0, 0, cv::INTER_LINEAR);
      sx = static_cast<double>(w) / image.width;
      sy = static_cast<double>(h) / image.height;
    }
  }

  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  try {
    orb_->orb->detectAndCompute(work, cv::noArray(), keypoints, descriptors);
  } catch (const cv::Exception&) {
    // ORB has nothing to say about this image (e.g. smaller than its border):
    // the frame is kept with no keypoints and every check against it rejects.
    keypoints.clear();
    descriptors.release();
  }
  const int n = descriptors.empty() ? 0 : std::min<int>(descriptors.rows, keypoints.size());
  if (n > 0 && (descriptors.type() != CV_8UC1 || descriptors.cols != kDescriptorBytes)) {
    internal::throw_invalid("GeometricVerifier::add: unexpected ORB descriptor layout");
  }

  points_.reserve(points_.size() + 2 * static_cast<std::size_t>(n));
  descriptors_.reserve(descriptors_.size() + static_cast<std::size_t>(n) * kDescriptorBytes);
  offsets_.reserve(offsets_.size() + 1);  // nothing below throws once reserved
  for (int i = 0; i < n; ++i) {
    // cv::resize maps pixel centres: x_up + 0.5 = (x + 0.5) * sx.
    points_.push_back(static_cast<float>((keypoints[i].pt.x + 0.5) / sx - 0.5));
    points_.push_back(static_cast<float>((keypoints[i].pt.y + 0.5) / sy - 0.5));
    const std::uint8_t* row = descriptors.ptr<std::uint8_t>(i);
    descriptors_.insert(descriptors_.end(), row, row + kDescriptorBytes);
  }
  offsets_.push_back(offsets_.back() + n);
}

std::int64_t GeometricVerifier::size() const {
  return static_cast<std::int64_t>(offsets_.size()) - 1;
}

int GeometricVerifier::keypoints(std::int64_t frame) const {
  if (frame < 0 || frame >= size()) {
    internal::throw_invalid("geometric: frame ", frame, " was not added (", size(), " frames)");
  }
  const auto f = static_cast<std::size_t>(frame);
  return static_cast<int>(offsets_[f + 1] - offsets_[f]);
}

std::size_t GeometricVerifier::bytes_per_frame() const {
  if (size() == 0) return 0;
  const std::size_t bytes =
      points_.size() * sizeof(float) + descriptors_.size() + offsets_.size() * sizeof(std::int64_t);
  return bytes / static_cast<std::size_t>(size());
}

GeometricCheck GeometricVerifier::verify(std::int64_t query, std::int64_t candidate) const {
  const auto start = std::chrono::steady_clock::now();
  const int qn = keypoints(query);  // throws InvalidArgument for ids not added
  const int cn = keypoints(candidate);
  GeometricCheck check;

  // 1. Nearest neighbours both ways, Lowe's ratio test, mutual check.
  const auto qo = static_cast<std::size_t>(offsets_[static_cast<std::size_t>(query)]);
  const auto co = static_cast<std::size_t>(offsets_[static_cast<std::size_t>(candidate)]);
  std::vector<cv::Point2f> a, b;
  if (qn > 0 && cn > 0) {
    NearestTable t;
    nearest(descriptors_.data() + qo * kDescriptorBytes, qn,
            descriptors_.data() + co * kDescriptorBytes, cn, t);
    for (int i = 0; i < qn; ++i) {
      const int j = t.best[i];
      if (j == kNoMatch || t.col_best[j] != i) continue;  // not mutual
      // With one candidate keypoint there is no second best: the ratio test passes.
      if (cn > 1 && !(t.best_dist[i] < options_.ratio * t.second_dist[i])) continue;
      a.emplace_back(points_[2 * (qo + i)], points_[2 * (qo + i) + 1]);
      b.emplace_back(points_[2 * (co + j)], points_[2 * (co + j) + 1]);
    }
  }
  check.matches = static_cast<int>(a.size());
  if (check.matches < kMinMatches) {
    check.reason = internal::concat("too few matches (", check.matches, " < ", kMinMatches, ")");
    check.ms = ms_since(start);
    return check;
  }

  // 2. Both models; the better one decides. H wins ties: when every match has
  // zero displacement F is degenerate (any skew-symmetric F fits) while H = I
  // is exact, and for a rotation or a plane H is the right model anyway.
  const ModelFit h = fit_homography(a, b, options_.ransac_threshold);
  const ModelFit f = fit_fundamental(a, b, options_.ransac_threshold);
  const bool use_h = h.inliers >= f.inliers;
  const ModelFit& best = use_h ? h : f;
  check.inliers = best.inliers;
  if (best.inliers > 0) check.model = use_h ? "homography" : "fundamental";
  check.accepted = best.inliers >= options_.min_inliers;
  if (best.inliers == 0) {
    const std::string& error = !h.error.empty() ? h.error : f.error;
    check.reason = internal::concat("no model fitted to ", check.matches, " matches",
                                    error.empty() ? " (degenerate points)" : ": ", error);
  } else {
    check.reason = internal::concat(check.model, ": ", check.inliers, " inliers of ",
                                    check.matches, " matches ", check.accepted ? ">=" : "<",
                                    " ", options_.min_inliers);
  }
  check.ms = ms_since(start);
  return check;
}

}  // namespace lsgd
