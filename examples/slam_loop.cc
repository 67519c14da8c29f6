// Feeds the frames of a folder (or an image list) to the detector one at a
// time, as a SLAM front end would, and prints every loop it declares.
//
//   lsgd_example_slam_loop FOLDER [MIN_GAP]
#include <cstdio>
#include <cstdlib>
#include <lsgd/detector.h>
#include <lsgd/error.h>
#include <lsgd/io/sequence.h>
#include <opencv2/core.hpp>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s FOLDER [MIN_GAP]\n", argv[0]);
    return 2;
  }
  try {
    lsgd::DetectorOptions options;  // the shipped defaults: docs/options.md
    options.search.min_gap = argc > 2 ? std::atoll(argv[2]) : 50;  // recent frames are never loops
    lsgd::Detector detector(options);  // validates the options: lsgd::InvalidArgument

    const lsgd::io::Sequence sequence = lsgd::io::open_sequence(argv[1]);
    int loops = 0;
    for (const std::string& path : sequence.images) {
      try {
        const cv::Mat image = lsgd::io::read_image(path);  // gray, BGR or BGRA, 8-bit
        const lsgd::Result r = detector.process(image);     // ids 0, 1, 2, ... in call order
        if (r.loop) {
          // r.best.score: loop evidence in sigma; r.evidence: appearance,
          // inliers, continues; r.candidates: top-N; r.verification: verdicts.
          std::printf("frame %lld closes a loop with frame %lld (score %.2f, %d inliers)\n",
                      static_cast<long long>(r.frame), static_cast<long long>(r.best.frame),
                      r.best.score, r.evidence.inliers);
          ++loops;
        }
      } catch (const lsgd::Error& e) {  // a bad frame: the detector is unchanged
        std::fprintf(stderr, "skipped %s: %s\n", path.c_str(), e.what());
      }
    }
    std::printf("%lld frames, %d loops\n", static_cast<long long>(detector.size()), loops);
    return 0;
  } catch (const lsgd::Error& e) {  // bad options, missing folder
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
