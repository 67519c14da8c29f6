// Tests of the verification stage interface (include/lsgd/verification.h):
// a stage registered by an application runs in the detector through the
// interface alone, and its state travels with the frame's state blob (what
// docs/design.md, "Add a verification stage", promises: one file pair and
// its registration); the state records' helpers. The built-in stages:
// verification_test.cc.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/verification.h"
#include "synthetic/synthetic.h"
#include "test_util.h"
#include "verification_test_support.h"

namespace lsgd {
namespace {

using test::kPlaces;
using test::place;
using test::route_options;

// A gate that rejects candidates with an odd frame id, and remembers for each
// query how many candidates it rejected (its state, version 1).
class EvenFramesOnly final : public VerificationStage {
 public:
  const char* name() const override { return "test-even"; }
  Role role() const override { return Role::kGate; }
  StageCheck check(std::int64_t, const Candidate& c) override {
    const bool even = c.frame % 2 == 0;
    if (!even) ++rejected_now_;
    return {even, -1, even ? "even" : "odd frame", 0.0, nullptr};
  }
  void end(std::int64_t query, const std::vector<Candidate>&) override {
    rejected_.resize(static_cast<std::size_t>(query));
    rejected_.push_back(rejected_now_);
    rejected_now_ = 0;
  }
  bool has_state() const override { return true; }
  void save_frame(std::int64_t frame, StateWriter& out) const override {
    out.put_i64(rejected_.at(static_cast<std::size_t>(frame)));
  }
  void check_frame(std::int64_t, int, int, std::uint32_t version, StateReader in) const override {
    check_state_version(in.what(), name(), version, 1);
    in.get_i64();
    in.finish();
  }
  void restore_frame(std::int64_t frame, int, int, std::uint32_t, StateReader in) override {
    rejected_.resize(static_cast<std::size_t>(frame));
    rejected_.push_back(in.get_i64());
  }

