// Options of the verification stages that run after the candidate search
// (beyond the paper), so that a reported loop can be trusted by a SLAM map
// (the stages themselves: lsgd/stage.h). Each is switchable; with none
// enabled the detector is the faithful method (its ranking; the loop decision
// is decision.h's).
//
// - temporal (sequence consistency): every candidate is scored by its
//   sequence evidence, the mean standardised similarity along the diagonal
//   over `frames` and `long_frames` frames, standardised against every other
//   place the query could be (evidence.h); candidates are the best distinct
//   places by that score (exhaustive search) or the search's candidates moved
//   within +-tolerance frames to their best diagonal (dynamic nodes).
//   Optionally (agree > 0) a candidate is accepted only when the previous
//   `agree` queries were placed on consecutive places (query i - t's best
//   place within tolerance + 1 of j - t).
// - geometric: ORB features matched between the query and the candidate,
//   F and H fitted with RANSAC, accepted on the inlier count (geometric.h);
//   its verdict adds to the loop's score or removes the candidate (decision.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lsgd/geometric.h"
#include "lsgd/search.h"

namespace lsgd {

struct TemporalOptions {
  // Sequence length: the query and the frames-1 frames before it, [1, 100]
  // (docs/results.md has the sweeps behind 16 and 48).
  int frames = 16;
  // Realignment: a candidate moves within +-tolerance frames to its
  // best-aligned diagonal; also the slack of the agreement check. [0, 100].
  int tolerance = 2;
  // Previous queries that must agree on consecutive places, [0, 100] (0: no
  // gate). Off by default: the decision's continuity (decision.h) rewards
  // agreement instead of requiring it (docs/results.md).
  int agree = 0;
  // Second, longer sequence, [0, 1000] frames (0: off; else > frames): the
  // score is the mean of the sequence scores over `frames` and over
  // `long_frames` frames, so a long consistent history counts while a short
  // revisit still scores on its first frames. Memory: long_frames rows of 4
  // bytes per stored frame (exhaustive search).
  int long_frames = 48;
  // Places (issue 32, lsgd/places.h): the block contrast of the frames'
  // gradient-orientation signatures at which a new place begins; a candidate
  // must then stand out from its own place and from the whole map
  // (evidence.h). 0: one place (the whole map's statistics, as before).
  // 1.1: chosen by leaving one sequence out (docs/results.md, "Places found
  // from the frames"): no real sequence here reaches 1.01, every cut between
  // two environments of scripts/mixed_map.py's maps 1.24 or more.
  double place_cut = 1.1;
  void check() const;
  static const OptionTable<TemporalOptions>& fields();  // lsgd/options.h
};

// Names of the built-in stages (lsgd/stage.h has the registry).
inline constexpr const char* kTemporalStage = "temporal";
inline constexpr const char* kGeometricStage = "geometric";

struct VerificationOptions {
  // The stages run after the search, by registered name (lsgd/stage.h), kept
  // in registration order. Default: both built-in stages.
  // - temporal, sequence evidence: docs/results.md: it raises R@1 and the
  //   loops declared on every sequence measured.
  // - geometric, ORB + RANSAC. Appearance alone cannot separate a revisit
  //   from a look-alike place on every camera; geometry can (docs/results.md).
  //   Costs ORB on every frame (~1.5-5 ms at the default working size) and a
  //   check (~0.5 ms) for each candidate that could become a loop.
  std::vector<std::string> stages = {kTemporalStage, kGeometricStage};
  // Candidates examined best first; the first one that no enabled stage
  // rejects is reported. [1, 100]; at most search.top_n are available.
  int max_candidates = 3;
  TemporalOptions temporal_options;    // used with the temporal stage
  GeometricOptions geometric_options;  // used with the geometric stage
  // The options registered stages declare (StageType::options), keys
  // "<stage>.<name>" (verification.<stage>.<name> in DetectorOptions), set
  // through the option table like any other. A stage reads its own in its
  // make function with own_integer("<stage>", "name") and the like: the
  // value set, or the declared default (InvalidArgument for an option the
  // stage does not declare with that kind).
  OwnOptionValues own;
  std::int64_t own_integer(const std::string& stage, const std::string& name) const;
  double own_real(const std::string& stage, const std::string& name) const;
  std::string own_choice(const std::string& stage, const std::string& name) const;
  // True when `stage` is one of `stages`.
  bool has(const std::string& stage) const;
  void check() const;
  // Built again after register_verification_stage() (a new stage's options).
  static const OptionTable<VerificationOptions>& fields();  // lsgd/options.h
};

// Sets options.stages from "none" or a comma-separated list of registered
// stages ("temporal,geometric", "geometric", ...; each at most once, any
// order). Throws InvalidArgument naming an unknown or repeated stage.
void parse_verification_stages(const std::string& text, VerificationOptions& options);
// The stages as that text: "temporal,geometric", or "none".
std::string verification_stages(const VerificationOptions& options);

// The verdict of one stage on one candidate.
struct StageVerdict {
  std::int64_t candidate = -1;
  std::string stage;  // "temporal" or "geometric"; "decision" for a stay (DecisionOptions::stay_z)
                      // or a contradicted continuation (DecisionOptions::contradiction)
  bool accepted = false;
  std::string reason;  // e.g. "3 of 3 previous queries agree" or "12 inliers < 20"
  double ms = 0;
};

}  // namespace lsgd
