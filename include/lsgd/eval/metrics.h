// The strict evaluation protocol of docs/evaluation.md: every query reports at
// most its best candidate j < i - w; a reported loop is a true positive iff
// GT(i, j) = 1 and a false positive otherwise, also on queries without any
// ground-truth loop; a threshold sweep over the scores gives the PR curve.
// Also the LSGDDN authors' lenient protocol, only to compare with their paper.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/eval/groundtruth.h"

namespace lsgd::eval {

// What a system reported for one query frame.
struct FrameRecord {
  std::int64_t frame = -1;
  Candidate reported;                 // the reported loop and its score; frame -1: none
  // The system declared `reported` a loop (Result::loop; for detections of
  // another system, every reported match). The operating point scores these.
  bool loop = false;
  // The ranking, which no decision setting changes (Result::ranking: the
  // best candidate, its appearance score, confirmed or not): R@100P, AP and
  // the PR curve sweep over it, confirmed reports first. Not given (another
  // system's detections): the sweep takes `reported`, every report confirmed.
  std::optional<Ranking> ranking;
  std::vector<Candidate> candidates;  // ranked candidates, best first (for Recall@N)
  Timings timings;                    // zeros when unknown (detections from another system)
  double load_ms = 0;                 // reading and decoding the image (outside process())
  bool skipped = false;  // the image could not be read or was rejected: no report
};

struct PrPoint {
  // Score threshold: loops with score >= threshold are reported; of the
  // ranking, the confirmed ones (confirmed true) and then, after every
  // confirmed report, the unconfirmed ones too (confirmed false).
  double threshold = 0;
  bool confirmed = true;
  double precision = 0;
  double recall = 0;
  std::int64_t true_positives = 0;
  std::int64_t false_positives = 0;
};

struct Metrics {
  // "strict" (evaluate) or "lsgddn-reference" (evaluate_lsgddn_reference).
  std::string protocol = "strict";
  std::int64_t tolerance = 0;  // lsgddn-reference: match tolerance, frames; 0 for strict
  std::int64_t frames = 0;     // query frames evaluated: every frame of the ground truth
  std::int64_t positives = 0;  // queries with a GT match j < i - min_gap
  std::int64_t min_gap = 0;    // temporal window w, frames
  // The operating point: the loops the system declared with its own settings
  // (FrameRecord::loop), scored under the same protocol. No ground truth
  // chose them, unlike R@100P's threshold.
  std::int64_t declared_loops = 0;
  std::int64_t declared_true = 0;
  std::int64_t declared_false = 0;
  double precision_at_decision = 0;  // declared_true / declared_loops (0 when none)
  double recall_at_decision = 0;     // recalled positives / positives
  // The ranking metrics sweep a threshold over the ranking's scores
  // (FrameRecord::ranking), confirmed reports first; no decision setting
  // changes them.
  // Largest recall reached at precision exactly 1 (0 when the best-scored
  // report is already false), and the threshold that reaches it.
  double recall_at_100_precision = 0;
  double threshold_at_100_precision = 0;
  // Largest precision reached at recall 1 (0 when recall 1 is never reached).
  double precision_at_100_recall = 0;
  // Area under the PR curve, step-wise: sum over thresholds of
  // (R_k - R_{k-1}) * P_k (as scikit-learn's average_precision_score).
  double average_precision = 0;
  // The same sweep over the decision's own loop scores (FrameRecord::reported),
  // which the decision's settings change (continuity feeds decisions back
  // into later scores): for comparing decision settings, not methods.
  double decision_recall_at_100_precision = 0;
  double decision_threshold_at_100_precision = 0;
  double decision_average_precision = 0;
  // Fraction of positive queries with a GT match among their N best candidates.
  double recall_at_1 = 0;
  double recall_at_5 = 0;
  double recall_at_10 = 0;
  // Per-frame wall time of Detector::process() (conversion, segmentation,
  // descriptor, search), milliseconds; image decoding is reported apart.
  double ms_per_frame_median = 0;
  double ms_per_frame_p95 = 0;
  double ms_per_frame_mean = 0;
  // Per-stage medians, milliseconds.
  double load_ms_median = 0;  // reading + decoding the image file
  double convert_ms_median = 0;
  double segment_ms_median = 0;
  double describe_ms_median = 0;
  double search_ms_median = 0;
  double verify_ms_median = 0;
  // Per-stage 95th percentiles (nearest rank), milliseconds.
  double load_ms_p95 = 0;
  double convert_ms_p95 = 0;
  double segment_ms_p95 = 0;
  double describe_ms_p95 = 0;
  double search_ms_p95 = 0;
  double verify_ms_p95 = 0;
  // PRT = AP / (1 + omega * t), t = mean seconds per frame, omega = 10 (paper Sec. IV-D).
  double prt = 0;
  std::vector<PrPoint> curve;  // the ranking's: one point per distinct score, decreasing threshold
};

// Scores records (any order, frame ids in [0, gt.frames()), each at most once)
// under the strict protocol with temporal window min_gap. Every ground-truth
// frame is a query: a frame without a record reported nothing, so a positive
// query that was dropped, skipped or never written counts as missed, and
// records may list only the frames that reported (another system's
// detections: memory grows with its rows, not with the frame count). Metrics::
// frames is gt.frames(); timings come from the records. A reported candidate
// inside the window (j >= i - min_gap) is not allowed and counts as a false
// positive; the ranked candidates only matter for Recall@N. Throws
// InvalidArgument for a frame id outside the ground truth or a repeated frame.
Metrics evaluate(const std::vector<FrameRecord>& records, const GroundTruth& gt,
                 std::int64_t min_gap);

// The LSGDDN authors' evaluator (tools/P&R_Evaluator.py of
// BaoshengZhang0/LSGDDN-LCD), applied to one reported loop per query. It is
// lenient; use it only to compare with the paper's numbers:
// - a report on a query without a ground-truth loop j < i - min_gap is ignored
//   (such false positives are invisible);
// - a report j with |i - j| <= min_gap is dropped (their |i - j| > 50);
// - a report is correct when |j - g| < tolerance for some ground-truth loop
//   g < i - min_gap of the query (their `abs(loopinf - lcd) < 50`);
// - recall counts a loop query with any report at the threshold, right or
//   wrong, unless recall_counts_any_report is false.
struct ReferenceProtocolOptions {
  std::int64_t min_gap = 50;             // temporal window w, frames, [0, 1e9]
  std::int64_t tolerance = 50;           // correct when |j - g| < tolerance, frames, [1, 1e9]
  bool recall_counts_any_report = true;  // the authors' recall; false: only correct reports

  void check() const;  // InvalidArgument naming the field and value
};

// Scores records as evaluate() does (same checks, same output struct, the
// same threshold sweep over every distinct score) under the rules above;
// Recall@N counts a loop query when one of its N best candidates is correct
// under the same rules. Metrics::protocol is "lsgddn-reference".
Metrics evaluate_lsgddn_reference(const std::vector<FrameRecord>& records, const GroundTruth& gt,
                                  const ReferenceProtocolOptions& options = {});

// One line saying which protocol produced `m` and, for the lenient one, how
// it differs from the strict one.
std::string describe_protocol(const Metrics& m);

// Value at quantile q in [0, 1] by nearest rank (0 for an empty set).
double percentile(std::vector<double> values, double q);

}  // namespace lsgd::eval
