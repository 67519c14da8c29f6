// Verification stages: the detector's extension point for checking loop
// candidates after the search (beyond the paper). A stage is a class
// implementing VerificationStage, registered by name in src/stage.cc (the one
// table of built-in stages) or by register_verification_stage();
// VerificationOptions::stages lists the stages a detector runs, chosen once
// when it is made. The built-in stages:
// - "temporal" (lsgd/stages/temporal.h): the agreement gate of sequence
//   consistency (the sequence scores themselves are appearance evidence,
//   evidence.h, which the temporal stage switches on);
// - "geometric" (lsgd/stages/geometric.h): ORB + RANSAC confirmation.
// How verdicts become the loop decision is decision.h's (LoopDecision).
// docs/design.md, "Add a verification stage", is the recipe.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lsgd/frame_store.h"
#include "lsgd/image.h"
#include "lsgd/loop_geometry.h"
#include "lsgd/search.h"
#include "lsgd/state.h"
#include "lsgd/verification.h"

namespace lsgd {

// kTemporalStage, kGeometricStage: the built-in stages' names (verification.h).

// The query as a stage sees it, once per frame before any check.
struct StageQuery {
  std::int64_t frame;  // its id (== store.size(): stored after the stages ran)
  // Its gray image; empty when the frame came described (Detector::
  // process(const FrameDescription&)): begin_described() has its record instead.
  const GrayImage& gray;
  const FrameStore& store;
  DescriptorView descriptor;  // as stored
  int width = 0;   // the frame's size (also when gray is empty)
  int height = 0;
};

// One stage's verdict on one candidate.
struct StageCheck {
  bool accepted = false;
  // How strongly a confirmation holds (geometric: inliers); -1 when the
  // stage has no such measure. The decision's continuity rule reads it.
  double support = -1;
  std::string reason;  // e.g. "3 of 3 previous queries agree" or "12 inliers < 20"
  double ms = 0;
  // What the stage fitted, when it fits a model (null otherwise, or when no
  // model could be fitted); Result::geometry carries the reported candidate's.
  std::shared_ptr<const LoopGeometry> geometry;
};

class VerificationStage : public Stateful {
 public:
  enum class Role {
    // Examined on the best verification.max_candidates candidates in rank
    // order; a rejected candidate is never reported.
    kGate,
    // Examined on the candidates the gates let through, in the order of the
    // score each could reach, only while that score could reach the
    // threshold; the first candidate every confirming stage accepts is
    // reported and earns decision.geometric_bonus (decision.h).
    kConfirm,
  };
  virtual Role role() const = 0;
  // False when the stage's options leave it nothing to check (temporal with
  // agree = 0): it gives no verdicts, but begin() and end() still run.
  virtual bool examines() const { return true; }
  // Called once per frame before any check (geometric: computes the frame's
  // features). Throws only for a frame it cannot take, before changing.
  virtual void begin(const StageQuery& query) { (void)query; }
  // The verdict on candidate `candidate` of query `query` (after begin()).
  virtual StageCheck check(std::int64_t query, const Candidate& candidate) = 0;
  // Called once per frame after the decision, with the query's candidates
  // best first (temporal: remembers its best place).
  virtual void end(std::int64_t query, const std::vector<Candidate>& candidates) {
    (void)query, (void)candidates;
  }
  // A query that is not stored (Detector::query()): discard() is called
  // instead of end() and forgets whatever begin() kept of it, so that the
  // stage is as it was before begin(). answers_queries() says the stage can
  // do that; by default, a stage without per-frame state (has_state()).
  // Detector::query() refuses (InvalidArgument naming the stage) to run one
  // that cannot.
  virtual bool answers_queries() const { return !has_state(); }
  virtual void discard(std::int64_t query) { (void)query; }

  // A frame described apart from the map (Detector::describe_frame(): a
  // robot describes its frames, the map's process takes the descriptions).
  // describes(): the stage takes such frames; what begin() needs of the
  // image, describe() writes into the frame's record, and begin_described()
  // reads it back (with query.gray empty). Detector::process() and query()
  // of a FrameDescription refuse (InvalidArgument naming the stage) a stage
  // that does not describe. By default a stage does not: an application's
  // begin() may read the image.
  virtual bool describes() const { return false; }
  // Writes what begin() would take from `gray` (nothing by default); changes nothing.
  virtual void describe(const GrayImage& gray, StateWriter& out) const { (void)gray, (void)out; }
  // Checks a record describe() wrote (InvalidArgument "<what>: ..." for one
  // begin_described() cannot take), before the frame changes anything.
  virtual void check_description(StateReader record) const { record.finish(); }
  // begin() of a described frame, from its checked record.
  virtual void begin_described(const StageQuery& query, StateReader record) {
    record.finish();
    begin(query);
  }
};

// A registered stage.
struct StageType {
  const char* name;
  const char* summary;  // one line, for help texts
  std::unique_ptr<VerificationStage> (*make)(const VerificationOptions& options);
  // Its own options (lsgd/options.h): verification.<name>.<option>, when
  // the stage runs; make() reads them with VerificationOptions::own_integer()
  // and the like.
  std::vector<OwnOption> options = {};
};

// Every registered stage, in registration order: the built-in ones first.
std::vector<StageType> verification_stage_types();
// Registers another stage (an application's own check), usable by name in
// VerificationOptions::stages from then on; call it before the detectors
// that use it are made. InvalidArgument for a missing name, summary or make
// function, a name already registered, "none", or an own option that is not
// complete (as register_search_mode(); a stage with options may not be
// named as a verification option: "stages"); thread-safe.
void register_verification_stage(const StageType& type);
// The registered stage named `name` (InvalidArgument naming it and the
// registered ones when there is none).
StageType find_verification_stage(const std::string& name);
// "temporal, geometric": the names, for messages and help texts.
std::string verification_stage_names();
// Throws InvalidArgument naming `name` and the registered stages unless it is one.
void check_verification_stage(const std::string& name);
// The stages options.stages names, in that order, made with `options`.
std::vector<std::unique_ptr<VerificationStage>> make_stages(const VerificationOptions& options);

}  // namespace lsgd