 private:
  std::int64_t rejected_now_ = 0;
  std::vector<std::int64_t> rejected_;
};

void register_test_stage() {
  static const bool once = [] {
    register_verification_stage({"test-even", "rejects odd frames",
                                 [](const VerificationOptions&) -> std::unique_ptr<VerificationStage> {
                                   return std::make_unique<EvenFramesOnly>();
                                 }});
    return true;
  }();
  (void)once;
}

TEST(StageRegistry, ARegisteredStageRunsInTheDetectorThroughTheInterfaceAlone) {
  register_test_stage();
  EXPECT_NE(verification_stage_names().find("temporal, geometric, test-even"), std::string::npos);
  const auto make = [](const VerificationOptions&) -> std::unique_ptr<VerificationStage> {
    return std::make_unique<EvenFramesOnly>();
  };
  EXPECT_THROW(register_verification_stage({"test-even", "again", make}), InvalidArgument);
  EXPECT_THROW(register_verification_stage({"none", "reserved", make}), InvalidArgument);
  EXPECT_THROW(register_verification_stage({"", "no name", make}), InvalidArgument);
  EXPECT_THROW(register_verification_stage({"test-x", "no make", nullptr}), InvalidArgument);

  DetectorOptions o = route_options("temporal");
  parse_verification_stages("test-even,temporal", o.verification);
  EXPECT_EQ(verification_stages(o.verification), "temporal,test-even");
  Detector d(o);
  ASSERT_NE(d.stage("test-even"), nullptr);
  EXPECT_EQ(d.stage(kGeometricStage), nullptr);
  int examined = 0, odd_reported = 0;
  for (int lap = 0; lap < 2; ++lap) {
    for (int p = 0; p < kPlaces; ++p) {
      const Result r = d.process(place(p, lap));
      for (const StageVerdict& v : r.verification) {
        ASSERT_EQ(v.stage, "test-even");
        EXPECT_EQ(v.accepted, v.candidate % 2 == 0);
        ++examined;
      }
      odd_reported += r.best.frame >= 0 && r.best.frame % 2 != 0 ? 1 : 0;
    }
  }
  EXPECT_GT(examined, 50);
  EXPECT_EQ(odd_reported, 0);
}

// With geometry the decision also examines the continuation of the previous
// frame's loop; a registered gate judges it too.
TEST(StageRegistry, ARegisteredGateJudgesTheContinuationToo) {
  register_test_stage();
  DetectorOptions g = route_options("temporal");
  parse_verification_stages("temporal,geometric,test-even", g.verification);
  DetectorOptions plain = g;
  plain.verification.stages = {kTemporalStage, kGeometricStage};
  Detector with(g), without(plain);
  int odd_loops_without = 0, loops = 0;
  for (int lap = 0; lap < 3; ++lap) {
    for (int p = 0; p < kPlaces; ++p) {
      const Result a = with.process(place(p, lap));
      const Result b = without.process(place(p, lap));
      EXPECT_FALSE(a.loop && a.best.frame % 2 != 0) << "query " << a.frame;
      loops += a.loop ? 1 : 0;
      odd_loops_without += b.loop && b.best.frame % 2 != 0 ? 1 : 0;
    }
  }
  EXPECT_GT(loops, 10);
  EXPECT_GT(odd_loops_without, 10);  // the gate had work to do
}

// A registered stage's state travels in the frame's state blob: a detector
// restored from the blobs continues exactly as the original, and one without
// the stage refuses its records.
TEST(StageRegistry, ARegisteredStagesStateIsRestoredAndRefusedWithoutIt) {
  register_test_stage();
  DetectorOptions o = route_options("temporal");
  parse_verification_stages("test-even,temporal", o.verification);
  Detector d(o);
  for (int lap = 0; lap < 2; ++lap) {
    for (int p = 0; p < kPlaces; ++p) d.process(place(p, lap));
  }
  Detector restored(o);
  for (std::int64_t f = 0; f < d.size(); ++f) {
    Descriptor copy;
    const DescriptorView v = d.store().view(f);
    copy.grid = d.store().grid();
    copy.hist.assign(v.hist, v.hist + v.cells * kBins);
    copy.pixels.assign(v.pixels, v.pixels + v.cells);
    restored.restore_frame(d.width(), d.height(), copy, d.frame_state(f));
    EXPECT_EQ(restored.frame_state(f), d.frame_state(f));
  }
  for (int p = 0; p < 10; ++p) {
    const Result a = d.process(place(p, 3));
    const Result b = restored.process(place(p, 3));
    EXPECT_EQ(a.best.frame, b.best.frame);
    EXPECT_EQ(a.best.score, b.best.score);
    EXPECT_EQ(a.verification.size(), b.verification.size());
  }
  // A detector without the stage refuses its records.
  DetectorOptions without = o;
  without.verification.stages = {kTemporalStage};
  Detector other(without);
  Descriptor first;
  first.grid = d.store().grid();
  first.hist.assign(d.store().view(0).hist, d.store().view(0).hist + first.grid.cells() * kBins);
  first.pixels.assign(d.store().view(0).pixels, d.store().view(0).pixels + first.grid.cells());
  EXPECT_NE(test::message_of<InvalidArgument>([&] {
              other.restore_frame(d.width(), d.height(), first, d.frame_state(0));
            }).find("has state of 'test-even', which these options do not have"),
            std::string::npos);
}

// Records of a frame's state blob read back as written; the record helpers
// refuse what they cannot read.
TEST(StateRecords, RoundTripAndBounds) {
  StateWriter w;
  w.put_i64(-5);
  w.put_f64(2.5);
  const float xs[2] = {1.5f, -0.25f};
  w.put_f32s(xs, 2);
  const std::uint8_t raw[3] = {7, 8, 9};
  w.put_bytes(raw, 3);
  const std::vector<std::uint8_t> blob = encode_records({{"a", 1, w.bytes()}, {"b", 3, {}}});
  const std::vector<StateRecord> r = decode_records(blob.data(), blob.size());
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].component, "a");
  EXPECT_EQ(r[1].version, 3u);
  StateReader in(r[0].bytes.data(), r[0].bytes.size(), "a");
  EXPECT_EQ(in.get_i64(), -5);
  EXPECT_EQ(in.get_f64(), 2.5);
  float ys[2] = {};
  in.get_f32s(ys, 2);
  EXPECT_EQ(ys[0], 1.5f);
  EXPECT_EQ(ys[1], -0.25f);
  EXPECT_EQ(in.get_bytes(3)[2], 9);
  EXPECT_NO_THROW(in.finish());
  EXPECT_THROW(in.get_i64(), InvalidArgument);
  StateReader absent("frame 3's x state");
  EXPECT_FALSE(absent.present());
  EXPECT_NE(test::message_of<InvalidArgument>([&] { absent.get_i64(); }).find("frame 3's x state: there is no record"),
            std::string::npos);
  for (std::size_t cut = 0; cut < blob.size(); ++cut) {
    EXPECT_THROW(decode_records(blob.data(), cut), InvalidArgument) << cut;
  }
  EXPECT_THROW(check_state_version("x", "a", 2, 1), InvalidArgument);
  EXPECT_THROW(check_state_version("x", "a", 0, 1), InvalidArgument);
}
}  // namespace
}  // namespace lsgd
