// The geometric stage (verification.stages "geometric"): ORB features matched
// between the query and the candidate, F and H fitted with RANSAC, accepted
// on the inlier count (GeometricVerifier, geometric.h). It confirms: its
// verdict adds decision.geometric_bonus to the loop's score or removes the
// candidate (decision.h). Its state: every frame's ORB features.
#pragma once

#include <memory>

#include "lsgd/geometric.h"
#include "lsgd/stage.h"

namespace lsgd {

std::unique_ptr<VerificationStage> make_geometric_stage(const VerificationOptions& options);

}  // namespace lsgd
