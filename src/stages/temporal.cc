#include "lsgd/stages/temporal.h"

#include <algorithm>
#include <cstdlib>

#include "internal/check.h"
#include "internal/clock.h"

namespace lsgd {

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

namespace {

class TemporalStage final : public VerificationStage {
 public:
  explicit TemporalStage(const TemporalOptions& options) : verifier_(options) {}
  const char* name() const override { return kTemporalStage; }
  Role role() const override { return Role::kGate; }
  // begin() reads nothing of the image: a described frame needs no record.
  bool describes() const override { return true; }
  bool has_state() const override { return true; }
  bool examines() const override { return verifier_.options().agree > 0; }

  StageCheck check(std::int64_t query, const Candidate& candidate) override {
    const auto start = internal::now_ns();
    const TemporalVerifier::Check c = verifier_.agree(query, candidate);
    return {c.accepted, -1, c.reason, internal::ms_since(start), nullptr};
  }

  // Only end() keeps anything (the query's place): discard() has nothing to forget.
  bool answers_queries() const override { return true; }
  // The query's best place: its first candidate (-1: none).
  void end(std::int64_t query, const std::vector<Candidate>& candidates) override {
    const std::int64_t place = candidates.empty() ? -1 : candidates.front().frame;
    verifier_.push(query, place);
    places_.resize(static_cast<std::size_t>(query));
    places_.push_back(place);
  }

  // State, version 1: the query's best place (int64, -1: none). A frame
  // without a record (written before the stage kept one) has place -1.
  void save_frame(std::int64_t frame, StateWriter& out) const override {
    if (frame < 0 || frame >= static_cast<std::int64_t>(places_.size())) {
      internal::throw_invalid("temporal: frame ", frame, " was not processed (", places_.size(),
                              " frames)");
    }
    out.put_i64(places_[static_cast<std::size_t>(frame)]);
  }
  void check_frame(std::int64_t frame, int, int, std::uint32_t version,
                   StateReader in) const override {
    if (!in.present()) return;
    check_state_version(in.what(), name(), version, 1);
    const std::int64_t place = in.get_i64();
    in.finish();
    if (place < -1 || place >= frame) {
      internal::throw_invalid(in.what(), ": place ", place, " is not an earlier frame or -1");
    }
  }
  void restore_frame(std::int64_t frame, int width, int height, std::uint32_t version,
                     StateReader in) override {
    restore_renumbered(frame, width, height, version, in, FrameRenumbering::identity());
  }
  // A forgotten place is no place (-1).
  bool forgets() const override { return true; }
  void restore_renumbered(std::int64_t frame, int, int, std::uint32_t, StateReader in,
                          const FrameRenumbering& renumbered) override {
    const std::int64_t place = in.present() ? renumbered.after(in.get_i64()) : -1;
    end(frame, {Candidate{place, 0.0}});
  }

 private:
  TemporalVerifier verifier_;
  std::vector<std::int64_t> places_;  // best place of every query
};

}  // namespace

std::unique_ptr<VerificationStage> make_temporal_stage(const VerificationOptions& options) {
  return std::make_unique<TemporalStage>(options.temporal_options);
}

}  // namespace lsgd
