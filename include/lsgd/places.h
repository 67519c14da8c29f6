// The places of a map (issue 32): where one environment ends and another
// begins, found from the frames themselves.
//
// A map made of several places (two buildings, a street and a corridor, a
// fleet's sessions) cannot standardise a query's scores against one null:
// a corridor query scores every corridor frame above every street frame, so
// against the whole map its true revisit stands out from nothing
// (docs/results.md, "Each candidate against its own place"). With the places
// known, the evidence standardises each candidate against the query's
// statistics over the candidate's own place (evidence.h).
//
// The detector's gray-level histograms cannot find the places (two places'
// histograms are as alike as two stretches of one route); a descriptor of
// structure can. Each frame gets a small signature: the frame at 160 x 120,
// 4 x 4 cells, a histogram of 8 gradient orientations per cell weighted by
// the gradient's magnitude, each cell normalised (128 bytes). A place begins
// at frame c when the block contrast
//   (within - cross) / (1 - within)
// of the kBlock frames before c and the kBlock frames from c on (within: the
// mean similarity of the frames inside each block, cross: between the two)
// reaches the threshold, is the highest of c - 1, c, c + 1, and the place
// before has at least kMinPlaceFrames frames. So a place beginning at c is
// found when frame c + kPlaceBlock (its ninth) is stored.
//
// A cut is found late, so the decision also asks of each frame whether its
// view leapt away from the frames just before it (a scene cut as it happens,
// or a sharp turn): its leap is the contrast of its signature against the
// kPlaceBlock frames before it, (within - cross) / (1 - within) with within
// the mean similarity of those frames to each other and cross their mean
// similarity to it. No loop is continued across a frame whose leap reaches
// decision.leap (decision.h).
#pragma once

#include <cstdint>
#include <vector>

#include "lsgd/image.h"
#include "lsgd/state.h"

namespace lsgd {

constexpr int kSignatureBytes = 128;  // 4 x 4 cells x 8 orientations
constexpr int kPlaceBlock = 8;        // frames on each side of a cut
// Memory a map keeps per frame for its places (PlaceCuts): the signature,
// the block contrast and the cut found then (the memory model of
// estimated_map_bytes()).
constexpr std::int64_t kPlaceBytesPerFrame = kSignatureBytes + 17;
// The fewest frames of a place: a place that could not calibrate its own
// statistics (kMinCalibration) is no place.
constexpr std::int64_t kMinPlaceFrames = 32;

// The signature of a frame (kSignatureBytes, each cell's 8 bins summing to
// about 255).
std::vector<std::uint8_t> place_signature(const GrayImage& gray);
// 1 - half the mean L1 distance of the cells' normalised histograms: 1 for
// equal signatures, 0 for cells with nothing in common.
double signature_similarity(const std::uint8_t* a, const std::uint8_t* b);
// The block contrast of a cut at `c` from the signatures of frames c -
// kPlaceBlock .. c + kPlaceBlock - 1 (`block`, 2 kPlaceBlock pointers, in
// frame order); -infinity when one is missing (nullptr).
double block_contrast(const std::uint8_t* const* block);

// The leap of a frame (`frame`'s signature) from the kPlaceBlock frames
// before it (`before`, kPlaceBlock pointers): the block contrast of one frame
// (the comment at the top); -infinity when one is missing (nullptr).
double leap_contrast(const std::uint8_t* frame, const std::uint8_t* const* before);

// The first frame of the place holding `frame`, given the first frames of
// the places after the first (`cuts`, ascending: PlaceCuts::cuts()); 0 in
// the first place.
std::int64_t place_start(const std::vector<std::int64_t>& cuts, std::int64_t frame);
// The last frame of the place holding `frame` (INT64_MAX in the last place).
std::int64_t place_end(const std::vector<std::int64_t>& cuts, std::int64_t frame);

// The places found so far, and every frame's signature (Stateful "places":
// each frame's record is its signature and the cut found when it was stored,
// so a restored map has the places it had).
class PlaceCuts : public Stateful {
 public:
  // threshold: the block contrast a cut needs (verification.temporal.place_cut);
  // 0: off (one place, nothing kept).
  explicit PlaceCuts(double threshold);
  bool enabled() const { return threshold_ > 0; }
  // Frame `frame` (== the frames added so far) is stored with `signature`
  // (kSignatureBytes, or empty: a frame without one, which no cut spans).
  // Returns the first frame of a place found now, -1 if none.
  std::int64_t add(std::int64_t frame, const std::vector<std::uint8_t>& signature);
  // The first frames of the places after the first, ascending.
  const std::vector<std::int64_t>& cuts() const { return cuts_; }
  std::int64_t size() const { return static_cast<std::int64_t>(found_.size()); }
  // The block contrast at c, computed once frame c + kPlaceBlock - 1 was
  // added (-infinity before, or when a signature is missing).
  double contrast(std::int64_t c) const;
  // The leap of stored frame `frame` from the kPlaceBlock frames before it,
  // computed from their signatures (leap_contrast; -infinity for the first
  // kPlaceBlock frames, a frame without a signature or one after such a frame).
  double leap(std::int64_t frame) const;
  // The leap of a frame about to be added (or a query not stored) with
  // `signature` from the last kPlaceBlock frames stored.
  double leap(const std::vector<std::uint8_t>& signature) const;

  const char* name() const override { return "places"; }
  bool has_state() const override { return enabled(); }
  void save_frame(std::int64_t frame, StateWriter& out) const override;
  void check_frame(std::int64_t frame, int width, int height, std::uint32_t version,
                   StateReader in) const override;
  void restore_frame(std::int64_t frame, int width, int height, std::uint32_t version,
                     StateReader in) override;
  bool forgets() const override { return true; }
  void restore_renumbered(std::int64_t frame, int width, int height, std::uint32_t version,
                          StateReader in, const FrameRenumbering& renumbered) override;

 private:
  void push(const std::vector<std::uint8_t>& signature);
  // Frame `frame`'s signature (nullptr: none).
  const std::uint8_t* signature(std::int64_t frame) const;
  // The leap of signature `s` as frame `frame`, from the frames before it.
  double leap_at(std::int64_t frame, const std::uint8_t* s) const;
  void record_cut(std::int64_t frame, std::int64_t cut);

  double threshold_ = 0;
  std::vector<std::uint8_t> signatures_;  // kSignatureBytes per frame
  std::vector<bool> has_signature_;
  std::vector<double> contrast_;          // by frame c: the block contrast of a cut at c
  std::vector<std::int64_t> found_;       // by frame: the cut found when it was stored, -1
  std::vector<std::int64_t> cuts_;
};

}  // namespace lsgd
