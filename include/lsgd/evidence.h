// Appearance evidence that transfers across cameras (beyond the paper).
//
// A raw similarity's range moves with the camera and the scene (loops score
// 0.74-0.78 on one camera, 0.85-0.88 on another), so no fixed threshold on it
// transfers. Every score the detector reports is therefore standardised
// against the query's own distribution of scores over the map:
//
// 1. Similarities. For query i, s(i, j) over its candidates j < i - w has a
//    mean m_i and a standard deviation sd_i; z(i, j) = (s(i, j) - m_i) / sd_i
//    is in standard deviations (sigma) and does not depend on the camera's
//    similarity range.
// 2. Sequences (the temporal stage). The sequence score of candidate j is the
//    mean of z along the diagonal, A_L(i, j) = 1/L sum_{t<L} z(i-t, j-t), for
//    L = frames and long_frames (their mean when both are on). A term that does
//    not exist (j - t < 0, or a query too early to have a distribution) counts
//    as 0, the mean of z, and the divisor stays L: a candidate near the start
//    of the map has no noisier score than any other (no edge effect).
// 3. Sequence scores are standardised once more against their own
//    distribution over the query's candidates: R(i, j) = (A(i, j) - mean_j A)
//    / sd_j A. Averaging correlated frames narrows A by an amount that depends
//    on the frame rate and the scene; R measures how far the candidate's
//    sequence stands out from every other place the query could be, in sigma.
//
// The distributions come from every candidate in exhaustive search, up to
// kExactStatisticsCandidates of them. The modes that do not score every frame
// (dynamic nodes, index) take them from a sample of diagonals: offsets
// d = i - j of min_gap + 1 + k * stride, at most kMaxSampledDiagonals of them
// (the stride doubles as the map grows). Beyond kExactStatisticsCandidates
// exhaustive search takes them from the same sample too, so in a large map
// every mode standardises with the same statistics and scores any candidate
// bit for bit alike: the modes differ only in which candidates they look at.
// Index mode scores every frame up to search.index.exhaustive_up_to
// candidates (CandidateSearch::scores_every_frame_up_to(); by default
// kExactStatisticsCandidates), as exhaustive search, and samples beyond: by
// default its statistics are exhaustive search's at every size.
// (A 512-value sample puts the mean within 0.05 sigma, the standard deviation
// within 3 %.) Along a diagonal the offset is constant, so each diagonal's
// running sums carry from query to query in every mode.
//
// All sums are exact: z is kept in fixed point (1/1024 sigma), so a detector
// restored from a database (which recomputes the last long_frames queries'
// rows from the stored descriptors) scores exactly as one that never stopped.
//
// Places (set_places(); places.h finds them): in a map of several places a
// candidate must stand out from its own place and from the whole map. At
// level 1, z is the lower of the two standardisations (the query's
// statistics over the candidates of j's place, and over all); at level 2, R
// is A less the higher of the place's mean and the map's, over the place's
// standard deviation but at least half the map's. A place with fewer than
// kMinCalibration candidates has no statistics of its own: it counts 0 there
// (no null to stand out from). A sequence's terms stay within
// the places of its two ends: z(i - t, j - t) counts 0 when frame j - t lies
// before the place of j or query i - t before the place of i (as a frame
// before the map). The whole map's statistics stay what
// similarity_statistics(), sequence_statistics() and single_frame() give.
// With one place (no cut) every score is the one of a map without places,
// bit for bit. docs/results.md, "Places found from the frames".
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <utility>
#include <vector>

#include "lsgd/frame_store.h"
#include "lsgd/search.h"
#include "lsgd/similarity.h"

