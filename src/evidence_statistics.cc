// The statistics of the appearance evidence (evidence.h): exact summaries
// that merge, the statistics of a query's kept diagonals from the summaries
// of the map's parts (over all and by place), and the prior of the young
// queries. docs/design.md, "Statistics that merge".
#include "lsgd/evidence.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "internal/check.h"

namespace lsgd {

namespace {
constexpr double kSummaryScale = 1099511627776.0;  // 2^40
constexpr double kSummaryClamp = 8192.0;           // 2^13: |q| <= 2^53, q^2 * kMaxCount < 2^127
}  // namespace

void StatisticsSummary::add(double value) {
  if (count_ >= kMaxCount) {
    internal::throw_invalid("StatisticsSummary: more than ", kMaxCount, " values");
  }
  const double v = std::isnan(value) ? 0.0 : std::clamp(value, -kSummaryClamp, kSummaryClamp);
  const auto q = static_cast<std::int64_t>(std::llround(v * kSummaryScale));
  ++count_;
  sum_ += q;
  squares_ += static_cast<Sum>(q) * q;
}

void StatisticsSummary::add(const double* values, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) add(values[i]);
}

void StatisticsSummary::merge(const StatisticsSummary& other) {
  if (count_ + other.count_ > kMaxCount) {
    internal::throw_invalid("StatisticsSummary: merging ", count_, " and ", other.count_,
                            " values, more than ", kMaxCount);
  }
  count_ += other.count_;
  sum_ += other.sum_;
  squares_ += other.squares_;
}

ScoreStatistics StatisticsSummary::statistics() const {
  ScoreStatistics s;
  s.count = count_;
  if (count_ == 0) return s;
  // Long double: the squares' mean minus the squared mean keeps the 53 bits
  // of a double for any spread the evidence meets (sd / mean >= 1e-4).
  const long double n = static_cast<long double>(count_);
  const long double mean = static_cast<long double>(sum_) / n;
  const long double variance = static_cast<long double>(squares_) / n - mean * mean;
  s.mean = static_cast<double>(mean / kSummaryScale);
  s.sd = variance > 0 ? static_cast<double>(std::sqrt(variance) / kSummaryScale) : 0.0;
  return s;
}

ScoreStatistics statistics(const double* values, std::size_t n) {
  StatisticsSummary summary;
  summary.add(values, n);
  return summary.statistics();
}

ScoreStatistics AppearanceEvidence::kept_statistics(std::int64_t query,
                                                    const std::vector<double>& values,
                                                    std::vector<ScoreStatistics>& by_place) {
  const auto every = static_cast<std::size_t>(statistics_stride(query) / stride(query));
  // Each part of the map summarises the values of its own frames, over all
  // and by place (what a map part answers a query with); the merged summaries
  // are the map's. With one part and one place, one summary.
  const std::size_t places = cuts_.empty() ? 0 : cuts_.size() + 1, width = places + 1;
  part_summaries_.assign((parts_.size() + 1) * width, StatisticsSummary{});
  const std::int64_t newest = query - min_gap_ - 1, s = stride(query);
  if (parts_.empty() && places == 0) {
    for (std::size_t k = 0; k < values.size(); k += every) part_summaries_[0].add(values[k]);
  } else {
    for (std::size_t k = 0; k < values.size(); k += every) {
      const std::int64_t frame = newest - static_cast<std::int64_t>(k) * s;
      StatisticsSummary* part = &part_summaries_[part_of(frame) * width];
      part[0].add(values[k]);
      if (places > 0) part[1 + place_of(frame)].add(values[k]);
    }
  }
  // Merged last part first: integer sums do not depend on the order.
  StatisticsSummary all;
  summaries_.assign(places, StatisticsSummary{});
  for (std::size_t p = parts_.size() + 1; p-- > 0;) {
    all.merge(part_summaries_[p * width]);
    for (std::size_t place = 0; place < places; ++place) {
      summaries_[place].merge(part_summaries_[p * width + 1 + place]);
    }
  }
  by_place.clear();
  for (const StatisticsSummary& summary : summaries_) by_place.push_back(summary.statistics());
  return all.statistics();
}

void AppearanceEvidence::set_parts(const std::vector<std::int64_t>& firsts) {
  for (std::size_t k = 0; k < firsts.size(); ++k) {
    if (firsts[k] <= 0 || (k > 0 && firsts[k] <= firsts[k - 1])) {
      internal::throw_invalid("AppearanceEvidence::set_parts: part ", k + 1, " begins at frame ",
                              firsts[k], ", not after the one before");
    }
  }
  parts_ = firsts;
  // The prior's summaries so far, regrouped: their merged sums are unchanged.
  StatisticsSummary prior;
  for (const StatisticsSummary& part : prior_parts_) prior.merge(part);
  prior_parts_.assign(parts_.size() + 1, StatisticsSummary{});
  prior_parts_[0] = prior;
}

std::size_t AppearanceEvidence::part_of(std::int64_t frame) const {
  return static_cast<std::size_t>(std::upper_bound(parts_.begin(), parts_.end(), frame) - parts_.begin());
}

void AppearanceEvidence::add_to_prior(std::int64_t query, const std::vector<double>& values) {
  prior_parts_.resize(parts_.size() + 1);
  const std::int64_t newest = query - min_gap_ - 1;  // a young query's stride is 1
  for (std::size_t k = 0; k < values.size(); ++k) {
    prior_parts_[part_of(newest - static_cast<std::int64_t>(k))].add(values[k]);
  }
}

ScoreStatistics AppearanceEvidence::prior(std::int64_t query, const std::vector<double>& values) {
  add_to_prior(query, values);
  StatisticsSummary merged;
  for (std::size_t p = prior_parts_.size(); p-- > 0;) merged.merge(prior_parts_[p]);
  return merged.statistics();
}

}  // namespace lsgd
