#include "lsgd/evidence.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>

// AppearanceEvidence's places: the best ones of the last query (best_places())
// and a search's candidates realigned to them (realign()).
namespace lsgd {
namespace {

// Adds c to out unless it is there already (or is no frame).
void add_place(std::vector<Candidate>& out, const Candidate& c) {
  const bool seen = std::any_of(out.begin(), out.end(), [&](const Candidate& o) { return o.frame == c.frame; });
  if (c.frame >= 0 && !seen) out.push_back(c);
}

}  // namespace

void AppearanceEvidence::best_places(int top_n, std::vector<Candidate>& out) const {
  out.clear();
  if (!options_.enabled || sampled(last_query_) || !level2_.valid()) return;
  const std::int64_t n = static_cast<std::int64_t>(sequence_.size());
  const std::int64_t radius = 2 * static_cast<std::int64_t>(options_.tolerance) + 1;
  const std::int64_t newest = last_query_ - min_gap_ - 1;  // frame of slot 0
  // The score a place is found by: A with one place (R is A standardised
  // once for all), else R (the lower of its place's and the map's).
  std::vector<double> by_place;
  if (!cuts_.empty()) {
    by_place.resize(sequence_.size());
    for (std::int64_t k = 0; k < n; ++k) {
      by_place[static_cast<std::size_t>(k)] = place_score(newest - k, sequence_[static_cast<std::size_t>(k)]);
    }
  }
  const std::vector<double>& score = cuts_.empty() ? sequence_ : by_place;
  // A place is a local maximum of the score within `radius` (ties: the older
  // frame); two such maxima are never closer than radius + 1.
  const auto beats = [&](std::int64_t k, std::int64_t m) {
    const double a = score[static_cast<std::size_t>(k)], b = score[static_cast<std::size_t>(m)];
    return a != b ? a > b : k > m;  // higher slot = older frame
  };
  for (std::int64_t k = 0; k < n; ++k) {
    bool peak = true;
    for (std::int64_t m = std::max<std::int64_t>(0, k - radius); m <= std::min(n - 1, k + radius) && peak; ++m) {
      if (m != k && beats(m, k)) peak = false;
    }
    if (peak) out.push_back({newest - k, score[static_cast<std::size_t>(k)]});
  }
  const std::size_t keep = std::min(out.size(), static_cast<std::size_t>(std::max(top_n, 0)));
  std::partial_sort(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(keep), out.end(), better);
  out.resize(keep);
  if (cuts_.empty()) {
    for (Candidate& c : out) c.score = level2_.standardise(c.score);
  }
}


void AppearanceEvidence::realign(const FrameStore& store, const DescriptorView& descriptor,
                                 const std::vector<Candidate>& raw, SimilarityMetric metric,
                                 int top_n, std::int64_t reach, std::vector<Candidate>& out) {
  static const std::vector<std::int64_t> none;
  realign(store, descriptor, raw, none, metric, top_n, reach, top_n, out);
}

void AppearanceEvidence::realign(const FrameStore& store, const DescriptorView& descriptor,
                                 const std::vector<Candidate>& raw,
                                 const std::vector<std::int64_t>& followed, SimilarityMetric metric,
                                 int top_n, std::int64_t reach, int keep,
                                 std::vector<Candidate>& out) {
  out.clear();
  if (!level2_.valid()) return;
  top_n = std::max(top_n, 0);
  keep = std::max(keep, top_n);
  const std::int64_t limit = last_query_ - min_gap_;  // candidates j < limit
  if (reach <= 0) {
    realign_each(store, descriptor, raw, metric, top_n, out);
    return;
  }
  // Every place within tolerance + reach of a candidate: a frame no other
  // within 2 * tolerance + 1 beats, as best_places() reports them. A
  // shortlist finds a revisit by its single frames, whose best frame may
  // sit a few frames off the best aligned sequence, and two places of one
  // stretch of road may sit between them; climbing uphill would find one.
  const Reach r{limit, options_.tolerance + reach, 2 * static_cast<std::int64_t>(options_.tolerance) + 1};
  raw_all_.assign(raw.begin(), raw.end());
  for (;;) {
    out.clear();
    score_windows(store, descriptor, metric, r);
    window_places(r, out);
    std::sort(out.begin(), out.end(), better);
    if (!promote_followed(store, descriptor, followed, metric, r, top_n, out)) break;
  }
  if (out.size() <= static_cast<std::size_t>(top_n) && extra_.empty()) return;
  keep_beyond(static_cast<std::size_t>(top_n), static_cast<std::size_t>(keep), r.radius, out);
}

// The best frame of +-tolerance around each candidate (better(): ties to the
// older frame), the top_n best.
void AppearanceEvidence::realign_each(const FrameStore& store, const DescriptorView& descriptor,
                                      const std::vector<Candidate>& raw, SimilarityMetric metric,
                                      int top_n, std::vector<Candidate>& out) {
  const std::int64_t limit = last_query_ - min_gap_;
  const std::int64_t tolerance = options_.tolerance;
  for (const Candidate& c : raw) {
    Candidate best{-1, 0};
    for (std::int64_t j = std::max<std::int64_t>(0, c.frame - tolerance);
         j <= std::min(limit - 1, c.frame + tolerance); ++j) {
      const Candidate s{j, sequence(store, descriptor, j, metric)};
      if (best.frame < 0 || better(s, best)) best = s;
    }
    add_place(out, best);
  }
  std::sort(out.begin(), out.end(), better);
  if (out.size() > static_cast<std::size_t>(top_n)) out.resize(static_cast<std::size_t>(top_n));
}

// Scores the frames of the candidates' windows and their radius, merged, into
// window_scores_ (in frame order).
void AppearanceEvidence::score_windows(const FrameStore& store, const DescriptorView& descriptor,
                                       SimilarityMetric metric, const Reach& r) {
  windows_.clear();
  for (const Candidate& c : raw_all_) {
    const std::int64_t lo = std::max<std::int64_t>(0, c.frame - r.span - r.radius);
    const std::int64_t hi = std::min(r.limit - 1, c.frame + r.span + r.radius);
    if (lo <= hi) windows_.push_back({lo, hi});
  }
  std::sort(windows_.begin(), windows_.end());
  window_scores_.clear();
  std::int64_t scored_to = -1;  // frames up to here are in window_scores_
  for (const auto& [lo, hi] : windows_) {
    for (std::int64_t j = std::max(lo, scored_to + 1); j <= hi; ++j) {
      window_scores_.push_back({j, sequence(store, descriptor, j, metric)});
    }
    scored_to = std::max(scored_to, hi);
  }
}

// The places in each candidate's window (a frame no other within radius beats).
void AppearanceEvidence::window_places(const Reach& r, std::vector<Candidate>& out) const {
  // window_scores_ is in frame order: the index of frame j's score.
  const auto index = [&](std::int64_t j) {
    return std::lower_bound(window_scores_.begin(), window_scores_.end(), j,
                            [](const Candidate& c, std::int64_t f) { return c.frame < f; }) -
           window_scores_.begin();
  };
  const std::int64_t radius = r.radius;
  for (const Candidate& c : raw_all_) {
    const std::int64_t lo = std::max<std::int64_t>(0, c.frame - r.span);
    const std::int64_t hi = std::min(r.limit - 1, c.frame + r.span);
    if (lo > hi) continue;
    // Frames lo - radius .. hi + radius (within the map) are contiguous there.
    const std::ptrdiff_t k0 = index(lo), first = k0 - (lo - std::max<std::int64_t>(0, lo - radius));
    const std::ptrdiff_t last = k0 + (std::min(r.limit - 1, hi + radius) - lo);
    for (std::ptrdiff_t k = k0; k <= k0 + (hi - lo); ++k) {
      bool peak = true;
      for (std::ptrdiff_t m = std::max(first, k - radius); m <= std::min(last, k + radius) && peak; ++m) {
        if (m != k && better(window_scores_[static_cast<std::size_t>(m)], window_scores_[static_cast<std::size_t>(k)])) {
          peak = false;
        }
      }
      if (peak) add_place(out, window_scores_[static_cast<std::size_t>(k)]);
    }
  }
}

// The followed frames no candidate's window examined: a sequence that would
// rank among the top_n becomes a candidate (its window then reports the
// places around it; returns true), the others are only ranked (extra_).
bool AppearanceEvidence::promote_followed(const FrameStore& store, const DescriptorView& descriptor,
                                          const std::vector<std::int64_t>& followed,
                                          SimilarityMetric metric, const Reach& r, int top_n,
                                          const std::vector<Candidate>& out) {
  extra_.clear();
  bool promoted = false;
  for (const std::int64_t f : followed) {
    if (f < 0 || f >= r.limit) continue;
    const bool examined = std::any_of(raw_all_.begin(), raw_all_.end(), [&](const Candidate& c) {
      return f >= c.frame - r.span && f <= c.frame + r.span;
    });
    if (examined) continue;
    const Candidate c{f, sequence(store, descriptor, f, metric)};
    const bool ranks = top_n > 0 && (out.size() < static_cast<std::size_t>(top_n) ||
                                     better(c, out[static_cast<std::size_t>(top_n) - 1]));
    if (ranks) {
      raw_all_.push_back(c);
      promoted = true;
    } else {
      extra_.push_back(c);
    }
  }
  return promoted;
}

// Beyond the top_n places: the next places and the followed frames (extra_),
// best first, up to keep in all; a followed frame within radius of a better
// one or of a place is left out (the same stretch of diagonals).
void AppearanceEvidence::keep_beyond(std::size_t top_n, std::size_t keep, std::int64_t radius,
                                     std::vector<Candidate>& out) const {
  const std::size_t n = std::min(out.size(), top_n);
  const std::size_t places = out.size();
  for (const Candidate& c : extra_) {
    const bool near = std::any_of(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(places),
                                  [&](const Candidate& o) { return std::abs(o.frame - c.frame) <= radius; });
    if (!near) out.push_back(c);
  }
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(n), out.end(), better);
  std::size_t kept = n;
  for (std::size_t k = n; k < out.size() && kept < keep; ++k) {
    // (Places are never within radius of a place or of a followed frame
    // kept, so this only leaves out followed frames.)
    const Candidate c = out[k];
    const bool covered = std::any_of(out.begin() + static_cast<std::ptrdiff_t>(n),
                                     out.begin() + static_cast<std::ptrdiff_t>(kept),
                                     [&](const Candidate& o) { return std::abs(o.frame - c.frame) <= radius; });
    if (!covered) out[kept++] = c;
  }
  out.resize(kept);
}

}  // namespace lsgd
