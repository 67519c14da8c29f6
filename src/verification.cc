#include "lsgd/verification.h"

#include <algorithm>
#include <cstdlib>
#include <sstream>

#include "internal/check.h"

namespace lsgd {

void TemporalOptions::check() const {
  internal::check_range("verification.temporal.frames", frames, 1, 100, "frames");
  internal::check_range("verification.temporal.long_frames", long_frames, 0, 1000, "frames");
  if (long_frames != 0 && long_frames <= frames) {
    internal::throw_invalid(
        "verification.temporal.long_frames = ", long_frames,
        " must be 0 (off) or more than verification.temporal.frames = ", frames);
  }
  internal::check_range("verification.temporal.tolerance", tolerance, 0, 100, "frames");
  internal::check_range("verification.temporal.agree", agree, 0, 100, "queries");
}

void VerificationOptions::check() const {
  internal::check_range("verification.max_candidates", max_candidates, 1, 100);
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

void TemporalVerifier::check_cache(const FrameStore& store, SimilarityMetric metric) const {
  if (pairs_store_ != &store || store.size() < pairs_store_size_ || pairs_metric_ != metric) {
    pairs_.clear();
    pairs_store_ = &store;
    pairs_metric_ = metric;
  }
  pairs_store_size_ = store.size();
}

double TemporalVerifier::stored_similarity(const FrameStore& store, std::int64_t a, std::int64_t b,
                                           SimilarityMetric metric) const {
  const std::uint64_t key = static_cast<std::uint64_t>(a) << 32 | static_cast<std::uint64_t>(b);
  const auto [it, inserted] = pairs_.try_emplace(key, 0.0);
  if (inserted) it->second = similarity(store.view(a), store.view(b), metric);
  return it->second;
}

double TemporalVerifier::sequence_score(const FrameStore& store, const DescriptorView& descriptor,
                                        std::int64_t query, std::int64_t j,
                                        SimilarityMetric metric) const {
  // Both lengths sum the same diagonal: one pass, the short sum taken on the way.
  const std::int64_t short_steps = std::min<std::int64_t>(options_.frames, j + 1);
  const std::int64_t long_steps = std::min<std::int64_t>(options_.long_frames, j + 1);
  const std::int64_t steps = std::max(short_steps, long_steps);
  double sum = similarity(descriptor, store.view(j), metric);  // the query is not stored yet
  double short_sum = sum;
  for (std::int64_t t = 1; t < steps; ++t) {
    sum += stored_similarity(store, query - t, j - t, metric);
    if (t + 1 == short_steps) short_sum = sum;
  }
  const double short_score = short_sum / static_cast<double>(short_steps);
  if (options_.long_frames == 0) return short_score;
  return 0.5 * (short_score + sum / static_cast<double>(long_steps));
}

void TemporalVerifier::rescore(const FrameStore& store, const DescriptorView& descriptor,
                               std::int64_t query, const std::vector<Candidate>& raw,
                               std::int64_t min_gap, SimilarityMetric metric, int top_n,
                               std::vector<Candidate>& out) const {
  out.clear();
  scored_.clear();
  check_cache(store, metric);
  const auto score_of = [&](std::int64_t j) {
    for (const Candidate& s : scored_) {
      if (s.frame == j) return s;
    }
    scored_.push_back({j, sequence_score(store, descriptor, query, j, metric)});
    return scored_.back();
  };
  const std::int64_t limit = std::min(store.size(), query - min_gap);  // candidates j < limit
  for (const Candidate& c : raw) {
    Candidate aligned{-1, -1.0};
    const std::int64_t lo = std::max<std::int64_t>(0, c.frame - options_.tolerance);
    const std::int64_t hi = std::min(limit - 1, c.frame + options_.tolerance);
    for (std::int64_t j = lo; j <= hi; ++j) {
      const Candidate s = score_of(j);
      if (better(s, aligned)) aligned = s;
    }
    const bool seen = std::any_of(out.begin(), out.end(),
                                  [&](const Candidate& o) { return o.frame == aligned.frame; });
    if (aligned.frame >= 0 && !seen) out.push_back(aligned);
  }
  std::sort(out.begin(), out.end(), better);
  if (out.size() > static_cast<std::size_t>(top_n)) out.resize(static_cast<std::size_t>(top_n));
  // The next query's sequences start at frame query + 1 - max(frames, long_frames) or later.
  const std::int64_t oldest = query + 1 - std::max(options_.frames, options_.long_frames);
  for (auto it = pairs_.begin(); it != pairs_.end();) {
    it = static_cast<std::int64_t>(it->first >> 32) < oldest ? pairs_.erase(it) : std::next(it);
  }
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
