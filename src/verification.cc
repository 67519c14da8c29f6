#include "lsgd/verification.h"

#include <algorithm>
#include <cstdlib>
#include <sstream>

#include "internal/check.h"

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

const OptionTable<VerificationOptions>& VerificationOptions::fields() {
  using S = VerificationOptions;
  static const OptionTable<S> table = [] {
    OptionField<S> stages;
    stages.name = "stages";
    stages.kind = OptionKind::kChoice;
    stages.doc = "verification stages after the search (either order)";
    stages.choices = [] {
      return std::vector<std::string>{"none", "temporal", "geometric", "temporal,geometric"};
    };
    stages.text = [](const S& s) { return verification_stages(s); };
    stages.set_choice = [](S& s, const std::string& text) { parse_verification_stages(text, s); };
    OptionTable<S> t = {
        stages,
        integer_option("max_candidates", &S::max_candidates, 1, 100, "",
                       "candidates examined best first; the first no stage rejects is reported"),
    };
    t.back().applies = [](const S& s) { return s.temporal || s.geometric; };
    t.back().when = "with a stage";
    nest<S, TemporalOptions>(t, "temporal", &S::temporal_options, TemporalOptions::fields(),
                             [](const S& s) { return s.temporal; }, "with the temporal stage");
    nest<S, GeometricOptions>(t, "geometric", &S::geometric_options, GeometricOptions::fields(),
                              [](const S& s) { return s.geometric; }, "with the geometric stage");
    return t;
  }();
  return table;
}

void VerificationOptions::check() const {
  check_options(fields(), *this, "verification");
  temporal_options.check();
  geometric_options.check();
}

void parse_verification_stages(const std::string& text, VerificationOptions& options) {
  bool temporal = false, geometric = false;
  if (text != "none") {
    std::istringstream parts(text);
    std::string stage;
    while (std::getline(parts, stage, ',')) {
      if (stage == "temporal") {
        temporal = true;
      } else if (stage == "geometric") {
        geometric = true;
      } else {
        internal::throw_invalid("verification stage '", stage, "' in '", text,
                                "' is unknown: expected none, temporal, geometric or "
                                "temporal,geometric");
      }
    }
    if (!temporal && !geometric) {
      internal::throw_invalid("verification '", text,
                              "' names no stage: use none, temporal, "
                              "geometric or temporal,geometric");
    }
  }
  options.temporal = temporal;
  options.geometric = geometric;
}

std::string verification_stages(const VerificationOptions& options) {
  if (options.temporal && options.geometric) return "temporal,geometric";
  if (options.temporal) return "temporal";
  if (options.geometric) return "geometric";
  return "none";
}

TemporalVerifier::TemporalVerifier(const TemporalOptions& options) : options_(options) {
  options_.check();
}

TemporalVerifier::Check TemporalVerifier::agree(std::int64_t query,
                                                const Candidate& candidate) const {
  Check check;
  const int k = options_.agree;
  if (k == 0) {
    check.accepted = true;
    check.reason = internal::concat("sequence score ", candidate.score, " (no agreement gate)");
    return check;
  }
  if (last_query_ != query - 1 || places_.size() < static_cast<std::size_t>(k)) {
    check.reason = internal::concat("needs ", k, " previous queries");
    return check;
  }
  const std::int64_t slack = options_.tolerance + 1;
  for (int t = 1; t <= k; ++t) {
    const std::int64_t place = places_[places_.size() - t];
    const std::int64_t expected = candidate.frame - t;
    if (place < 0 || std::llabs(place - expected) > slack) {
      check.reason = internal::concat("query ", query - t, " was placed at ", place,
                                      ", not within ", slack, " of frame ", expected);
      return check;
    }
  }
  check.accepted = true;
  check.reason = internal::concat(k, " previous queries agree; sequence score ", candidate.score);
  return check;
}

void TemporalVerifier::push(std::int64_t query, std::int64_t place) {
  if (query != last_query_ + 1) places_.clear();  // a gap: earlier places no longer adjacent
  last_query_ = query;
  places_.push_back(place);
  while (places_.size() > static_cast<std::size_t>(std::max(options_.agree, 1))) {
    places_.pop_front();
  }
}

void TemporalVerifier::restore(std::int64_t last_query, std::vector<std::int64_t> places) {
  const std::size_t capacity = static_cast<std::size_t>(std::max(options_.agree, 1));
  if (places.size() > capacity) {
    internal::throw_invalid("TemporalVerifier::restore: ", places.size(), " places but at most ",
                            capacity, " are kept (agree = ", options_.agree, ")");
  }
  if (last_query < -1 || last_query + 1 < static_cast<std::int64_t>(places.size())) {
    internal::throw_invalid("TemporalVerifier::restore: last query ", last_query, " cannot have ",
                            places.size(), " places");
  }
  for (const std::int64_t place : places) {
    if (place < -1) internal::throw_invalid("TemporalVerifier::restore: place ", place, " < -1");
  }
  places_.assign(places.begin(), places.end());
  last_query_ = last_query;
}

}  // namespace lsgd