namespace lsgd {

// A query's scores are standardised with statistics of its own when it has
// at least this many candidates (exhaustive) or sampled diagonals (nodes).
// Before that it is young: its similarities are standardised with the prior
// (every similarity of the young queries so far, once they are this many),
// it has no sequence evidence, and only a candidate geometry confirms is
// reported (decision.h).
constexpr std::int64_t kMinCalibration = 32;

// The first query with a score (the prior has kMinCalibration similarities:
// queries min_gap + 1, + 2, ... have 1, 2, ... candidates).
constexpr std::int64_t first_scored_query(std::int64_t min_gap) {
  std::int64_t k = 0, values = 0;
  while (values < kMinCalibration) values += ++k;
  return min_gap + k;
}
// The most diagonals sampled per query (between half this and this).
constexpr std::int64_t kMaxSampledDiagonals = 512;
// Exhaustive search: statistics over every candidate up to this many, over the
// sampled diagonals beyond (above every real sequence of docs/results.md).
constexpr std::int64_t kExactStatisticsCandidates = 8192;

struct ScoreStatistics {
  double mean = 0;
  double sd = 0;            // population standard deviation
  std::int64_t count = 0;   // values the statistics were computed over
  bool valid() const { return count >= kMinCalibration && sd > 0; }
  double standardise(double value) const { return (value - mean) / sd; }
};

// Statistics that merge (issue 32; a map split into parts, issue 34): the
// exact sums of a set of values in fixed point (1/2^40, |value| clamped to
// 2^13), which integer addition makes independent of order and grouping. A
// part of the map summarises its own candidates; the merged summaries of any
// split give the statistics of the whole bit for bit (docs/design.md, "Statistics
// that merge"). Every ScoreStatistics the evidence computes comes from one.
class StatisticsSummary {
 public:
  void add(double value);
  void add(const double* values, std::size_t n);
  // Adds another part's summary (InvalidArgument beyond kMaxCount values).
  void merge(const StatisticsSummary& other);
  std::int64_t count() const { return count_; }
  // Mean and population standard deviation, a function of the sums alone.
  ScoreStatistics statistics() const;
  // The most values a summary holds (the sums cannot overflow below it).
  static constexpr std::int64_t kMaxCount = std::int64_t{1} << 20;

 private:
  __extension__ typedef __int128 Sum;
  std::int64_t count_ = 0;
  Sum sum_ = 0;      // of round(value * 2^40)
  Sum squares_ = 0;  // of its square
};

// Mean and standard deviation of values[0 .. n) (a StatisticsSummary's).
ScoreStatistics statistics(const double* values, std::size_t n);

struct SequenceOptions {
  bool enabled = true;    // sequence scores (temporal stage); false: single-frame z only
  int frames = 16;        // L of the short sequence
  int long_frames = 48;   // L of the long sequence, 0: off
  int tolerance = 2;      // realignment and distinct-place radius, frames
};

// The appearance evidence of one detector: per-query statistics and the
// sequence sums along the kept diagonals. Not thread-safe.
class AppearanceEvidence {
 public:
  // sample: the search does not score every frame (sampled diagonals);
  // exact_statistics: when every frame is scored, the most candidates the
  // statistics are computed over (kExactStatisticsCandidates; tests use a
  // smaller one); every_frame_up_to: with sample, the search still scores
  // every frame of a query with at most this many candidates (0: never;
  // CandidateSearch::scores_every_frame_up_to()), and its diagonals are
  // sampled beyond.
  AppearanceEvidence(const SequenceOptions& sequence, std::int64_t min_gap, bool sample,
                     std::int64_t exact_statistics = kExactStatisticsCandidates,
                     std::int64_t every_frame_up_to = 0);

  // Adds query `query` (== store.size(): the frame is not stored yet, its
  // descriptor is `descriptor`). `row`, when given, holds s(query, j) for
  // every j < query - min_gap in frame order (the search already computed
  // it; only for a query whose diagonals are not sampled); otherwise the
  // kept diagonals are scored here. Queries must come in order; a detector
  // restored from storage is brought up to date first (rebuild()).
  void add_query(const FrameStore& store, const DescriptorView& descriptor, std::int64_t query,
                 SimilarityMetric metric, const std::vector<double>* row);

  // The first frames of the places after the first (ascending, from
  // PlaceCuts::cuts()). The rows kept are not recomputed: rebuild() after a
  // change (the detector does, on a cut found).
  void set_places(const std::vector<std::int64_t>& cuts);
  const std::vector<std::int64_t>& places() const { return cuts_; }
  // The place of frame j (0 before the first cut).
  std::size_t place_of(std::int64_t frame) const;

