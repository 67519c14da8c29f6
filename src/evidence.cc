#include "lsgd/evidence.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "internal/check.h"
#include "lsgd/places.h"

namespace lsgd {
namespace {

constexpr double kZScale = 1024.0;   // fixed point: 1/1024 sigma
constexpr double kZLimit = 64.0;     // |z| is clamped to 64 sigma
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// With places, the least standard deviation a place's sequence scores are
// standardised with, as a share of the whole map's (docs/results.md, "Places
// found from the frames").
constexpr double kPlaceSpreadFloor = 0.5;
// A term not computed yet (quantise() stays within +-kZLimit * kZScale).
constexpr std::int32_t kUnknownTerm = std::numeric_limits<std::int32_t>::min();

// Offsets d of the candidates of `query`: min_gap + 1 .. query.
std::int64_t offsets(std::int64_t query, std::int64_t min_gap) {
  return std::max<std::int64_t>(0, query - min_gap);
}

// The stride of the sampled diagonals among `offsets`: the smallest power of
// two that keeps at most kMaxSampledDiagonals of them.
std::int64_t sampled_stride(std::int64_t offsets) {
  std::int64_t s = 1;
  while ((offsets + s - 1) / s > kMaxSampledDiagonals) s *= 2;
  return s;
}

}  // namespace

AppearanceEvidence::AppearanceEvidence(const SequenceOptions& sequence, std::int64_t min_gap,
                                       bool sample, std::int64_t exact_statistics,
                                       std::int64_t every_frame_up_to)
    : options_(sequence),
      min_gap_(min_gap),
      sample_(sample),
      exact_statistics_(exact_statistics),
      every_frame_up_to_(every_frame_up_to) {
  if (min_gap < 0) internal::throw_invalid("AppearanceEvidence: min_gap ", min_gap, " < 0");
  if (exact_statistics < 0) {
    internal::throw_invalid("AppearanceEvidence: exact_statistics ", exact_statistics, " < 0");
  }
  if (every_frame_up_to < 0) {
    internal::throw_invalid("AppearanceEvidence: every_frame_up_to ", every_frame_up_to, " < 0");
  }
  if (options_.enabled) {
    if (options_.frames < 1 || options_.long_frames < 0 || options_.tolerance < 0) {
      internal::throw_invalid("AppearanceEvidence: sequence lengths ", options_.frames, ", ",
                              options_.long_frames, " and tolerance ", options_.tolerance,
                              " are out of range");
    }
    span_ = std::max(options_.frames, options_.long_frames);
  }
  while (term_ring_ < span_) term_ring_ *= 2;
}

bool AppearanceEvidence::sampled(std::int64_t query) const {
  return sample_ && offsets(query, min_gap_) > every_frame_up_to_;
}

std::int64_t AppearanceEvidence::stride(std::int64_t query) const {
  return sampled(query) ? sampled_stride(offsets(query, min_gap_)) : 1;
}

std::int64_t AppearanceEvidence::statistics_stride(std::int64_t query) const {
  const std::int64_t n = offsets(query, min_gap_);
  return sampled(query) || n > exact_statistics_ ? sampled_stride(n) : 1;
}

void AppearanceEvidence::set_places(const std::vector<std::int64_t>& cuts) {
  for (std::size_t k = 0; k < cuts.size(); ++k) {
    if (cuts[k] <= 0 || (k > 0 && cuts[k] <= cuts[k - 1])) {
      internal::throw_invalid("AppearanceEvidence::set_places: place ", k + 1, " begins at frame ",
                              cuts[k], ", not after the one before");
    }
  }
  cuts_ = cuts;
}

std::size_t AppearanceEvidence::place_of(std::int64_t frame) const {
  return static_cast<std::size_t>(std::upper_bound(cuts_.begin(), cuts_.end(), frame) - cuts_.begin());
}

const ScoreStatistics& AppearanceEvidence::of_place(const std::vector<ScoreStatistics>& by_place,
                                                    std::int64_t frame) const {
  static const ScoreStatistics kNoPlace;
  const std::size_t p = place_of(frame);
  return p < by_place.size() ? by_place[p] : kNoPlace;
}

std::int64_t AppearanceEvidence::place_start(std::int64_t frame) const {
  return lsgd::place_start(cuts_, frame);
}

double AppearanceEvidence::standardise_min(const ScoreStatistics& all,
                                           const std::vector<ScoreStatistics>& places,
                                           std::int64_t frame, double value) const {
  const double z = all.standardise(value);
  if (cuts_.empty() || places.empty()) return z;
  const ScoreStatistics& place = of_place(places, frame);
  return std::min(z, place.valid() ? place.standardise(value) : 0.0);
}

void AppearanceEvidence::quantise_row(Row& row, const std::vector<double>& values,
                                      std::size_t every) const {
  row.z.clear();
  const std::int64_t newest = row.query - min_gap_ - 1, s = stride(row.query);
  for (std::size_t k = 0; k < values.size(); k += every) {
    row.z.push_back(quantise(row.stats, row.places, newest - static_cast<std::int64_t>(k) * s, values[k]));
  }
}

double AppearanceEvidence::place_score(std::int64_t frame, double a) const {
  if (cuts_.empty()) return level2_.standardise(a);
  const ScoreStatistics& place = of_place(level2_places_, frame);
  if (!place.valid()) return std::min(0.0, level2_.standardise(a));  // a young place: no score of its own
  // Above the higher of the place's mean and the map's, in the place's spread
  // but at least kPlaceSpreadFloor of the map's: a place whose sequences all
  // score alike (another environment, far from the query) does not make its
  // small deviations large.
  return (a - std::max(place.mean, level2_.mean)) / std::max(place.sd, kPlaceSpreadFloor * level2_.sd);
}

bool AppearanceEvidence::young(std::int64_t query) const {
  return offsets(query, min_gap_) < kMinCalibration;
}

std::int64_t AppearanceEvidence::diagonals(std::int64_t query) const {
  const std::int64_t s = stride(query);
  return (offsets(query, min_gap_) + s - 1) / s;
}

std::int32_t AppearanceEvidence::quantise(const ScoreStatistics& stats, double similarity) const {
  if (!stats.valid()) return 0;
  const double z = std::clamp(stats.standardise(similarity), -kZLimit, kZLimit);
  return static_cast<std::int32_t>(std::lround(z * kZScale));
}

std::int32_t AppearanceEvidence::quantise(const ScoreStatistics& stats,
                                          const std::vector<ScoreStatistics>& places,
                                          std::int64_t frame, double similarity) const {
  if (!stats.valid()) return 0;
  if (places.empty()) return quantise(stats, similarity);
  const double z = std::clamp(standardise_min(stats, places, frame, similarity), -kZLimit, kZLimit);
  return static_cast<std::int32_t>(std::lround(z * kZScale));
}

void AppearanceEvidence::diagonal_similarities(const FrameStore& store,
                                               const DescriptorView& descriptor,
                                               std::int64_t query, SimilarityMetric metric,
                                               const std::vector<double>* row,
                                               std::vector<double>& out) const {
  const std::int64_t n = diagonals(query);
  const std::int64_t s = stride(query);
  out.resize(static_cast<std::size_t>(n));
  const std::int64_t newest = query - min_gap_ - 1;  // frame of slot 0
  if (row != nullptr) {
    if (s != 1) {
      internal::throw_invalid("AppearanceEvidence: a row of similarities for query ", query,
                              ", whose diagonals are sampled (stride ", s, ")");
    }
    if (static_cast<std::int64_t>(row->size()) != offsets(query, min_gap_)) {
      internal::throw_invalid("AppearanceEvidence: a row of ", row->size(),
                              " similarities for query ", query, ", expected ",
                              offsets(query, min_gap_));
    }
    for (std::int64_t k = 0; k < n; ++k) out[static_cast<std::size_t>(k)] = (*row)[static_cast<std::size_t>(newest - k)];
    return;
  }
  constexpr std::int64_t kBatch = 16;
  DescriptorView views[kBatch];
  for (std::int64_t k0 = 0; k0 < n; k0 += kBatch) {
    const std::int64_t m = std::min(kBatch, n - k0);
    for (std::int64_t k = 0; k < m; ++k) views[k] = store.view(newest - (k0 + k) * s);
    similarities(descriptor, views, static_cast<std::size_t>(m), metric,
                 out.data() + static_cast<std::ptrdiff_t>(k0));
  }
}

double AppearanceEvidence::sequence_mean(std::int64_t short_sum, std::int64_t long_sum) const {
  const double a = static_cast<double>(short_sum) / (kZScale * options_.frames);
  if (options_.long_frames == 0) return a;
  return 0.5 * (a + static_cast<double>(long_sum) / (kZScale * options_.long_frames));
}

void AppearanceEvidence::push_row(Row row) {
  const std::int64_t i = row.query;
  const std::size_t n = row.z.size();
  if (short_sum_.size() < n) {
    short_sum_.resize(n, 0);
    long_sum_.resize(n, 0);
  }
  const bool two = options_.long_frames > 0;
  for (std::size_t k = 0; k < n; ++k) {
    short_sum_[k] += row.z[k];
    if (two) long_sum_[k] += row.z[k];
  }
  const auto leave = [&](std::int64_t query, std::vector<std::int32_t>& sums) {
    if (const Row* old = ring_row(query)) {
      const std::size_t m = std::min(old->z.size(), sums.size());
      for (std::size_t k = 0; k < m; ++k) sums[k] -= old->z[k];
    }
  };
  leave(i - options_.frames, short_sum_);
  if (two) leave(i - options_.long_frames, long_sum_);
  ring_.push_back(std::move(row));
  while (static_cast<int>(ring_.size()) > span_) ring_.pop_front();
}

const AppearanceEvidence::Row* AppearanceEvidence::ring_row(std::int64_t query) const {
  if (ring_.empty() || query < ring_.front().query || query > ring_.back().query) return nullptr;
  return &ring_[static_cast<std::size_t>(query - ring_.front().query)];
}

AppearanceEvidence::Row* AppearanceEvidence::ring_row(std::int64_t query) {
  return const_cast<Row*>(std::as_const(*this).ring_row(query));
}

void AppearanceEvidence::add_query(const FrameStore& store, const DescriptorView& descriptor,
                                   std::int64_t query, SimilarityMetric metric,
                                   const std::vector<double>* row) {
  if (query != store.size() || query != last_query_ + 1) {
    internal::throw_invalid("AppearanceEvidence::add_query: query ", query, " after query ",
                            last_query_, " with ", store.size(), " frames stored");
  }
  diagonal_similarities(store, descriptor, query, metric, row, scratch_);
  // A young query's own statistics are not valid: its row's z stay 0 (no
  // sequence term) and it is scored on the prior alone.
  Row r;
  r.query = query;
  r.stats = kept_statistics(query, scratch_, r.places);
  const ScoreStatistics own = r.stats;
  level1_ = young(query) ? prior(query, scratch_) : own;
  level2_ = ScoreStatistics{};
  level2_places_.clear();
  scored_.clear();
  // The previous query's carries are this one's (add_query takes the queries in order).
  std::swap(carried_, carrying_);
  carrying_.clear();
  last_query_ = query;
  if (!options_.enabled) return;
  prune_terms();

  // The stride grew (it doubled, or the diagonals are sampled from this
  // query on): keep the diagonals of the new stride in the ring and the sums.
  const std::int64_t s = stride(query);
  if (query > 0 && s != stride(query - 1)) {
    const auto every = static_cast<std::size_t>(s / stride(query - 1));
    const auto keep = [every](auto& v) {
      std::size_t n = 0;
      for (std::size_t k = 0; k < v.size(); k += every) v[n++] = v[k];
      v.resize(n);
    };
    for (Row& kept : ring_) keep(kept.z);
    keep(short_sum_);
    keep(long_sum_);
  }
  quantise_row(r, scratch_, 1);
  push_row(std::move(r));

  const std::size_t n = scratch_.size();
  sequence_.resize(n);
  for (std::size_t k = 0; k < n; ++k) sequence_[k] = sequence_mean(short_sum_[k], long_sum_[k]);
  if (!cuts_.empty()) sums_within_places(query);
  if (own.valid()) level2_ = kept_statistics(query, sequence_, level2_places_);
}

void AppearanceEvidence::sums_within_places(std::int64_t query) {
  const std::int64_t query_start = place_start(query);
  const std::int64_t newest = query - min_gap_ - 1, s = stride(query);
  const auto n = static_cast<std::int64_t>(sequence_.size());
  // Slot k's sums again from the rows, without the pairs across a place.
  const auto within = [&](std::int64_t k, std::int64_t frame) {
    const std::int64_t frame_start = place_start(frame);
    std::int64_t short_sum = 0, long_sum = 0;
    for (const Row& row : ring_) {
      const std::int64_t t = query - row.query;
      if (row.query < query_start || frame - t < frame_start ||
          k >= static_cast<std::int64_t>(row.z.size())) {
        continue;
      }
      const std::int32_t z = row.z[static_cast<std::size_t>(k)];
      if (t < options_.frames) short_sum += z;
      if (options_.long_frames > 0 && t < options_.long_frames) long_sum += z;
    }
    sequence_[static_cast<std::size_t>(k)] = sequence_mean(short_sum, long_sum);
  };
  if (query - query_start < span_) {  // rows of another place are in the ring: every slot
    for (std::int64_t k = 0; k < n; ++k) within(k, newest - k * s);
    return;
  }
  // Only the frames less than a sequence after a place's first.
  for (const std::int64_t c : cuts_) {
    for (std::int64_t j = c; j < c + span_ - 1 && j <= newest; ++j) {
      if ((newest - j) % s == 0 && (newest - j) / s < n) within((newest - j) / s, j);
    }
  }
}

double AppearanceEvidence::single_frame(double similarity) const {
  return level1_.valid() ? level1_.standardise(similarity) : kNaN;
}

template <typename V>
const V* AppearanceEvidence::Table<V>::find(std::int64_t b) const {
  if (entries_.empty()) return nullptr;
  const std::size_t mask = entries_.size() - 1;
  for (std::size_t at = static_cast<std::size_t>(b) & mask;; at = (at + 1) & mask) {
    if (entries_[at].key == b) return &entries_[at].value;
    if (entries_[at].key < 0) return nullptr;
  }
}

template <typename V>
V& AppearanceEvidence::Table<V>::find_or_add(std::int64_t b, bool& added) {
  if (2 * (size_ + 1) > entries_.size()) {  // at most half full
    std::vector<Entry> entries(std::max<std::size_t>(64, 2 * entries_.size()));
    const std::size_t mask = entries.size() - 1;
    for (const Entry& e : entries_) {
      if (e.key < 0) continue;
      std::size_t at = static_cast<std::size_t>(e.key) & mask;
      while (entries[at].key >= 0) at = (at + 1) & mask;
      entries[at] = e;
    }
    entries_.swap(entries);
  }
  const std::size_t mask = entries_.size() - 1;
  std::size_t at = static_cast<std::size_t>(b) & mask;
  while (entries_[at].key >= 0 && entries_[at].key != b) at = (at + 1) & mask;
  added = entries_[at].key < 0;
  if (added) {
    ++size_;
    entries_[at] = Entry{b, V{}};
  }
  return entries_[at].value;
}

template <typename V>
void AppearanceEvidence::Table<V>::insert(std::int64_t b, const V& value) {
  bool added = false;
  find_or_add(b, added) = value;
}

template <typename V>
void AppearanceEvidence::Table<V>::clear() {
  if (size_ == 0) return;
  std::fill(entries_.begin(), entries_.end(), Entry{});
  size_ = 0;
}

std::size_t AppearanceEvidence::terms(std::int64_t d) {
  bool added = false;
  std::int64_t& r = term_index_.find_or_add(d, added);
  if (added) {
    r = static_cast<std::int64_t>(term_records_.size());
    term_records_.push_back({d, -1});
    term_z_.resize(term_z_.size() + static_cast<std::size_t>(term_ring_), kUnknownTerm);
  }
  return static_cast<std::size_t>(r);
}

std::int32_t AppearanceEvidence::term(std::size_t r, const FrameStore& store,
                                      const DescriptorView& view, std::int64_t a, std::int64_t d,
                                      const Row& row, SimilarityMetric metric) {
  const std::int64_t b = a - d;
  if (b < 0 || !row.stats.valid()) return 0;
  std::int32_t* z = term_z_.data() + r * static_cast<std::size_t>(term_ring_);
  const std::int64_t mask = term_ring_ - 1;
  std::int64_t& newest = term_records_[r].newest;
  if (a > newest) {
    // The slots of queries newest + 1 .. a held queries a ring earlier, out
    // of the ring now. (a is never a ring or more below newest: a is in the
    // ring, newest at most the last query.)
    for (std::int64_t q = std::max(newest + 1, a - mask); q <= a; ++q) z[q & mask] = kUnknownTerm;
    newest = a;
  }
  std::int32_t& v = z[a & mask];
  if (v == kUnknownTerm) v = quantise(row.stats, row.places, b, similarity(view, store.view(b), metric));
  return v;
}

void AppearanceEvidence::prune_terms() {
  if (term_records_.size() <= term_limit_) return;
  const std::int64_t oldest = last_query_ - span_ + 1;  // the oldest query in the ring
  term_index_.clear();
  std::size_t kept = 0;
  const auto ring = static_cast<std::size_t>(term_ring_);
  for (std::size_t r = 0; r < term_records_.size(); ++r) {
    if (term_records_[r].newest < oldest) continue;
    term_records_[kept] = term_records_[r];
    std::copy_n(term_z_.begin() + static_cast<std::ptrdiff_t>(r * ring), ring,
                term_z_.begin() + static_cast<std::ptrdiff_t>(kept * ring));
    term_index_.insert(term_records_[kept].diagonal, static_cast<std::int64_t>(kept));
    ++kept;
  }
  term_records_.resize(kept);
  term_z_.resize(kept * ring);
  term_limit_ = std::max(kTermRecords, 2 * kept);
}

double AppearanceEvidence::sequence(const FrameStore& store, const DescriptorView& descriptor,
                                    std::int64_t frame, SimilarityMetric metric) {
  if (!options_.enabled) internal::throw_invalid("AppearanceEvidence: sequences are off");
  if (!level2_.valid() || level2_.sd <= 0) return kNaN;
  if (const double* a = scored_.find(frame)) return place_score(frame, *a);
  const std::int64_t i = last_query_;
  // On a kept diagonal the sums are already there.
  const std::int64_t d = i - frame, s = stride(i);
  if ((d - min_gap_ - 1) % s == 0) {
    const std::int64_t k = (d - min_gap_ - 1) / s;
    if (k >= 0 && k < static_cast<std::int64_t>(sequence_.size())) {
      const double a = sequence_[static_cast<std::size_t>(k)];
      scored_.insert(frame, a);
      return place_score(frame, a);
    }
  }
  // Term t of the sequence, z(i - t, frame - t): the query's own (t = 0,
  // kept for the next queries' sequences on this diagonal) or a stored
  // query's (0 when it left the ring or was never calibrated).
  const std::size_t r = terms(d);
  const std::int64_t query_start = cuts_.empty() ? 0 : place_start(i);
  const std::int64_t frame_start = cuts_.empty() ? 0 : place_start(frame);
  const auto z = [&](int t) -> std::int32_t {
    if (t == 0) return term(r, store, descriptor, i, d, ring_.back(), metric);
    // Across a place (with cuts): as a term before the map.
    if (i - t < query_start || frame - t < frame_start) return 0;
    const Row* row = ring_row(i - t);
    return row == nullptr ? 0 : term(r, store, store.view(i - t), i - t, d, *row, metric);
  };
  const std::int32_t z0 = z(0);
  std::int64_t short_sum = z0;
  std::int64_t long_sum = z0;
  const int steps = std::max(options_.frames, options_.long_frames);
  const Carry* c = carried_.find(d);
  // A carry from the frame or query before a place's first leaves out other pairs.
  if (!cuts_.empty() && (frame == frame_start || i == query_start)) c = nullptr;
  if (c != nullptr) {
    // The previous query scored this diagonal: its terms t >= 1 are that
    // sequence's, less its oldest (the same fixed-point values, so the same sums).
    short_sum += c->short_sum;
    long_sum += c->long_sum;
  } else {
    for (int t = 1; t < steps && frame - t >= 0; ++t) {
      const std::int32_t zt = z(t);
      if (t < options_.frames) short_sum += zt;
      long_sum += zt;
    }
  }
  // For the next query on this diagonal: both sums without their oldest term
  // (0 when it does not exist: a frame before the map or a query before the ring).
  const int s_last = options_.frames - 1, l_last = steps - 1;
  carrying_.insert(d, Carry{short_sum - z(s_last), long_sum - z(l_last)});
  const double a = sequence_mean(short_sum, long_sum);
  scored_.insert(frame, a);
  return place_score(frame, a);
}

void AppearanceEvidence::rebuild(const FrameStore& store, SimilarityMetric metric) {
  ring_.clear();
  short_sum_.clear();
  long_sum_.clear();
  sequence_.clear();
  scored_.clear();
  carried_.clear();
  carrying_.clear();
  term_index_.clear();
  term_records_.clear();
  term_z_.clear();
  term_limit_ = kTermRecords;
  level1_ = level2_ = ScoreStatistics{};
  level2_places_.clear();
  last_query_ = store.size() - 1;
  // The prior, when the next query is young: every young query's similarities.
  prior_parts_.assign(parts_.size() + 1, StatisticsSummary{});
  if (young(store.size())) {
    for (std::int64_t q = 0; q < store.size(); ++q) {
      diagonal_similarities(store, store.view(q), q, metric, nullptr, scratch_);
      add_to_prior(q, scratch_);
    }
  }
  if (!options_.enabled || store.empty()) return;
  const std::int64_t first = std::max<std::int64_t>(0, store.size() - span_);
  std::vector<double> row;
  // Rows in the current stride: the ring holds only the last span_ queries,
  // so a stride change within them would be undone by halving anyway.
  const std::int64_t last = store.size() - 1;
  const std::int64_t s_last = stride(last);
  for (std::int64_t q = first; q <= last; ++q) {
    diagonal_similarities(store, store.view(q), q, metric, nullptr, scratch_);
    // In the stride of the last query (the ring was halved when it doubled).
    const std::int64_t ratio = s_last / stride(q);
    Row r;
    r.query = q;
    r.stats = kept_statistics(q, scratch_, r.places);
    quantise_row(r, scratch_, static_cast<std::size_t>(ratio));
    ring_.push_back(std::move(r));
  }
  // Sums over the windows ending at the last query.
  const std::size_t n = ring_.back().z.size();
  short_sum_.assign(n, 0);
  long_sum_.assign(n, 0);
  for (const Row& r : ring_) {
    const std::int64_t age = last - r.query;
    for (std::size_t k = 0; k < r.z.size() && k < n; ++k) {
      if (age < options_.frames) short_sum_[k] += r.z[k];
      if (options_.long_frames > 0 && age < options_.long_frames) long_sum_[k] += r.z[k];
    }
  }
}

}  // namespace lsgd
