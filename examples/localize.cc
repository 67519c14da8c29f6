// Localises a camera against a saved map without changing it: the map is
// opened read-only, restored into a detector, and the images of a folder are
// answered against it.
//
//   lsgd_example_localize DATABASE FOLDER [FIRST]
//
// The first image is a relocalisation: Detector::query() answers as
// process() would, storing nothing. The images after it are a new session:
// process() keeps them in the detector's memory (each then has the sequence
// of the session's frames before it), and the file never changes. Last, the
// map's oldest frames are forgotten (a working memory of bounded size).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <lsgd/detector.h>
#include <lsgd/error.h>
#include <lsgd/io/database.h>
#include <lsgd/io/sequence.h>
#include <opencv2/core.hpp>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s DATABASE FOLDER [FIRST]\n", argv[0]);
    return 2;
  }
  const std::string path = argv[1];
  try {
    const lsgd::io::Database map = lsgd::io::Database::open(path, lsgd::io::Database::Mode::kReadOnly);
    lsgd::Detector detector(map.options());
    map.restore(detector);
    const std::int64_t mapped = detector.size();
    const lsgd::io::Sequence sequence = lsgd::io::open_sequence(argv[2]);
    const std::size_t first = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 0;
    if (first >= sequence.images.size()) {
      std::fprintf(stderr, "error: %s has %zu images, none from %zu\n", argv[2],
                   sequence.images.size(), first);
      return 1;
    }

    // Where am I? Nothing is stored: the map is as it was.
    const cv::Mat image = lsgd::io::read_image(sequence.images[first]);
    const lsgd::Result where = detector.query(image);  // relocalisation: nothing stored
    std::printf("relocalised: best place %lld (appearance %.2f sigma, %s)\n",
                static_cast<long long>(where.ranking.best.frame), where.ranking.best.score,
                where.loop ? "a loop" : "no loop");

    detector.cut();  // then a session in memory: it continues no loop of the map's last frames
    int localised = 0, loops = 0;
    for (std::size_t i = first; i < sequence.images.size(); ++i) {
      const cv::Mat image = lsgd::io::read_image(sequence.images[i]);
      const lsgd::Result r = detector.process(image);
      loops += r.loop ? 1 : 0;
      if (r.loop && r.best.frame < mapped) ++localised;  // a place of the map
    }
    std::printf("%d of %zu images localised in the map of %lld frames (%d loops in all)\n",
                localised, sequence.images.size() - first, static_cast<long long>(mapped), loops);

    // A working memory of bounded size: the oldest frames go, by their ids
    // (the kept frames keep theirs; their frame numbers close up).
    const std::int64_t forgotten = detector.forget(0, detector.id_of(49));  // the map's first 50 frames
    std::printf("forgot %lld frames: %lld kept, ids %lld .. %lld\n", static_cast<long long>(forgotten),
                static_cast<long long>(detector.size()), static_cast<long long>(detector.id_of(0)),
                static_cast<long long>(detector.id_of(detector.size() - 1)));
    return 0;
  } catch (const lsgd::Error& e) {  // IoError, FormatError, InvalidArgument, each naming the file
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
