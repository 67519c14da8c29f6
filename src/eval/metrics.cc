#include "lsgd/eval/metrics.h"
#include "lsgd/limits.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>

#include "internal/check.h"

namespace lsgd::eval {
namespace {

struct Report {
  double score;
  bool correct;
  bool recalled;  // counts towards recall (strict: iff correct)
  bool declared;  // the system declared it a loop
  bool confirmed = true;  // the ranking's: swept before every unconfirmed report
};

// What the ranking sweeps for record r: its ranking, or its `reported`
// (confirmed) when it has none (another system's detections).
const Candidate& ranked(const FrameRecord& r) { return r.ranking ? r.ranking->best : r.reported; }
bool ranked_confirmed(const FrameRecord& r) { return !r.ranking || r.ranking->confirmed; }

// The operating point: the declared reports alone.
void operating_point(const std::vector<Report>& reports, Metrics& m) {
  std::int64_t recalled = 0;
  for (const Report& r : reports) {
    if (!r.declared) continue;
    ++m.declared_loops;
    (r.correct ? m.declared_true : m.declared_false) += 1;
    recalled += r.recalled ? 1 : 0;
  }
  m.precision_at_decision =
      m.declared_loops > 0 ? static_cast<double>(m.declared_true) / m.declared_loops : 0.0;
  m.recall_at_decision = m.positives > 0 ? static_cast<double>(recalled) / m.positives : 0.0;
}

bool correct_loop(const GroundTruth& gt, std::int64_t query, const Candidate& c,
                  std::int64_t min_gap) {
  return c.frame >= 0 && c.frame < query - min_gap && gt.is_loop(query, c.frame);
}

// True when some ground-truth loop g < query - min_gap of the query lies
// within tolerance of the candidate: |c - g| < tolerance.
bool near_loop(const GroundTruth& gt, std::int64_t query, const Candidate& c, std::int64_t min_gap,
               std::int64_t tolerance) {
  if (c.frame < 0 || std::abs(query - c.frame) <= min_gap) return false;
  const auto& loops = gt.matches(query);  // ascending
  const auto end = std::lower_bound(loops.begin(), loops.end(), query - min_gap);
  const auto near = std::lower_bound(loops.begin(), end, c.frame - tolerance + 1);
  return near != end && *near < c.frame + tolerance;
}

// Every ground-truth frame is a query: the positives are its frames with a
// loop outside the window, whether or not a record reports anything for them.
std::int64_t positive_queries(const GroundTruth& gt, std::int64_t min_gap) {
  std::int64_t n = 0;
  for (const std::int64_t q : gt.queries()) n += gt.has_loop(q, min_gap) ? 1 : 0;
  return n;
}

// Frame ids inside the ground truth, each at most once.
void check_records(const std::vector<FrameRecord>& records, const GroundTruth& gt,
                   const char* who) {
  std::vector<char> seen(static_cast<std::size_t>(gt.frames()), 0);
  for (const auto& r : records) {
    if (r.frame < 0 || r.frame >= gt.frames()) {
      internal::throw_invalid(who, ": frame ", r.frame, " is outside the ground truth's ",
                              gt.frames(), " frames");
    }
    if (seen[static_cast<std::size_t>(r.frame)]++) {
      internal::throw_invalid(who, ": frame ", r.frame, " is reported twice");
    }
  }
}

// Fills the threshold sweep, R@100P, P@100R and AP from the best reports.
void sweep(std::vector<Report> reports, Metrics& m) {
  std::sort(reports.begin(), reports.end(), [](const Report& a, const Report& b) {
    return a.confirmed != b.confirmed ? a.confirmed : a.score > b.score;
  });
  std::int64_t tp = 0, fp = 0, recalled = 0;
  double previous_recall = 0;
  for (std::size_t i = 0; i < reports.size();) {
    const double threshold = reports[i].score;
    const bool confirmed = reports[i].confirmed;
    for (; i < reports.size() && reports[i].score == threshold && reports[i].confirmed == confirmed;
         ++i) {
      (reports[i].correct ? tp : fp) += 1;
      recalled += reports[i].recalled ? 1 : 0;
    }
    PrPoint p;
    p.threshold = threshold;
    p.confirmed = confirmed;
    p.true_positives = tp;
    p.false_positives = fp;
    p.precision = static_cast<double>(tp) / static_cast<double>(tp + fp);
    p.recall =
        m.positives > 0 ? static_cast<double>(recalled) / static_cast<double>(m.positives) : 0.0;
    m.average_precision += (p.recall - previous_recall) * p.precision;
    previous_recall = p.recall;
    if (fp == 0 && p.recall > m.recall_at_100_precision) {
      m.recall_at_100_precision = p.recall;
      m.threshold_at_100_precision = threshold;
    }
    if (m.positives > 0 && recalled == m.positives) {
      m.precision_at_100_recall = std::max(m.precision_at_100_recall, p.precision);
    }
    m.curve.push_back(p);
  }
}

// The ranking's sweep (the main metrics) and the decision's.
void sweeps(std::vector<Report> ranking, std::vector<Report> decision, Metrics& m) {
  sweep(std::move(ranking), m);
  Metrics d;
  d.positives = m.positives;
  sweep(std::move(decision), d);
  m.decision_recall_at_100_precision = d.recall_at_100_precision;
  m.decision_threshold_at_100_precision = d.threshold_at_100_precision;
  m.decision_average_precision = d.average_precision;
}

// Recall@1/5/10 over the positive queries; correct(query, candidate) decides a hit.
template <typename Correct>
void fill_recall_at_n(const std::vector<FrameRecord>& records, const GroundTruth& gt,
                      std::int64_t min_gap, const Correct& correct, Metrics& m) {
  std::int64_t hits[3] = {0, 0, 0};
  const std::size_t ns[3] = {1, 5, 10};
  for (const auto& r : records) {
    if (!gt.has_loop(r.frame, min_gap)) continue;
    for (int k = 0; k < 3; ++k) {
      const std::size_t n = std::min(ns[k], r.candidates.size());
      for (std::size_t c = 0; c < n; ++c) {
        if (correct(r.frame, r.candidates[c])) {
          ++hits[k];
          break;
        }
      }
    }
  }
  if (m.positives == 0) return;
  const double p = static_cast<double>(m.positives);
  m.recall_at_1 = hits[0] / p;
  m.recall_at_5 = hits[1] / p;
  m.recall_at_10 = hits[2] / p;
}

void fill_timings(const std::vector<FrameRecord>& records, Metrics& m) {
  std::vector<double> total, load, convert, segment, describe, search, verify;
  for (const auto& r : records) {
    if (r.skipped) continue;  // never processed: no time of the detector's
    load.push_back(r.load_ms);
    total.push_back(r.timings.total_ms);
    convert.push_back(r.timings.convert_ms);
    segment.push_back(r.timings.segment_ms);
    describe.push_back(r.timings.describe_ms);
    search.push_back(r.timings.search_ms);
    verify.push_back(r.timings.verify_ms);
  }
  m.ms_per_frame_median = percentile(total, 0.5);
  m.ms_per_frame_p95 = percentile(total, 0.95);
  m.ms_per_frame_mean =
      total.empty() ? 0.0 : std::accumulate(total.begin(), total.end(), 0.0) / total.size();
  m.load_ms_median = percentile(load, 0.5);
  m.convert_ms_median = percentile(convert, 0.5);
  m.segment_ms_median = percentile(segment, 0.5);
  m.describe_ms_median = percentile(describe, 0.5);
  m.search_ms_median = percentile(search, 0.5);
  m.verify_ms_median = percentile(verify, 0.5);
  m.load_ms_p95 = percentile(load, 0.95);
  m.convert_ms_p95 = percentile(convert, 0.95);
  m.segment_ms_p95 = percentile(segment, 0.95);
  m.describe_ms_p95 = percentile(describe, 0.95);
  m.search_ms_p95 = percentile(search, 0.95);
  m.verify_ms_p95 = percentile(verify, 0.95);
  m.prt = m.average_precision / (1.0 + 10.0 * m.ms_per_frame_mean * 1e-3);
}

}  // namespace

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  q = std::clamp(q, 0.0, 1.0);
  const std::size_t rank = static_cast<std::size_t>(std::ceil(q * values.size()));
  const std::size_t index = rank == 0 ? 0 : rank - 1;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(index),
                   values.end());
  return values[index];
}

