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

constexpr int kNoMatch = -1;
constexpr int kMinMatches = 8;  // the 8-point fundamental matrix needs 8
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
// RANSAC settings (both models).
constexpr double kConfidence = 0.99;
constexpr int kMaxIters = 1000;
// Inliers whose spread across their principal axis is below this many RANSAC
// thresholds lie on a line: a degenerate configuration for F and H. 1.0 only
// catches (nearly) collinear sets: on corridor it changes no decision, while
// 2.0 already discarded a third of the accepted true loops (thin bands of
// inliers along the corridor's vanishing line).
constexpr double kMinSpread = 1.0;

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

inline void load4(const std::uint8_t* d, std::uint64_t w[4]) { std::memcpy(w, d, kOrbBytes); }

// The kernel is written once and compiled twice: with the POPCNT instruction
// (chosen at run time when the CPU has it: every x86-64 CPU since 2008) and
// portable (libgcc's bit-twiddling popcount), the scalar reference.
#define LSGD_NEAREST_BODY                                                                   \
  for (int i = 0; i < qn; ++i) {                                                            \
    std::uint64_t a[4];                                                                     \
    load4(q + static_cast<std::size_t>(i) * kOrbBytes, a);                           \
    int b1 = std::numeric_limits<int>::max(), b2 = b1, bi = kNoMatch;                       \
    for (int j = 0; j < cn; ++j) {                                                          \
      std::uint64_t b[4];                                                                   \
      load4(c + static_cast<std::size_t>(j) * kOrbBytes, b);                         \
      const int d = __builtin_popcountll(a[0] ^ b[0]) + __builtin_popcountll(a[1] ^ b[1]) + \
                    __builtin_popcountll(a[2] ^ b[2]) + __builtin_popcountll(a[3] ^ b[3]);  \
      if (d < b1) {                                                                         \
        b2 = b1, b1 = d, bi = j;                                                            \
      } else if (d < b2) {                                                                  \
        b2 = d;                                                                             \
      }                                                                                     \
      if (d < t.col_dist[j]) t.col_dist[j] = d, t.col_best[j] = i;                          \
    }                                                                                       \
    t.best[i] = bi, t.best_dist[i] = b1, t.second_dist[i] = b2;                             \
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
  std::string note;  // why a fitted model was discarded, or OpenCV's error
  cv::Mat model;     // 3x3 CV_64F when inliers > 0
  cv::Mat mask;      // CV_8U, one per match
};

bool finite(const cv::Mat& m) { return !m.empty() && cv::checkRange(m, true, nullptr); }

// Standard deviation, in pixels, of the points across their principal axis:
// about 0 when every point lies on one line.
double thickness(const std::vector<cv::Point2f>& p, const cv::Mat& mask) {
  double n = 0, mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!mask.at<std::uint8_t>(static_cast<int>(i))) continue;
    n += 1, mx += p[i].x, my += p[i].y;
  }
  if (n < 2) return 0;
  mx /= n, my /= n;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!mask.at<std::uint8_t>(static_cast<int>(i))) continue;
    const double dx = p[i].x - mx, dy = p[i].y - my;
    sxx += dx * dx, syy += dy * dy, sxy += dx * dy;
  }
  sxx /= n, syy /= n, sxy /= n;
  const double half_trace = (sxx + syy) / 2;
  const double smaller =
      half_trace - std::sqrt(std::max(0.0, half_trace * half_trace - (sxx * syy - sxy * sxy)));
  return std::sqrt(std::max(0.0, smaller));
}

