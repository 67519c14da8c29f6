#include "lsgd/verification.h"

#include <algorithm>
#include <cstdlib>
#include <sstream>

#include "internal/check.h"
#include "internal/option_tables.h"
#include "lsgd/stage.h"

namespace lsgd {

const OptionTable<TemporalOptions>& TemporalOptions::fields() {
  using S = TemporalOptions;
  static const OptionTable<S> table = {
      integer_option("frames", &S::frames, 1, 100, "frames",
                     "sequence length: the query and the frames-1 frames before it"),
      integer_option("long_frames", &S::long_frames, 0, 1000, "frames",
                     "second, longer sequence (0: off; else > frames); the score is the mean of "
                     "both"),
      integer_option("tolerance", &S::tolerance, 0, 100, "frames",
                     "realignment radius of a candidate and slack of the agreement gate"),
      integer_option("agree", &S::agree, 0, 100, "queries",
                     "previous queries that must agree on consecutive places (0: no gate)"),
      real_option("place_cut", &S::place_cut, 0.0, 1000.0, false, "",
                  "block contrast of the frames' gradient signatures at which a new place "
                  "begins, each candidate then scored against its own place (0: one place)"),
  };
  return table;
}

void TemporalOptions::check() const {
  check_options(fields(), *this, "verification.temporal");
  if (long_frames != 0 && long_frames <= frames) {
    internal::throw_invalid(
        "verification.temporal.long_frames = ", long_frames,
        " must be 0 (off) or more than verification.temporal.frames = ", frames);
  }
}

namespace {

OptionTable<VerificationOptions> verification_table() {
  using S = VerificationOptions;
  OptionField<S> stages_field;
  stages_field.name = "stages";
  stages_field.kind = OptionKind::kChoice;
  stages_field.list = true;
  stages_field.doc = "verification stages after the search (any order; lsgd/stage.h)";
  stages_field.choices = [] {
    std::vector<std::string> names;
    for (const StageType& t : verification_stage_types()) names.emplace_back(t.name);
    return names;
  };
  stages_field.text = [](const S& s) { return verification_stages(s); };
  stages_field.set_choice = [](S& s, const std::string& text) { parse_verification_stages(text, s); };
  OptionTable<S> t = {
      stages_field,
      integer_option("max_candidates", &S::max_candidates, 1, 100, "",
                     "candidates examined best first; the first no stage rejects is reported"),
  };
  t.back().applies = [](const S& s) { return !s.stages.empty(); };
  t.back().when = "with a stage";
  nest<S, TemporalOptions>(t, "temporal", &S::temporal_options, TemporalOptions::fields(),
                           [](const S& s) { return s.has(kTemporalStage); }, "with the temporal stage");
  nest<S, GeometricOptions>(t, "geometric", &S::geometric_options, GeometricOptions::fields(),
                            [](const S& s) { return s.has(kGeometricStage); }, "with the geometric stage");
  for (const StageType& type : verification_stage_types()) {
    const std::string name = type.name;
    add_own_options<S>(t, name, type.options, &S::own, [name](const S& s) { return s.has(name); },
                       "with the " + name + " stage");
  }
  return t;
}

}  // namespace

const OptionTable<VerificationOptions>& VerificationOptions::fields() {
  return internal::current_table(verification_table);
}

std::int64_t VerificationOptions::own_integer(const std::string& stage, const std::string& name) const {
  return lsgd::own_integer(own, find_verification_stage(stage).options, stage, name);
}

double VerificationOptions::own_real(const std::string& stage, const std::string& name) const {
  return lsgd::own_real(own, find_verification_stage(stage).options, stage, name);
}

std::string VerificationOptions::own_choice(const std::string& stage, const std::string& name) const {
  return lsgd::own_choice(own, find_verification_stage(stage).options, stage, name);
}

bool VerificationOptions::has(const std::string& stage) const {
  return std::find(stages.begin(), stages.end(), stage) != stages.end();
}

void VerificationOptions::check() const {
  check_options(fields(), *this, "verification");
  for (std::size_t i = 0; i < stages.size(); ++i) {
    check_verification_stage(stages[i]);
    if (std::find(stages.begin(), stages.begin() + static_cast<std::ptrdiff_t>(i), stages[i]) !=
        stages.begin() + static_cast<std::ptrdiff_t>(i)) {
      internal::throw_invalid("verification.stages lists '", stages[i], "' twice");
    }
  }
  temporal_options.check();
  geometric_options.check();
}

void parse_verification_stages(const std::string& text, VerificationOptions& options) {
  std::vector<std::string> named;
  if (text != "none") {
    if (text.empty() || text.back() == ',') {
      internal::throw_invalid("verification stages '", internal::shown_value(text), "': expected none or a "
                              "comma-separated list of ", verification_stage_names());
    }
    std::istringstream parts(text);
    for (std::string stage; std::getline(parts, stage, ',');) {
      if (stage.empty() || stage == "none") {
        internal::throw_invalid("verification stages '", internal::shown_value(text), "': expected none or a "
                                "comma-separated list of ", verification_stage_names());
      }
      try {
        check_verification_stage(stage);
      } catch (const InvalidArgument& e) {
        internal::throw_invalid(e.what(), " (in '", internal::shown_value(text), "')");
      }
      if (std::find(named.begin(), named.end(), stage) != named.end()) {
        internal::throw_invalid("verification stages '", internal::shown_value(text), "' name '", internal::shown_value(stage), "' twice");
      }
      named.push_back(stage);
    }
    if (named.empty()) {
      internal::throw_invalid("verification stages '", internal::shown_value(text), "' name no stage: use none or ",
                              verification_stage_names());
    }
  }
  // Registration order: the same stages read the same whatever the order.
  options.stages.clear();
  for (const StageType& t : verification_stage_types()) {
    if (std::find(named.begin(), named.end(), t.name) != named.end()) options.stages.emplace_back(t.name);
  }
}

std::string verification_stages(const VerificationOptions& options) {
  std::string text;
  for (const std::string& stage : options.stages) text += (text.empty() ? "" : ",") + stage;
  return text.empty() ? "none" : text;
}

}  // namespace lsgd