Metrics evaluate(const std::vector<FrameRecord>& records, const GroundTruth& gt,
                 std::int64_t min_gap) {
  if (min_gap < 0) internal::throw_invalid("evaluate: min_gap = ", min_gap, " must be >= 0");
  Metrics m;
  m.min_gap = min_gap;
  m.frames = gt.frames();
  m.positives = positive_queries(gt, min_gap);
  check_records(records, gt, "evaluate");
  std::vector<Report> reports, ranking;
  for (const auto& r : records) {
    if (r.reported.frame >= 0) {
      const bool correct = correct_loop(gt, r.frame, r.reported, min_gap);
      reports.push_back({r.reported.score, correct, correct, r.loop});
    }
    const Candidate& c = ranked(r);
    if (c.frame >= 0) {
      const bool correct = correct_loop(gt, r.frame, c, min_gap);
      ranking.push_back({c.score, correct, correct, false, ranked_confirmed(r)});
    }
  }
  operating_point(reports, m);
  sweeps(std::move(ranking), std::move(reports), m);
  fill_recall_at_n(
      records, gt, min_gap,
      [&](std::int64_t q, const Candidate& c) { return correct_loop(gt, q, c, min_gap); }, m);
  fill_timings(records, m);
  return m;
}

void ReferenceProtocolOptions::check() const {
  internal::check_range<std::int64_t>("min_gap", min_gap, 0, kMaxWindowFrames, "frames");
  internal::check_range<std::int64_t>("tolerance", tolerance, 1, kMaxWindowFrames, "frames");
}