  // The map in parts (issue 34's shards): the first frames of the parts
  // after the first (ascending). Every statistic (both levels, over the map
  // and by place, and the prior) is then the merge of each part's summary of
  // its own frames' values, as a map split over k machines computes it; the
  // scores are those of one part bit for bit (docs/design.md, "Statistics
  // that merge"). Takes effect from the next query.
  void set_parts(const std::vector<std::int64_t>& firsts);
  const std::vector<std::int64_t>& parts() const { return parts_; }
  // The part of frame j (0 before the second part's first frame).
  std::size_t part_of(std::int64_t frame) const;

  // Statistics of the last added query's similarities (level 1) and, with
  // sequences on, of its sequence scores (level 2), over the whole map.
  const ScoreStatistics& similarity_statistics() const { return level1_; }
  const ScoreStatistics& sequence_statistics() const { return level2_; }

  // Whether the last query is young: it has fewer than kMinCalibration
  // candidates, so it has no statistics of its own and no sequence evidence;
  // its similarities are standardised with the prior (valid once the young
  // queries so far have kMinCalibration similarities between them).
  bool young() const { return last_query_ >= 0 && young(last_query_); }

  // Standardised single-frame score of candidate `frame` for the last query,
  // given its raw similarity (a young query's: with the prior); NaN when the
  // query is not calibrated.
  double single_frame(double similarity) const;

  // Sequence evidence R of candidate `frame` of the last query (the query's
  // descriptor again, for the t = 0 term); NaN when not calibrated.
  double sequence(const FrameStore& store, const DescriptorView& descriptor, std::int64_t frame,
                  SimilarityMetric metric);

  // A query whose every frame was scored (not sampled(last_query())): the
  // best `top_n` distinct places of the last query by sequence evidence
  // (local maxima of A at least 2 * tolerance + 2 frames apart), best first,
  // scores R. Empty when not calibrated or sampled.
  void best_places(int top_n, std::vector<Candidate>& out) const;

  // Re-aligns each raw candidate within +-tolerance frames to its best
  // sequence; with reach > 0 it reports instead every place best_places()
  // would report (a frame no other within 2 * tolerance + 1 beats) within
  // tolerance + reach frames of a candidate. Drops duplicates and writes the
  // best top_n by R (modes that do not score every frame; reach:
  // CandidateSearch::realign_reach()).
  void realign(const FrameStore& store, const DescriptorView& descriptor,
               const std::vector<Candidate>& raw, SimilarityMetric metric, int top_n,
               std::int64_t reach, std::vector<Candidate>& out);
  // The same, and (reach > 0) frames `followed` scored at that frame only,
  // without a window: one whose sequence would rank among the top_n places is
  // realigned as a candidate, so the top_n written first are places as
  // above. After them, up to keep - top_n more, best first: the next places
  // and the followed frames no place or better followed frame within
  // 2 * tolerance + 1 covers (what a mode follows to the next query).
  void realign(const FrameStore& store, const DescriptorView& descriptor,
               const std::vector<Candidate>& raw, const std::vector<std::int64_t>& followed,
               SimilarityMetric metric, int top_n, std::int64_t reach, int keep,
               std::vector<Candidate>& out);

  // Recomputes the state of the last max(frames, long_frames) queries from
  // the stored frames, as if they had been added one by one (after a detector
  // was restored from storage). The queries are store.size() - L .. store.size() - 1.
  void rebuild(const FrameStore& store, SimilarityMetric metric);

  // The last query added (-1: none).
  std::int64_t last_query() const { return last_query_; }
  // Whether the diagonals of `query` are sampled (stride() may exceed 1, no
  // row of every frame): with sample, beyond every_frame_up_to candidates.
  bool sampled(std::int64_t query) const;
  // Diagonals kept for `query`: offsets min_gap + 1 + k * stride(query), k < count.
  std::int64_t stride(std::int64_t query) const;
  std::int64_t diagonals(std::int64_t query) const;
  // Stride of the diagonals the statistics of `query` are computed over (a
  // multiple of stride(query)).
  std::int64_t statistics_stride(std::int64_t query) const;

