// Scores the detector on a sequence with loop ground truth under the strict
// protocol (docs/evaluation.md): the loops it declares with its settings (the
// operating point) next to R@100P, AP and Recall@1.
//
//   lsgd_example_evaluate SEQUENCE GROUND_TRUTH MIN_GAP
//
// SEQUENCE: a folder, an image list or a dataset layout (KITTI, FAB-MAP,
// NEU); GROUND_TRUTH: any format lsgd reads (pairs, .mat, KITTI poses, loopinf).
#include <cstdio>
#include <cstdlib>
#include <lsgd/detector.h>
#include <lsgd/error.h>
#include <lsgd/eval/dataset.h>
#include <lsgd/eval/metrics.h>
#include <lsgd/eval/runner.h>

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s SEQUENCE GROUND_TRUTH MIN_GAP\n", argv[0]);
    return 2;
  }
  try {
    const std::int64_t min_gap = std::atoll(argv[3]);
    const lsgd::eval::Dataset dataset = lsgd::eval::open_dataset(argv[1], {}, argv[2]);
    lsgd::DetectorOptions options;
    options.search.min_gap = min_gap;
    lsgd::Detector detector(options);
    const std::vector<lsgd::eval::FrameRecord> records =
        lsgd::eval::run_detector(detector, lsgd::eval::sequence_source(dataset.frames));
    const lsgd::eval::Metrics m = lsgd::eval::evaluate(records, dataset.gt, min_gap);
    std::printf("%lld frames, %lld with a loop\n", static_cast<long long>(m.frames),
                static_cast<long long>(m.positives));
    std::printf("declared %lld loops (%lld true, %lld false), recall %.3f\n",
                static_cast<long long>(m.declared_loops), static_cast<long long>(m.declared_true),
                static_cast<long long>(m.declared_false), m.recall_at_decision);
    std::printf("R@100P %.3f  AP %.3f  R@1 %.3f  %.2f ms/frame median\n",
                m.recall_at_100_precision, m.average_precision, m.recall_at_1,
                m.ms_per_frame_median);
    return 0;
  } catch (const lsgd::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
