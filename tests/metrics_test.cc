// Tests of the strict evaluation protocol and the LSGDDN authors' lenient one
// (eval/metrics.h), on hand-made reports whose metrics can be computed by hand.
#include "lsgd/eval/metrics.h"

#include <gtest/gtest.h>

#include "lsgd/error.h"

using lsgd::Candidate;
using lsgd::eval::FrameRecord;
using lsgd::eval::GroundTruth;

namespace {

FrameRecord report(std::int64_t frame, std::vector<Candidate> candidates, double ms = 1.0) {
  FrameRecord r;
  r.frame = frame;
  if (!candidates.empty()) r.reported = candidates.front();
  r.candidates = std::move(candidates);
  r.timings.total_ms = ms;
  return r;
}

// 10 frames, window 2. Queries 5, 6, 7 have GT loops with frames 0, 1, 2.
GroundTruth small_gt() {
  GroundTruth gt(10);
  gt.add(5, 0);
  gt.add(6, 1);
  gt.add(7, 2);
  return gt;
}

TEST(Evaluate, CountsPositivesOnlyOutsideTheWindow) {
  GroundTruth gt(10);
  gt.add(5, 0);
  gt.add(6, 5);  // inside any window >= 1: not a positive
  std::vector<FrameRecord> records;
  for (int i = 0; i < 10; ++i) records.push_back(report(i, {}));
  EXPECT_EQ(lsgd::eval::evaluate(records, gt, 2).positives, 1);
  EXPECT_EQ(lsgd::eval::evaluate(records, gt, 0).positives, 2);
  EXPECT_EQ(lsgd::eval::evaluate(records, gt, 5).positives, 0);
}

// A revisit without a record (a frame dropped, skipped or never written)
// counts as missed: records cannot raise recall by leaving frames out.
TEST(Evaluate, APositiveWithoutARecordIsMissed) {
  const std::vector<FrameRecord> some = {report(5, {{0, 0.9}}), report(6, {{1, 0.8}})};
  std::vector<FrameRecord> all = some;
  for (const int q : {0, 1, 2, 3, 4, 7, 8, 9}) all.push_back(report(q, {}));
  const auto a = lsgd::eval::evaluate(some, small_gt(), 2);
  const auto b = lsgd::eval::evaluate(all, small_gt(), 2);
  EXPECT_EQ(a.frames, 10);
  EXPECT_EQ(a.positives, 3);
  EXPECT_DOUBLE_EQ(a.recall_at_100_precision, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(a.recall_at_1, 2.0 / 3.0);
  EXPECT_EQ(a.frames, b.frames);
  EXPECT_EQ(a.positives, b.positives);
  EXPECT_DOUBLE_EQ(a.recall_at_100_precision, b.recall_at_100_precision);
  EXPECT_DOUBLE_EQ(a.average_precision, b.average_precision);
  const auto lenient = lsgd::eval::evaluate_lsgddn_reference(some, small_gt(), {2, 3, true});
  EXPECT_EQ(lenient.positives, 3);
  EXPECT_DOUBLE_EQ(lenient.recall_at_100_precision, 2.0 / 3.0);
}

TEST(Evaluate, PerfectRankingGivesFullRecallAtFullPrecision) {
  std::vector<FrameRecord> r = {report(5, {{0, 0.9}}), report(6, {{1, 0.8}}),
                                report(7, {{2, 0.85}}), report(8, {{3, 0.5}}),
                                report(9, {{4, 0.4}})};
  const auto m = lsgd::eval::evaluate(r, small_gt(), 2);
  EXPECT_EQ(m.positives, 3);
  EXPECT_DOUBLE_EQ(m.recall_at_100_precision, 1.0);
  EXPECT_DOUBLE_EQ(m.threshold_at_100_precision, 0.8);
  EXPECT_DOUBLE_EQ(m.average_precision, 1.0);
  EXPECT_DOUBLE_EQ(m.precision_at_100_recall, 1.0);
  EXPECT_DOUBLE_EQ(m.recall_at_1, 1.0);
}

TEST(Evaluate, FalsePositivesOnLoopFreeQueriesCount) {
  // The best score is a false loop on query 9, which has no GT loop at all:
  // the reference evaluator would not see it; the strict protocol does.
  std::vector<FrameRecord> r = {report(5, {{0, 0.9}}), report(6, {{1, 0.8}}),
                                report(7, {{3, 0.7}}), report(9, {{4, 0.95}})};
  const auto m = lsgd::eval::evaluate(r, small_gt(), 2);
  EXPECT_DOUBLE_EQ(m.recall_at_100_precision, 0.0);
  // Sweep: 0.95 F (P 0, R 0), 0.9 T (1/2, 1/3), 0.8 T (2/3, 2/3), 0.7 F (2/4, 2/3).
  ASSERT_EQ(m.curve.size(), 4u);
  EXPECT_DOUBLE_EQ(m.curve[2].precision, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.curve[2].recall, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.average_precision, (1.0 / 3.0) * 0.5 + (1.0 / 3.0) * (2.0 / 3.0));
  EXPECT_DOUBLE_EQ(m.precision_at_100_recall, 0.0);  // recall 1 never reached
  EXPECT_NEAR(m.recall_at_1, 2.0 / 3.0, 1e-12);
}

TEST(Evaluate, RecallAt100PrecisionStopsAtTheFirstFalsePositive) {
  std::vector<FrameRecord> r = {report(5, {{0, 0.9}}), report(6, {{4, 0.8}}),
                                report(7, {{2, 0.7}})};
  const auto m = lsgd::eval::evaluate(r, small_gt(), 2);
  EXPECT_DOUBLE_EQ(m.recall_at_100_precision, 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.threshold_at_100_precision, 0.9);
}

TEST(Evaluate, TiedScoresAreDecidedTogether) {
  // A true and a false report with the same score: no threshold separates them.
  std::vector<FrameRecord> r = {report(5, {{0, 0.9}}), report(6, {{3, 0.9}})};
  const auto m = lsgd::eval::evaluate(r, small_gt(), 2);
  ASSERT_EQ(m.curve.size(), 1u);
  EXPECT_DOUBLE_EQ(m.recall_at_100_precision, 0.0);
  EXPECT_DOUBLE_EQ(m.curve[0].precision, 0.5);
}

TEST(Evaluate, CandidateInsideTheWindowIsAFalsePositive) {
  GroundTruth gt(10);
  gt.add(5, 0);
  gt.add(5, 4);  // a GT neighbour inside the window
  std::vector<FrameRecord> r = {report(5, {{4, 0.9}})};
  const auto m = lsgd::eval::evaluate(r, gt, 2);
  EXPECT_EQ(m.positives, 1);
  EXPECT_EQ(m.curve.at(0).false_positives, 1);
  EXPECT_DOUBLE_EQ(m.recall_at_1, 0.0);
}

TEST(Evaluate, RecallAtNLooksAtTheNBestCandidates) {
  std::vector<Candidate> c;
  for (int j = 1; j <= 6; ++j) c.push_back({j, 1.0 - 0.1 * j});
  GroundTruth gt(20);
  gt.add(15, 6);  // sixth candidate
  gt.add(16, 2);  // second candidate
  std::vector<FrameRecord> r = {report(15, c), report(16, c)};
  const auto m = lsgd::eval::evaluate(r, gt, 2);
  EXPECT_DOUBLE_EQ(m.recall_at_1, 0.0);
  EXPECT_DOUBLE_EQ(m.recall_at_5, 0.5);
  EXPECT_DOUBLE_EQ(m.recall_at_10, 1.0);
}

// The operating point scores only what the system declared, under the same
// rules: a declared loop on a loop-free query is a false one; an undeclared
// report, however well scored, counts for nothing there.
TEST(Evaluate, OperatingPointScoresTheDeclaredLoops) {
  const GroundTruth gt = small_gt();
  std::vector<FrameRecord> records;
  for (int i = 0; i < 10; ++i) records.push_back(report(i, {}));
  records[5] = report(5, {{0, 9.0}});  // true, declared
  records[5].loop = true;
  records[6] = report(6, {{1, 8.0}});  // true, not declared
  records[8] = report(8, {{3, 7.5}});  // false (no loop at 8), declared
  records[8].loop = true;
  records[9] = report(9, {{4, 1.0}});  // false, not declared
  const auto m = lsgd::eval::evaluate(records, gt, 2);
  EXPECT_EQ(m.declared_loops, 2);
  EXPECT_EQ(m.declared_true, 1);
  EXPECT_EQ(m.declared_false, 1);
  EXPECT_DOUBLE_EQ(m.precision_at_decision, 0.5);
  EXPECT_DOUBLE_EQ(m.recall_at_decision, 1.0 / 3.0);
  // R@100P chooses its own threshold with the ground truth: 9 and 8, before 7.5.
  EXPECT_DOUBLE_EQ(m.recall_at_100_precision, 2.0 / 3.0);
  // Nothing declared: precision 0, recall 0.
  for (auto& r : records) r.loop = false;
  const auto none = lsgd::eval::evaluate(records, gt, 2);
  EXPECT_EQ(none.declared_loops, 0);
  EXPECT_EQ(none.precision_at_decision, 0.0);
  EXPECT_EQ(none.recall_at_decision, 0.0);
  // The lenient protocol scores the declared loops by its own rules: the
  // false loop on loop-free query 8 is invisible there.
  records[5].loop = records[8].loop = true;
  const auto lenient = lsgd::eval::evaluate_lsgddn_reference(records, gt, {2, 3, false});
  EXPECT_EQ(lenient.declared_loops, 1);
  EXPECT_EQ(lenient.declared_false, 0);
}

// R@100P, AP and the curve sweep the ranking (confirmed reports first, by
// score, then the unconfirmed ones); the decision's loop scores give the
// decision_* metrics; a record without a ranking is its report, confirmed.
TEST(Evaluate, TheRankingIsSweptConfirmedFirstAndTheDecisionApart) {
  const GroundTruth gt = small_gt();
  std::vector<FrameRecord> r = {report(5, {{0, 9.0}}), report(6, {{4, 8.0}}), report(7, {{2, 7.0}})};
  // The ranking: query 5's right place, confirmed, appearance 2; query 6's
  // wrong one, unconfirmed, appearance 5 (above it); query 7's right one,
  // confirmed, appearance 1.
  r[0].ranking = lsgd::Ranking{{0, 2.0}, true};
  r[1].ranking = lsgd::Ranking{{4, 5.0}, false};
  r[2].ranking = lsgd::Ranking{{2, 1.0}, true};
  const auto m = lsgd::eval::evaluate(r, gt, 2);
  // Ranking: 2 T, 1 T (confirmed), then 5 F (unconfirmed).
  ASSERT_EQ(m.curve.size(), 3u);
  EXPECT_TRUE(m.curve[0].confirmed);
  EXPECT_TRUE(m.curve[1].confirmed);
  EXPECT_FALSE(m.curve[2].confirmed);
  EXPECT_DOUBLE_EQ(m.curve[2].threshold, 5.0);
  EXPECT_DOUBLE_EQ(m.recall_at_100_precision, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.threshold_at_100_precision, 1.0);
  EXPECT_DOUBLE_EQ(m.average_precision, 2.0 / 3.0);
  // Decision: 9 T, 8 F, 7 T.
  EXPECT_DOUBLE_EQ(m.decision_recall_at_100_precision, 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.decision_threshold_at_100_precision, 9.0);
  EXPECT_DOUBLE_EQ(m.decision_average_precision, 1.0 / 3.0 + (1.0 / 3.0) * (2.0 / 3.0));
  // A ranking with no candidate counts at no threshold.
  r[1].ranking = lsgd::Ranking{};
  EXPECT_EQ(lsgd::eval::evaluate(r, gt, 2).curve.size(), 2u);
  // Without rankings (another system's detections) both sweeps are the reports'.
  for (FrameRecord& f : r) f.ranking.reset();
  const auto plain = lsgd::eval::evaluate(r, gt, 2);
  EXPECT_DOUBLE_EQ(plain.recall_at_100_precision, plain.decision_recall_at_100_precision);
  EXPECT_DOUBLE_EQ(plain.average_precision, plain.decision_average_precision);
  EXPECT_DOUBLE_EQ(plain.threshold_at_100_precision, 9.0);
  // The lenient protocol sweeps the ranking too.
  r[0].ranking = lsgd::Ranking{{0, 2.0}, true};
  r[1].ranking = lsgd::Ranking{{4, 5.0}, false};
  r[2].ranking = lsgd::Ranking{{2, 1.0}, true};
  const auto lenient = lsgd::eval::evaluate_lsgddn_reference(r, gt, {2, 1, false});
  // (It drops query 6's reports of frame 4, |6 - 4| <= 2: 2 T and 1 T;
  // 9 T and 7 T.)
  EXPECT_DOUBLE_EQ(lenient.recall_at_100_precision, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(lenient.threshold_at_100_precision, 1.0);
  EXPECT_DOUBLE_EQ(lenient.decision_recall_at_100_precision, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(lenient.decision_threshold_at_100_precision, 7.0);
}

TEST(Evaluate, TimingsAndPrt) {
  std::vector<FrameRecord> r;
  for (int i = 0; i < 10; ++i) r.push_back(report(i, {}, i + 1.0));  // 1..10 ms
  r[3].timings.segment_ms = 7;
  const auto m = lsgd::eval::evaluate(r, small_gt(), 2);
  EXPECT_DOUBLE_EQ(m.ms_per_frame_median, 5.0);
  EXPECT_DOUBLE_EQ(m.ms_per_frame_p95, 10.0);
  EXPECT_DOUBLE_EQ(m.ms_per_frame_mean, 5.5);
  EXPECT_DOUBLE_EQ(m.segment_ms_median, 0.0);
  EXPECT_DOUBLE_EQ(m.segment_ms_p95, 7.0);  // nearest rank: the 10th of 10 values
  EXPECT_DOUBLE_EQ(m.search_ms_p95, 0.0);
  EXPECT_DOUBLE_EQ(m.prt, 0.0);  // AP 0 without reports
}

TEST(Evaluate, EmptyAndInvalidInput) {
  const auto m = lsgd::eval::evaluate({}, small_gt(), 2);
  EXPECT_EQ(m.frames, 10);    // every ground-truth frame is a query
  EXPECT_EQ(m.positives, 3);  // ... and its revisits are missed
  EXPECT_DOUBLE_EQ(m.average_precision, 0.0);
  EXPECT_THROW(lsgd::eval::evaluate({report(10, {})}, small_gt(), 2), lsgd::InvalidArgument);
  EXPECT_THROW(lsgd::eval::evaluate({report(3, {}), report(3, {})}, small_gt(), 2),
               lsgd::InvalidArgument);
  EXPECT_THROW(lsgd::eval::evaluate({}, small_gt(), -1), lsgd::InvalidArgument);
}

// ---------------------------------------------------------------- lsgddn-reference

using lsgd::eval::evaluate_lsgddn_reference;
using lsgd::eval::ReferenceProtocolOptions;

// 300 frames; queries 200, 201, 202 revisit frames 10, 11, 12.
GroundTruth far_gt() {
  GroundTruth gt(300);
  gt.add(200, 10);
  gt.add(201, 11);
  gt.add(202, 12);
  return gt;
}

// The same 300 frames with only query 200's revisit of frame 10.
GroundTruth one_gt() {
  GroundTruth gt(300);
  gt.add(200, 10);
  return gt;
}

TEST(ReferenceProtocol, FalsePositiveOnALoopFreeQueryIsInvisible) {
  // Query 250 has no GT loop; its false report has the best score.
  std::vector<FrameRecord> r = {report(200, {{10, 0.9}}), report(201, {{11, 0.8}}),
                                report(202, {{12, 0.7}}), report(250, {{100, 0.95}})};
  const auto strict = lsgd::eval::evaluate(r, far_gt(), 50);
  EXPECT_DOUBLE_EQ(strict.recall_at_100_precision, 0.0);
  // 0.95 F, 0.9 T (1/2, 1/3), 0.8 T (2/3, 2/3), 0.7 T (3/4, 1).
  EXPECT_DOUBLE_EQ(strict.average_precision, (0.5 + 2.0 / 3.0 + 0.75) / 3.0);
  const auto lenient = evaluate_lsgddn_reference(r, far_gt());
  EXPECT_EQ(lenient.positives, 3);
  EXPECT_DOUBLE_EQ(lenient.recall_at_100_precision, 1.0);
  EXPECT_DOUBLE_EQ(lenient.threshold_at_100_precision, 0.7);
  EXPECT_DOUBLE_EQ(lenient.average_precision, 1.0);
  EXPECT_EQ(lenient.curve.size(), 3u);  // the 0.95 report never enters the sweep
  EXPECT_EQ(lenient.frames, 300);
}

TEST(ReferenceProtocol, AcceptsAMatchWithinTheTolerance) {
  // One query (one positive) whose report is 30 frames off GT frame 10.
  std::vector<FrameRecord> r = {report(200, {{40, 0.9}})};
  EXPECT_DOUBLE_EQ(lsgd::eval::evaluate(r, one_gt(), 50).recall_at_100_precision, 0.0);
  EXPECT_DOUBLE_EQ(evaluate_lsgddn_reference(r, one_gt()).recall_at_100_precision, 1.0);
  EXPECT_DOUBLE_EQ(evaluate_lsgddn_reference(r, one_gt()).recall_at_1, 1.0);
  ReferenceProtocolOptions tight;
  tight.tolerance = 30;  // |40 - 10| < 30 is false
  EXPECT_DOUBLE_EQ(evaluate_lsgddn_reference(r, one_gt(), tight).recall_at_100_precision, 0.0);
  tight.tolerance = 31;
  EXPECT_DOUBLE_EQ(evaluate_lsgddn_reference(r, one_gt(), tight).recall_at_100_precision, 1.0);
  // 50 off is outside the default tolerance: the evaluator tests |j - g| < 50.
  std::vector<FrameRecord> off = {report(200, {{60, 0.9}})};
  EXPECT_DOUBLE_EQ(evaluate_lsgddn_reference(off, one_gt()).recall_at_100_precision, 0.0);
  EXPECT_EQ(evaluate_lsgddn_reference(off, one_gt()).curve.at(0).false_positives, 1);
}

TEST(ReferenceProtocol, ReportsInsideTheExclusionAreDropped) {
  std::vector<FrameRecord> r = {report(200, {{150, 0.9}})};           // |i - j| = 50: excluded
  EXPECT_EQ(lsgd::eval::evaluate(r, far_gt(), 50).curve.size(), 1u);  // strict: a false positive
  const auto lenient = evaluate_lsgddn_reference(r, far_gt());
  EXPECT_TRUE(lenient.curve.empty());
  EXPECT_EQ(lenient.min_gap, 50);
}

TEST(ReferenceProtocol, GroundTruthNeighboursInsideTheWindowDoNotCount) {
  GroundTruth gt = far_gt();
  gt.add(200, 198);  // a temporal neighbour, as pose-derived ground truth has
  std::vector<FrameRecord> r = {report(200, {{149, 0.9}})};  // 49 from 198, far from 10
  EXPECT_DOUBLE_EQ(evaluate_lsgddn_reference(r, gt).recall_at_100_precision, 0.0);
}

TEST(ReferenceProtocol, RecallCountsAnyReportOnALoopQuery) {
  // 0.9 correct, 0.8 wrong (129 off), query 202 reports nothing.
  std::vector<FrameRecord> r = {report(200, {{10, 0.9}}), report(201, {{140, 0.8}}),
                                report(202, {})};
  const auto m = evaluate_lsgddn_reference(r, far_gt());
  ASSERT_EQ(m.curve.size(), 2u);
  EXPECT_DOUBLE_EQ(m.curve[1].recall, 2.0 / 3.0);  // the wrong report counts for recall
  EXPECT_DOUBLE_EQ(m.curve[1].precision, 0.5);
  EXPECT_DOUBLE_EQ(m.recall_at_100_precision, 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.average_precision, 1.0 / 3.0 + (1.0 / 3.0) * 0.5);
  ReferenceProtocolOptions correct_only;
  correct_only.recall_counts_any_report = false;
  const auto c = evaluate_lsgddn_reference(r, far_gt(), correct_only);
  EXPECT_DOUBLE_EQ(c.curve[1].recall, 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(c.average_precision, 1.0 / 3.0);
}

TEST(ReferenceProtocol, RecallAtNUsesTheSameTolerance) {
  std::vector<FrameRecord> r = {report(200, {{120, 0.9}, {100, 0.8}, {30, 0.7}})};
  const auto m = evaluate_lsgddn_reference(r, one_gt());
  EXPECT_DOUBLE_EQ(m.recall_at_1, 0.0);
  EXPECT_DOUBLE_EQ(m.recall_at_5, 1.0);  // 30 is 20 off frame 10 (one positive query)
}

TEST(ReferenceProtocol, SaysWhichProtocolItIs) {
  const auto strict = lsgd::eval::evaluate({}, far_gt(), 50);
  EXPECT_EQ(strict.protocol, "strict");
  EXPECT_NE(lsgd::eval::describe_protocol(strict).find("strict"), std::string::npos);
  const auto lenient = evaluate_lsgddn_reference({}, far_gt());
  EXPECT_EQ(lenient.protocol, "lsgddn-reference");
  EXPECT_EQ(lenient.tolerance, 50);
  const std::string text = lsgd::eval::describe_protocol(lenient);
  EXPECT_NE(text.find("lenient"), std::string::npos) << text;
  EXPECT_NE(text.find("49 frames"), std::string::npos) << text;
}

TEST(ReferenceProtocol, InvalidInput) {
  ReferenceProtocolOptions bad;
  bad.tolerance = 0;
  EXPECT_THROW(evaluate_lsgddn_reference({}, far_gt(), bad), lsgd::InvalidArgument);
  bad = {};
  bad.min_gap = -1;
  EXPECT_THROW(evaluate_lsgddn_reference({}, far_gt(), bad), lsgd::InvalidArgument);
  EXPECT_THROW(evaluate_lsgddn_reference({report(300, {})}, far_gt()), lsgd::InvalidArgument);
  EXPECT_THROW(evaluate_lsgddn_reference({report(3, {}), report(3, {})}, far_gt()),
               lsgd::InvalidArgument);
}

TEST(Percentile, NearestRank) {
  EXPECT_DOUBLE_EQ(lsgd::eval::percentile({}, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(lsgd::eval::percentile({3, 1, 2}, 0.5), 2.0);
  EXPECT_DOUBLE_EQ(lsgd::eval::percentile({3, 1, 2}, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(lsgd::eval::percentile({3, 1, 2}, 1.0), 3.0);
  EXPECT_DOUBLE_EQ(lsgd::eval::percentile({4, 1, 2, 3}, 0.5), 2.0);
}

}  // namespace