Metrics evaluate_lsgddn_reference(const std::vector<FrameRecord>& records, const GroundTruth& gt,
                                  const ReferenceProtocolOptions& options) {
  options.check();
  Metrics m;
  m.protocol = "lsgddn-reference";
  m.tolerance = options.tolerance;
  m.min_gap = options.min_gap;
  m.frames = gt.frames();
  m.positives = positive_queries(gt, options.min_gap);
  check_records(records, gt, "evaluate_lsgddn_reference");
  const auto correct = [&](std::int64_t q, const Candidate& c) {
    return near_loop(gt, q, c, options.min_gap, options.tolerance);
  };
  std::vector<Report> reports, ranking;
  // A report the protocol looks at (outside the window), into `out`.
  const auto add = [&](std::int64_t query, const Candidate& c, Report report,
                       std::vector<Report>& out) {
    if (c.frame < 0 || std::abs(query - c.frame) <= options.min_gap) return;
    report.correct = correct(query, c);
    report.recalled = report.correct || options.recall_counts_any_report;
    out.push_back(report);
  };
  for (const auto& r : records) {
    // Queries without a ground-truth loop are never looked at: their reports vanish.
    if (!gt.has_loop(r.frame, options.min_gap)) continue;
    add(r.frame, r.reported, {r.reported.score, false, false, r.loop}, reports);
    add(r.frame, ranked(r), {ranked(r).score, false, false, false, ranked_confirmed(r)}, ranking);
  }
  operating_point(reports, m);
  sweeps(std::move(ranking), std::move(reports), m);
  fill_recall_at_n(records, gt, options.min_gap, correct, m);
  fill_timings(records, m);
  return m;
}

std::string describe_protocol(const Metrics& m) {
  if (m.protocol == "strict") {
    return internal::concat(
        "strict (one report per query, exact ground-truth match, false "
        "positives counted on every query; window ",
        m.min_gap, " frames)");
  }
  return internal::concat(
      m.protocol,
      " (lenient: reports on queries without a ground-truth loop are ignored, a "
      "report within ",
      m.tolerance - 1, " frames of a ground-truth loop counts as correct, |i - j| <= ", m.min_gap,
      " excluded; for comparison with the LSGDDN paper only, not with strict numbers)");
}

}  // namespace lsgd::eval