 private:
  // A value by frame (or offset) b >= 0: open addressing, linear probing.
  template <typename V>
  class Table {
   public:
    // The value of b, nullptr when there is none.
    const V* find(std::int64_t b) const;
    // Sets the value of b.
    void insert(std::int64_t b, const V& value);
    // The value of b, added as V{} (`added` true) when there is none: one
    // probe where find() then insert() take two. Valid until the next add.
    V& find_or_add(std::int64_t b, bool& added);
    void clear();

   private:
    struct Entry {
      std::int64_t key = -1;  // -1: empty
      V value{};
    };
    std::vector<Entry> entries_;  // key and value in one line: one miss a probe
    std::size_t size_ = 0;
  };
  // A sequence's sums (fixed point) without its oldest term: what the next
  // query's sequence on the same diagonal adds its own term to.
  struct Carry {
    std::int64_t short_sum = 0;
    std::int64_t long_sum = 0;
  };
  struct Row {
    std::int64_t query = -1;
    ScoreStatistics stats;
    std::vector<ScoreStatistics> places;  // by place of the candidate (empty without cuts)
    std::vector<std::int32_t> z;  // fixed point, one per kept diagonal (slot order)
  };
  std::int32_t quantise(const ScoreStatistics& stats, double similarity) const;
  // The same for candidate `frame` with places: the lower of its z over the
  // whole map (`stats`) and over its place (`places`).
  std::int32_t quantise(const ScoreStatistics& stats, const std::vector<ScoreStatistics>& places,
                        std::int64_t frame, double similarity) const;
  // The lower of value standardised with `all` and with frame's place's
  // statistics (0 for a young place); `all` alone without cuts.
  double standardise_min(const ScoreStatistics& all, const std::vector<ScoreStatistics>& places,
                         std::int64_t frame, double value) const;
  // The first frame of frame's place.
  std::int64_t place_start(std::int64_t frame) const;
  // The sequence sums of the last query with the terms across a place left
  // out (add_query, with cuts).
  void sums_within_places(std::int64_t query);
  bool young(std::int64_t query) const;
  // Adds a young query's similarities (slot k: frame query - min_gap - 1 - k)
  // to the prior, each to its part's summary ...
  void add_to_prior(std::int64_t query, const std::vector<double>& values);
  // ... and returns the merged statistics.
  ScoreStatistics prior(std::int64_t query, const std::vector<double>& values);
  void push_row(Row row);
  // Statistics of `values` (one per kept diagonal of `query`) over the
  // diagonals of statistics_stride(query): of all of them (returned) and,
  // with cuts, of those of each place (`by_place`, else empty).
  ScoreStatistics kept_statistics(std::int64_t query, const std::vector<double>& values,
                                  std::vector<ScoreStatistics>& by_place);
  // The place statistics a value of candidate `frame` is standardised with
  // (an invalid one: the place is too young).
  const ScoreStatistics& of_place(const std::vector<ScoreStatistics>& by_place, std::int64_t frame) const;
  // R of candidate `frame` from its sequence score A (with places: see the top).
  double place_score(std::int64_t frame, double a) const;
  // z of every kept diagonal of `row.query` (every `every`-th value).
  void quantise_row(Row& row, const std::vector<double>& values, std::size_t every) const;
  // Fills `out` with s(query, query - d) for the kept diagonals of `query`.
  void diagonal_similarities(const FrameStore& store, const DescriptorView& descriptor,
                             std::int64_t query, SimilarityMetric metric,
                             const std::vector<double>* row, std::vector<double>& out) const;
  double sequence_mean(std::int64_t short_sum, std::int64_t long_sum) const;
  // The terms of diagonal d (its record, added when there is none).
  std::size_t terms(std::int64_t d);
  // z(a, a - d) in fixed point (0 when a - d < 0 or the stats are not
  // valid), from record r of diagonal d or computed into it; `view` is query
  // a's descriptor, `stats` its row's statistics.
  std::int32_t term(std::size_t r, const FrameStore& store, const DescriptorView& view,
                    std::int64_t a, std::int64_t d, const Row& row, SimilarityMetric metric);
  // Drops the records that hold no query of the ring any more (add_query).
  void prune_terms();
  const Row* ring_row(std::int64_t query) const;
  // realign()'s steps (evidence_places.cc).
  struct Reach {
    std::int64_t limit;   // candidates j < limit
    std::int64_t span;    // tolerance + reach: a candidate's window
    std::int64_t radius;  // 2 * tolerance + 1: one place
  };
  void realign_each(const FrameStore& store, const DescriptorView& descriptor,
                    const std::vector<Candidate>& raw, SimilarityMetric metric, int top_n,
                    std::vector<Candidate>& out);
  void score_windows(const FrameStore& store, const DescriptorView& descriptor, SimilarityMetric metric,
                     const Reach& r);
  void window_places(const Reach& r, std::vector<Candidate>& out) const;
  bool promote_followed(const FrameStore& store, const DescriptorView& descriptor,
                        const std::vector<std::int64_t>& followed, SimilarityMetric metric,
                        const Reach& r, int top_n, const std::vector<Candidate>& out);
  void keep_beyond(std::size_t top_n, std::size_t keep, std::int64_t radius,
                   std::vector<Candidate>& out) const;
  Row* ring_row(std::int64_t query);