// Fits H (homography = true) or F with USAC and returns its inlier count, 0
// for a degenerate model. USAC_FAST (OpenCV >= 4.5) instead of classic
// RANSAC: classic RANSAC runs all its iterations on every pair of unrelated
// frames (14 ms for H and 20 ms for F on 60 random matches at 2000
// iterations), USAC_FAST stops early (0.2 ms and 2.4 ms; 0.07 and 0.7 ms at
// 500 iterations). Its local optimisation finds a few more inliers, for true
// and false pairs alike. Its random state is fixed: checks are deterministic.
ModelFit fit_model(bool homography, const std::vector<cv::Point2f>& a,
                   const std::vector<cv::Point2f>& b, double threshold) {
  ModelFit fit;
  try {
    cv::Mat mask;
    const cv::Mat m =
        homography
            ? cv::findHomography(a, b, cv::USAC_FAST, threshold, mask, kMaxIters, kConfidence)
            : cv::findFundamentalMat(a, b, cv::USAC_FAST, threshold, kConfidence, kMaxIters, mask);
    // No model: no non-degenerate sample was found (duplicate or collinear
    // points). 7-point solutions stack up to three 3x3 matrices without a
    // meaningful mask; only a single finite 3x3 model counts.
    if (!finite(m) || m.rows != 3 || m.cols != 3 || mask.empty() || mask.total() != a.size() ||
        mask.type() != CV_8UC1) {
      return fit;
    }
    const int inliers = cv::countNonZero(mask);
    // Inliers on one line (in either image) are no evidence: every F through
    // that line's pencil fits them, and a homography is undetermined. Such a
    // model is discarded rather than trusted (USAC's F accepts 20 collinear
    // matches with 20 inliers).
    const double spread = std::min(thickness(a, mask), thickness(b, mask));
    if (spread < kMinSpread * threshold) {
      fit.note = internal::concat(homography ? "homography" : "fundamental", " discarded: its ",
                                  inliers, " inliers lie on a line");
      return fit;
    }
    // A near-singular H folds the plane onto a line or a point.
    if (homography && std::abs(cv::determinant(m)) <= 1e-8 * std::pow(cv::norm(m), 3)) {
      fit.note = "homography discarded: singular";
      return fit;
    }
    fit.inliers = inliers;
    m.convertTo(fit.model, CV_64F);
    fit.mask = mask;
  } catch (const cv::Exception& e) {
    fit.note = internal::concat(homography ? "homography" : "fundamental", " failed: ", e.err);
  }
  return fit;
}

}  // namespace

// ---- GeometricOptions -----------------------------------------------------------------
const OptionTable<GeometricOptions>& GeometricOptions::fields() {
  using S = GeometricOptions;
  static const OptionTable<S> table = {
      integer_option("max_features", &S::max_features, 16, 20000, "", "ORB keypoints kept per frame"),
      integer_option("min_side", &S::min_side, 0, 4096, "pixels",
                     "ORB runs on the image scaled so that its shorter side is at least this "
                     "(0: never upscale)"),
      integer_option("max_side", &S::max_side, 0, 4096, "pixels",
                     "... and at most this (0: never downscale; else >= min_side)"),
      real_option("ratio", &S::ratio, 0.0, 1.0, true, "",
                  "Lowe's ratio test: a match is kept when best < ratio * second best distance"),
      real_option("ransac_threshold", &S::ransac_threshold, 0.0, 100.0, true, "pixels",
                  "RANSAC reprojection threshold in the working-size image"),
      integer_option("min_inliers", &S::min_inliers, 8, 10000, "",
                     "a candidate is accepted when the better model (F or H) has this many "
                     "inliers"),
      real_option("min_inlier_ratio", &S::min_inlier_ratio, 0.0, 1.0, false, "",
                  "... and they are at least this fraction of the matches"),
  };
  return table;
}

