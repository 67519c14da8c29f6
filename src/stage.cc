#include "lsgd/stage.h"

#include <algorithm>

#include "internal/check.h"
#include "internal/option_tables.h"
#include "internal/registry.h"
#include "lsgd/stages/geometric.h"
#include "lsgd/stages/temporal.h"

namespace lsgd {
namespace {

// The registered stages: a built-in stage is one line here (and its file
// pair in src/stages/, include/lsgd/stages/); others come from
// register_verification_stage(). Registration order is the order stages of
// one role run in.
internal::Registry<StageType>& registry() {
  static internal::Registry<StageType> stages(
      "verification stage",
      {
          {kTemporalStage, "sequence evidence; the agreement gate when temporal.agree > 0",
           make_temporal_stage},
          {kGeometricStage, "ORB + RANSAC confirmation", make_geometric_stage},
      });
  return stages;
}

}  // namespace

std::vector<StageType> verification_stage_types() { return registry().entries(); }

void register_verification_stage(const StageType& type) {
  registry().add(internal::with_checked_options<VerificationOptions>(type, "register_verification_stage",
                                                                     "stage", "verification"),
                 "register_verification_stage", "none");
  internal::count_registration();
}

StageType find_verification_stage(const std::string& name) { return registry().find(name); }

std::string verification_stage_names() { return registry().names(); }

void check_verification_stage(const std::string& name) { registry().find(name); }

std::vector<std::unique_ptr<VerificationStage>> make_stages(const VerificationOptions& options) {
  options.check();
  std::vector<std::unique_ptr<VerificationStage>> stages;
  for (const StageType& type : verification_stage_types()) {
    if (!options.has(type.name)) continue;
    std::unique_ptr<VerificationStage> stage = type.make(options);
    if (!stage || std::string(stage->name()) != type.name) {
      internal::throw_invalid("verification stage '", type.name, "' made ",
                              stage ? internal::concat("a stage named '", stage->name(), "'")
                                    : std::string("no stage"));
    }
    stages.push_back(std::move(stage));
  }
  return stages;
}

}  // namespace lsgd