  SequenceOptions options_;
  std::int64_t min_gap_ = 0;
  bool sample_ = false;
  std::int64_t exact_statistics_ = kExactStatisticsCandidates;
  std::int64_t every_frame_up_to_ = 0;
  int span_ = 1;                   // rows kept: max(frames, long_frames) with sequences, else 1
  std::int64_t last_query_ = -1;
  std::deque<Row> ring_;           // the last span_ queries, oldest first
  std::vector<std::int32_t> short_sum_, long_sum_;  // per kept diagonal
  std::vector<double> sequence_;   // A per kept diagonal of the last query
  ScoreStatistics level1_, level2_;
  std::vector<ScoreStatistics> level2_places_;  // level 2 by place
  std::vector<std::int64_t> cuts_;              // set_places()
  std::vector<std::int64_t> parts_;             // set_parts()
  std::vector<StatisticsSummary> summaries_;    // kept_statistics(): by place, merged
  std::vector<StatisticsSummary> part_summaries_;  // ... by part: all, then by place
  std::vector<double> scratch_;
  // The prior: the similarities of every young query so far, summarised by
  // the part of their frame.
  std::vector<StatisticsSummary> prior_parts_;
  Table<double> scored_;  // A of the frames scored for the last query
  // By diagonal (offset query - frame): the carries of the sequences the
  // previous query scored off the kept diagonals (read by this query's
  // sequence()), and those this query scored (for the next one).
  Table<Carry> carried_, carrying_;
  // z(a, a - d) of the queries a in the ring by diagonal d, computed once:
  // what a sequence on d reads for its terms t >= 1 (earlier queries' pairs
  // on d; the query's own, t = 0, for the next queries). One record a
  // diagonal, a ring of term_ring_ values indexed by a, so a sequence's
  // terms lie together and one probe finds them (they were kept by query,
  // one probe each, in tables that outgrew the cache).
  struct TermRecord {
    std::int64_t diagonal = 0;
    std::int64_t newest = -1;  // the newest query a it holds
  };
  Table<std::int64_t> term_index_;         // d -> record
  std::vector<TermRecord> term_records_;
  std::vector<std::int32_t> term_z_;       // per record: term_ring_ values, kUnknownTerm: not computed
  std::int64_t term_ring_ = 1;             // a power of two >= span_
  // Records before prune_terms() drops the stale ones: at least
  // kTermRecords, else twice those it kept last.
  static constexpr std::size_t kTermRecords = 4096;
  std::size_t term_limit_ = kTermRecords;
  std::vector<Candidate> raw_all_;    // realign(): the candidates and the followed frames promoted
  std::vector<Candidate> extra_;      // ... the followed frames' sequences
  std::vector<std::pair<std::int64_t, std::int64_t>> windows_;  // realign(): frames to score ...
  std::vector<Candidate> window_scores_;                        // ... and their R, in frame order
};

}  // namespace lsgd
