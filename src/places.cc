#include "lsgd/places.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "internal/check.h"

namespace lsgd {
namespace {

constexpr int kWidth = 160, kHeight = 120;  // the frame the signature is computed on
constexpr int kGrid = 4, kOrientations = 8;
constexpr double kNone = -std::numeric_limits<double>::infinity();

}  // namespace

std::vector<std::uint8_t> place_signature(const GrayImage& gray) {
  if (gray.empty()) internal::throw_invalid("place_signature: an empty image");
  const cv::Mat in(gray.height, gray.width, CV_8UC1, const_cast<std::uint8_t*>(gray.pixels.data()));
  // Area averaging in two steps: by whole factors first (OpenCV's fast
  // path; the last fx - 1 columns and fy - 1 rows left out), then the rest
  // on a frame at most twice the size (a 1241 x 376 frame: 0.79 ms in one
  // step, 0.45 ms in two, lsgd.place_signature from Python).
  const int fx = std::max(1, gray.width / kWidth), fy = std::max(1, gray.height / kHeight);
  cv::Mat whole = in, small;
  if (fx > 1 || fy > 1) {
    const cv::Mat cropped = in(cv::Rect(0, 0, gray.width / fx * fx, gray.height / fy * fy));
    cv::resize(cropped, whole, cv::Size(gray.width / fx, gray.height / fy), 0, 0, cv::INTER_AREA);
  }
  cv::resize(whole, small, cv::Size(kWidth, kHeight), 0, 0, cv::INTER_AREA);
  // The orientation bin of a gradient without atan2: its orientation (mod pi)
  // is at least k pi / 8 when cos(k pi / 8) gy >= sin(k pi / 8) gx, with the
  // gradient turned into the upper half plane first.
  static const auto bounds = [] {
    std::array<std::array<float, 2>, kOrientations - 1> b{};
    for (int k = 1; k < kOrientations; ++k) {
      b[static_cast<std::size_t>(k - 1)] = {static_cast<float>(std::cos(k * M_PI / kOrientations)),
                                            static_cast<float>(std::sin(k * M_PI / kOrientations))};
    }
    return b;
  }();
  float cells[kGrid * kGrid][kOrientations] = {};
  for (int y = 0; y < kHeight; ++y) {
    const int y0 = std::max(0, y - 1), y1 = std::min(kHeight - 1, y + 1);
    const std::uint8_t* up = small.ptr<std::uint8_t>(y0);
    const std::uint8_t* row = small.ptr<std::uint8_t>(y);
    const std::uint8_t* down = small.ptr<std::uint8_t>(y1);
    const float dy = 1.0f / static_cast<float>(y1 - y0);
    float* cell_row = cells[(y * kGrid / kHeight) * kGrid];
    for (int x = 0; x < kWidth; ++x) {
      const int x0 = std::max(0, x - 1), x1 = std::min(kWidth - 1, x + 1);
      // Central differences, one-sided at the border.
      float gx = static_cast<float>(row[x1] - row[x0]) / static_cast<float>(x1 - x0);
      float gy = static_cast<float>(down[x] - up[x]) * dy;
      if (gx == 0 && gy == 0) continue;
      if (gy < 0 || (gy == 0 && gx < 0)) gx = -gx, gy = -gy;  // orientation, not direction
      int bin = 0;
      for (const auto& [c, sn] : bounds) bin += c * gy >= sn * gx ? 1 : 0;
      cell_row[(x * kGrid / kWidth) * kOrientations + bin] += std::sqrt(gx * gx + gy * gy);
    }
  }
  std::vector<std::uint8_t> out(kSignatureBytes);
  for (int c = 0; c < kGrid * kGrid; ++c) {
    float sum = 0;
    for (const float v : cells[c]) sum += v;
    for (int b = 0; b < kOrientations; ++b) {
      out[static_cast<std::size_t>(c * kOrientations + b)] =
          sum > 0 ? static_cast<std::uint8_t>(std::lround(255.0f * cells[c][b] / sum)) : 0;
    }
  }
  return out;
}

double signature_similarity(const std::uint8_t* a, const std::uint8_t* b) {
  int distance = 0;
  for (int k = 0; k < kSignatureBytes; ++k) distance += std::abs(int{a[k]} - int{b[k]});
  return 1.0 - 0.5 * distance / (255.0 * kGrid * kGrid);
}

std::int64_t place_start(const std::vector<std::int64_t>& cuts, std::int64_t frame) {
  const auto it = std::upper_bound(cuts.begin(), cuts.end(), frame);
  return it == cuts.begin() ? 0 : *(it - 1);
}

std::int64_t place_end(const std::vector<std::int64_t>& cuts, std::int64_t frame) {
  const auto it = std::upper_bound(cuts.begin(), cuts.end(), frame);
  return it == cuts.end() ? std::numeric_limits<std::int64_t>::max() : *it - 1;
}

namespace {

// The summed similarity of every pair of the kPlaceBlock frames `block`.
double pairs_similarity(const std::uint8_t* const* block) {
  double sum = 0;
  for (int a = 0; a < kPlaceBlock; ++a) {
    for (int b = 0; b < a; ++b) sum += signature_similarity(block[a], block[b]);
  }
  return sum;
}

constexpr double kPairs = kPlaceBlock * (kPlaceBlock - 1) / 2.0;

// (within - cross) / (1 - within): how much less alike across than within.
double contrast_of(double within, double cross) { return (within - cross) / std::max(1.0 - within, 1e-9); }

}  // namespace

double block_contrast(const std::uint8_t* const* block) {
  for (int k = 0; k < 2 * kPlaceBlock; ++k) {
    if (block[k] == nullptr) return kNone;
  }
  double cross = 0;
  for (int a = 0; a < kPlaceBlock; ++a) {
    for (int b = 0; b < kPlaceBlock; ++b) cross += signature_similarity(block[kPlaceBlock + a], block[b]);
  }
  const double within = (pairs_similarity(block) + pairs_similarity(block + kPlaceBlock)) / (2 * kPairs);
  return contrast_of(within, cross / (kPlaceBlock * kPlaceBlock));
}

double leap_contrast(const std::uint8_t* frame, const std::uint8_t* const* before) {
  if (frame == nullptr) return kNone;
  for (int k = 0; k < kPlaceBlock; ++k) {
    if (before[k] == nullptr) return kNone;
  }
  double cross = 0;
  for (int a = 0; a < kPlaceBlock; ++a) cross += signature_similarity(frame, before[a]);
  return contrast_of(pairs_similarity(before) / kPairs, cross / kPlaceBlock);
}

PlaceCuts::PlaceCuts(double threshold) : threshold_(threshold) {
  if (!(threshold >= 0) || std::isinf(threshold)) {
    internal::throw_invalid("PlaceCuts: threshold ", threshold, " (0: off, else > 0)");
  }
}

double PlaceCuts::contrast(std::int64_t c) const {
  return c >= 0 && c < static_cast<std::int64_t>(contrast_.size()) ? contrast_[static_cast<std::size_t>(c)]
                                                                    : kNone;
}

const std::uint8_t* PlaceCuts::signature(std::int64_t frame) const {
  const auto f = static_cast<std::size_t>(frame);
  return has_signature_[f] ? signatures_.data() + f * kSignatureBytes : nullptr;
}

double PlaceCuts::leap_at(std::int64_t frame, const std::uint8_t* s) const {
  if (frame < kPlaceBlock || frame > size()) return kNone;
  const std::uint8_t* before[kPlaceBlock];
  for (int k = 0; k < kPlaceBlock; ++k) before[k] = signature(frame - kPlaceBlock + k);
  return leap_contrast(s, before);
}

double PlaceCuts::leap(std::int64_t frame) const {
  return frame >= 0 && frame < size() ? leap_at(frame, signature(frame)) : kNone;
}

double PlaceCuts::leap(const std::vector<std::uint8_t>& signature) const {
  return signature.size() == static_cast<std::size_t>(kSignatureBytes) ? leap_at(size(), signature.data())
                                                                       : kNone;
}

void PlaceCuts::push(const std::vector<std::uint8_t>& signature) {
  if (!signature.empty() && signature.size() != static_cast<std::size_t>(kSignatureBytes)) {
    internal::throw_invalid("PlaceCuts: a signature of ", signature.size(), " bytes, expected ",
                            kSignatureBytes);
  }
  const bool has = !signature.empty();
  has_signature_.push_back(has);
  signatures_.resize(signatures_.size() + kSignatureBytes, 0);
  if (has) std::copy(signature.begin(), signature.end(), signatures_.end() - kSignatureBytes);
  found_.push_back(-1);
  contrast_.push_back(kNone);
  // The frame completes the blocks of a cut at c = frame - kPlaceBlock + 1.
  const std::int64_t frame = size() - 1, c = frame - kPlaceBlock + 1;
  if (c < kPlaceBlock) return;
  const std::uint8_t* block[2 * kPlaceBlock];
  for (int k = 0; k < 2 * kPlaceBlock; ++k) block[k] = this->signature(c - kPlaceBlock + k);
  contrast_[static_cast<std::size_t>(c)] = block_contrast(block);
}

std::int64_t PlaceCuts::add(std::int64_t frame, const std::vector<std::uint8_t>& signature) {
  if (!enabled()) return -1;
  if (frame != size()) {
    internal::throw_invalid("PlaceCuts::add: frame ", frame, " after ", size(), " frames");
  }
  push(signature);
  // A cut at c = frame - kPlaceBlock: its contrast and both neighbours' are known.
  const std::int64_t c = frame - kPlaceBlock;
  const double r = contrast(c);
  const std::int64_t start = cuts_.empty() ? 0 : cuts_.back();
  if (r < threshold_ || r < contrast(c - 1) || !(r > contrast(c + 1)) || c - start < kMinPlaceFrames) {
    return -1;
  }
  record_cut(frame, c);
  return c;
}

void PlaceCuts::record_cut(std::int64_t frame, std::int64_t cut) {
  found_[static_cast<std::size_t>(frame)] = cut;
  cuts_.push_back(cut);
}

void PlaceCuts::save_frame(std::int64_t frame, StateWriter& out) const {
  if (frame < 0 || frame >= size()) internal::throw_invalid("places: frame ", frame, " is not stored");
  const auto f = static_cast<std::size_t>(frame);
  out.put_i64(found_[f]);
  if (has_signature_[f]) out.put_bytes(signatures_.data() + f * kSignatureBytes, kSignatureBytes);
}

void PlaceCuts::check_frame(std::int64_t frame, int, int, std::uint32_t version, StateReader in) const {
  if (!in.present()) return;
  check_state_version(in.what(), name(), version, 1);
  const std::int64_t cut = in.get_i64();
  if (in.remaining() != 0) in.get_bytes(kSignatureBytes);
  in.finish();
  const std::int64_t start = cuts_.empty() ? 0 : cuts_.back();
  if (cut != -1 && (cut < start + kMinPlaceFrames || cut > frame)) {
    internal::throw_invalid(in.what(), ": a place beginning at frame ", cut, " found at frame ", frame,
                            " (the last began at ", start, ")");
  }
}

void PlaceCuts::restore_frame(std::int64_t frame, int width, int height, std::uint32_t version,
                              StateReader in) {
  restore_renumbered(frame, width, height, version, std::move(in), FrameRenumbering::identity());
}

void PlaceCuts::restore_renumbered(std::int64_t frame, int, int, std::uint32_t, StateReader in,
                                   const FrameRenumbering& renumbered) {
  std::vector<std::uint8_t> signature;
  std::int64_t cut = -1;
  if (in.present()) {
    cut = renumbered.after(in.get_i64());
    if (in.remaining() != 0) {
      const std::uint8_t* s = in.get_bytes(kSignatureBytes);
      signature.assign(s, s + kSignatureBytes);
    }
  }
  if (frame != size()) internal::throw_invalid("places: frame ", frame, " restored after ", size());
  push(signature);
  // A place whose first frame was forgotten, or that would now be too short, is none.
  const std::int64_t start = cuts_.empty() ? 0 : cuts_.back();
  if (cut >= start + kMinPlaceFrames && cut <= frame) record_cut(frame, cut);
}

}  // namespace lsgd
