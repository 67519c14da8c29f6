#include "lsgd/search/exhaustive.h"

#include <algorithm>

#include "lsgd/detector.h"
#include "search/scoring.h"

namespace lsgd {

void search_exhaustive(const FrameStore& store, const DescriptorView& query, std::int64_t query_id,
                       const SearchOptions& options, SimilarityMetric metric,
                       std::vector<Candidate>& scratch, std::vector<Candidate>& out,
                       std::vector<double>* row) {
  scratch.clear();
  const std::int64_t limit = std::max<std::int64_t>(0, std::min(store.size(), query_id - options.min_gap));
  if (row != nullptr) row->resize(static_cast<std::size_t>(limit));
  internal::score_frames(
      store, query, metric, limit, [](std::int64_t j) { return j; },
      [&](std::int64_t, std::int64_t j, double score) {
        scratch.push_back({j, score});
        if (row != nullptr) (*row)[static_cast<std::size_t>(j)] = score;
      });
  internal::keep_best(scratch, options.top_n, out);
}

namespace {

class ExhaustiveSearch final : public CandidateSearch {
 public:
  explicit ExhaustiveSearch(const SearchOptions& options) : options_(options) {}
  const char* name() const override { return kExhaustiveSearch; }
  bool scores_every_frame() const override { return true; }
  Outcome search(const Query& q, std::vector<Candidate>& out, std::vector<double>& row) override {
    search_exhaustive(q.store, q.descriptor, q.id, options_, q.metric, scratch_, out, &row);
    return {};
  }
  // search() changes nothing.
  Outcome query(const Query& q, std::vector<Candidate>& out, std::vector<double>& row) override {
    return search(q, out, row);
  }

 private:
  SearchOptions options_;
  std::vector<Candidate> scratch_;
};

}  // namespace

std::unique_ptr<CandidateSearch> make_exhaustive_search(const SearchOptions& options) {
  return std::make_unique<ExhaustiveSearch>(options);
}

std::int64_t exhaustive_bytes_per_frame(const DetectorOptions& options, int) {
  const TemporalOptions& t = options.verification.temporal_options;
  const int rows = options.verification.has(kTemporalStage) ? std::max(t.frames, t.long_frames) : 1;
  return 8 * std::int64_t{rows};
}

}  // namespace lsgd
