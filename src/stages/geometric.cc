#include "lsgd/stages/geometric.h"

#include <algorithm>
#include <cmath>

#include "internal/check.h"

namespace lsgd {
namespace {

// x, y as float32, then the ORB descriptor.
constexpr std::size_t kFeatureBytes = 2 * sizeof(float) + kOrbBytes;

class GeometricStage final : public VerificationStage {
 public:
  explicit GeometricStage(const GeometricOptions& options) : verifier_(options) {}
  const char* name() const override { return kGeometricStage; }
  Role role() const override { return Role::kConfirm; }

  void begin(const StageQuery& query) override { verifier_.add(query.gray); }
  // begin() added the query's features: they go again.
  bool answers_queries() const override { return true; }
  void discard(std::int64_t) override { verifier_.remove_last(); }

  // A described frame's record is its features, as save_frame() writes them.
  bool describes() const override { return true; }
  void describe(const GrayImage& gray, StateWriter& out) const override {
    verifier_.compute(gray, points_, orb_);
    out.put_f32s(points_.data(), points_.size());
    out.put_bytes(orb_.data(), orb_.size());
  }
  void check_description(StateReader in) const override { check_features(in); }
  void begin_described(const StageQuery& query, StateReader in) override {
    read(in);
    verifier_.add_features(points_, orb_, query.width, query.height);
  }

  StageCheck check(std::int64_t query, const Candidate& candidate) override {
    const GeometricCheck c = verifier_.verify(query, candidate.frame);
    return {c.accepted, static_cast<double>(c.inliers), c.reason, c.ms, c.geometry};
  }

  // State, version 1: the frame's n keypoints as n * 2 float32 (x, y in
  // pixels of the original image), then n * 32 bytes of ORB descriptors.
  bool has_state() const override { return true; }
  void save_frame(std::int64_t frame, StateWriter& out) const override {
    verifier_.features(frame, points_, orb_);
    out.put_f32s(points_.data(), points_.size());
    out.put_bytes(orb_.data(), orb_.size());
  }
  void check_frame(std::int64_t frame, int, int, std::uint32_t version,
                   StateReader in) const override {
    check_state_version(in.what(), name(), version, 1);
    if (frame != verifier_.size()) {
      internal::throw_invalid(in.what(), ": frame ", frame, " restored after ", verifier_.size(),
                              " frames");
    }
    check_features(in);
  }
  void restore_frame(std::int64_t, int width, int height, std::uint32_t, StateReader in) override {
    read(in);
    verifier_.add_features(points_, orb_, width, height);
  }
  // Its records name no other frame: restore_frame() restores them after a forget.
  bool forgets() const override { return true; }

  const GeometricVerifier& verifier() const { return verifier_; }

 private:
  void read(StateReader& in) const {
    const std::size_t n = in.remaining() / kFeatureBytes;
    points_.resize(2 * n);
    in.get_f32s(points_.data(), points_.size());
    const std::uint8_t* orb = in.get_bytes(n * kOrbBytes);
    orb_.assign(orb, orb + n * kOrbBytes);
    in.finish();
  }

  // A record of features (a stored frame's or a description's) add_features() takes.
  void check_features(StateReader& in) const {
    if (!in.present()) internal::throw_invalid(in.what(), ": there is no record of its features");
    if (in.remaining() % kFeatureBytes != 0) {
      internal::throw_invalid(in.what(), ": ", in.remaining(), " bytes of features are not a "
                              "multiple of ", kFeatureBytes);
    }
    read(in);
    if (!std::all_of(points_.begin(), points_.end(), [](float v) { return std::isfinite(v); })) {
      internal::throw_invalid(in.what(), ": a keypoint coordinate is not finite");
    }
  }

  GeometricVerifier verifier_;
  mutable std::vector<float> points_;  // scratch of save_frame() and restore
  mutable std::vector<std::uint8_t> orb_;
};

}  // namespace

std::unique_ptr<VerificationStage> make_geometric_stage(const VerificationOptions& options) {
  return std::make_unique<GeometricStage>(options.geometric_options);
}

}  // namespace lsgd