void GeometricOptions::check() const {
  check_options(fields(), *this, "verification.geometric");
  if (max_side > 0 && min_side > max_side) {
    internal::throw_invalid("verification.geometric.min_side = ", min_side,
                            " is above verification.geometric.max_side = ", max_side,
                            ": the working size needs min_side <= max_side (or max_side 0)");
  }
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
      scales_(other.scales_),
      orb_(std::make_unique<Orb>(other.options_)) {}

GeometricVerifier& GeometricVerifier::operator=(const GeometricVerifier& other) {
  if (this != &other) *this = GeometricVerifier(other);
  return *this;
}

void GeometricVerifier::compute(const GrayImage& image, std::vector<float>& points,
                                std::vector<std::uint8_t>& descriptors) const {
  if (image.empty() || image.width < 0 || image.height < 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * image.height) {
    internal::throw_invalid("GeometricVerifier::add: image ", image.width, "x", image.height,
                            " with ", image.pixels.size(), " pixels is empty or inconsistent");
  }
  // A header on the caller's pixels: OpenCV only reads them.
  const cv::Mat gray(image.height, image.width, CV_8UC1,
                     const_cast<std::uint8_t*>(image.pixels.data()));
  cv::Mat work = gray;
  double sx = 1, sy = 1;  // working pixels per original pixel, per axis
  const double scale = working_scale(image.width, image.height);
  if (scale != 1) {
    const int w = std::max(1, static_cast<int>(std::lround(image.width * scale)));
    const int h = std::max(1, static_cast<int>(std::lround(image.height * scale)));
    cv::resize(gray, work, cv::Size(w, h), 0, 0, scale > 1 ? cv::INTER_LINEAR : cv::INTER_AREA);
    sx = static_cast<double>(w) / image.width;
    sy = static_cast<double>(h) / image.height;
  }

  std::vector<cv::KeyPoint> keypoints;
  cv::Mat found;
  try {
    orb_->orb->detectAndCompute(work, cv::noArray(), keypoints, found);
  } catch (const cv::Exception&) {
    // ORB has nothing to say about this image (e.g. smaller than its border):
    // the frame is kept with no keypoints and every check against it rejects.
    keypoints.clear();
    found.release();
  }
  const int n = found.empty() ? 0 : std::min<int>(found.rows, keypoints.size());
  if (n > 0 && (found.type() != CV_8UC1 || found.cols != kOrbBytes)) {
    internal::throw_invalid("GeometricVerifier::add: unexpected ORB descriptor layout");
  }
  points.resize(2 * static_cast<std::size_t>(n));
  descriptors.resize(static_cast<std::size_t>(n) * kOrbBytes);
  for (int i = 0; i < n; ++i) {
    // cv::resize maps pixel centres: x_up + 0.5 = (x + 0.5) * sx.
    points[2 * i] = static_cast<float>((keypoints[i].pt.x + 0.5) / sx - 0.5);
    points[2 * i + 1] = static_cast<float>((keypoints[i].pt.y + 0.5) / sy - 0.5);
    const std::uint8_t* row = found.ptr<std::uint8_t>(i);
    std::copy(row, row + kOrbBytes, descriptors.begin() + static_cast<std::ptrdiff_t>(i) * kOrbBytes);
  }
}

void GeometricVerifier::add(const GrayImage& image) {
  std::vector<float> points;
  std::vector<std::uint8_t> descriptors;
  compute(image, points, descriptors);
  add_features(points, descriptors, image.width, image.height);
}

double GeometricOptions::working_scale(int width, int height) const {
  const int shorter = std::min(width, height);
  const int longer = std::max(width, height);
  if (shorter <= 0) return 1;
  double scale = 1;
  if (shorter < min_side) {
    scale = static_cast<double>(min_side) / shorter;
  } else if (max_side > 0 && shorter > max_side) {
    scale = static_cast<double>(max_side) / shorter;
  }
  // Cap the longer side so that a thin strip is not blown up to gigabytes.
  if (scale > 1) scale = std::max(1.0, std::min(scale, static_cast<double>(kMaxImageSide) / longer));
  return scale;
}

double GeometricVerifier::working_scale(int width, int height) const {
  return options_.working_scale(width, height);
}

void GeometricVerifier::remove_last() {
  if (size() == 0) internal::throw_invalid("GeometricVerifier::remove_last: no frame was added");
  offsets_.pop_back();
  const auto n = static_cast<std::size_t>(offsets_.back());
  points_.resize(2 * n);
  descriptors_.resize(n * kOrbBytes);
  scales_.pop_back();
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
    nearest(descriptors_.data() + qo * kOrbBytes, qn,
            descriptors_.data() + co * kOrbBytes, cn, t);
    for (int i = 0; i < qn; ++i) {
      const int j = t.best[i];
      if (j == kNoMatch || t.col_best[j] != i) continue;  // not mutual
      // Lowe's ratio test; with one candidate keypoint the second best is
      // INT_MAX and the test passes.
      if (!(t.best_dist[i] < options_.ratio * t.second_dist[i])) continue;
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
  // The threshold is in working-size pixels; the points are in original ones.
  const double threshold =
      options_.ransac_threshold / scales_[static_cast<std::size_t>(query)];
  const ModelFit h = fit_model(true, a, b, threshold);
  const ModelFit f = fit_model(false, a, b, threshold);
  const bool use_h = h.inliers >= f.inliers;
  const ModelFit& best = use_h ? h : f;
  check.inliers = best.inliers;
  const bool enough = best.inliers >= options_.min_inliers;
  const bool dense = best.inliers >= options_.min_inlier_ratio * check.matches;
  check.accepted = enough && dense;
  if (best.inliers == 0) {
    std::string notes = h.note;
    if (!f.note.empty()) notes += (notes.empty() ? "" : "; ") + f.note;
    check.reason = internal::concat("no model fitted to ", check.matches, " matches",
                                    notes.empty() ? " (degenerate points)" : ": " + notes);
  } else {
    check.model = use_h ? "homography" : "fundamental";
    // The geometry, for the caller's relative pose: the matches (moved, they
    // are not needed any more) and the better model.
    auto g = std::make_shared<LoopGeometry>();
    g->model = check.model;
    for (int k = 0; k < 9; ++k) g->matrix[static_cast<std::size_t>(k)] = best.model.at<double>(k / 3, k % 3);
    g->query_points.reserve(2 * a.size());
    g->candidate_points.reserve(2 * b.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
      g->query_points.insert(g->query_points.end(), {a[k].x, a[k].y});
      g->candidate_points.insert(g->candidate_points.end(), {b[k].x, b[k].y});
    }
    g->inliers.assign(best.mask.ptr<std::uint8_t>(0), best.mask.ptr<std::uint8_t>(0) + best.mask.total());
    for (std::uint8_t& v : g->inliers) v = v ? 1 : 0;
    check.geometry = std::move(g);
    check.reason = internal::concat(
        check.model, ": ", check.inliers, " inliers of ", check.matches, " matches ",
        enough ? ">=" : "<", " ", options_.min_inliers,
        dense ? "" : internal::concat(", below ", options_.min_inlier_ratio, " of the matches"));
  }
  check.ms = ms_since(start);
  return check;
}

void GeometricVerifier::features(std::int64_t frame, std::vector<float>& points,
                                 std::vector<std::uint8_t>& descriptors) const {
  const int n = keypoints(frame);  // throws InvalidArgument for ids not added
  const auto begin = static_cast<std::size_t>(offsets_[static_cast<std::size_t>(frame)]);
  points.assign(points_.begin() + 2 * begin, points_.begin() + 2 * (begin + n));
  descriptors.assign(descriptors_.begin() + begin * kOrbBytes,
                     descriptors_.begin() + (begin + n) * kOrbBytes);
}

void GeometricVerifier::add_features(const std::vector<float>& points,
                                     const std::vector<std::uint8_t>& descriptors, int width,
                                     int height) {
  if (width <= 0 || height <= 0) {
    internal::throw_invalid("GeometricVerifier::add_features: image size ", width, "x", height);
  }
  const std::size_t n = points.size() / 2;
  if (points.size() != 2 * n || descriptors.size() != n * kOrbBytes) {
    internal::throw_invalid("GeometricVerifier::add_features: ", points.size(), " coordinates and ",
                            descriptors.size(), " descriptor bytes do not describe whole keypoints (",
                            "2 coordinates and ", kOrbBytes, " bytes each)");
  }
  for (const float v : points) {
    if (!std::isfinite(v)) internal::throw_invalid("GeometricVerifier::add_features: coordinate ", v);
  }
  const std::size_t old_points = points_.size(), old_descriptors = descriptors_.size();
  const std::size_t old_frames = scales_.size();
  try {
    points_.insert(points_.end(), points.begin(), points.end());
    descriptors_.insert(descriptors_.end(), descriptors.begin(), descriptors.end());
    scales_.push_back(static_cast<float>(working_scale(width, height)));
    offsets_.push_back(offsets_.back() + static_cast<std::int64_t>(n));
  } catch (...) {
    points_.resize(old_points);
    descriptors_.resize(old_descriptors);
    scales_.resize(old_frames);
    throw;
  }
}

}  // namespace lsgd
