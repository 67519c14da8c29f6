// Keeps the detector's places in a database, so that the next run of the
// program (a robot restarting) continues where the last one stopped.
//
//   lsgd_example_resume_database DATABASE FOLDER [FIRST [COUNT]]
//
// Processes images FIRST .. FIRST+COUNT-1 of FOLDER (default: all) after the
// frames the database already holds.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <lsgd/detector.h>
#include <lsgd/error.h>
#include <lsgd/io/database.h>
#include <lsgd/io/sequence.h>
#include <opencv2/core.hpp>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s DATABASE FOLDER [FIRST [COUNT]]\n", argv[0]);
    return 2;
  }
  const std::string path = argv[1];
  try {
    // Open the database, or create it with the options of its detector.
    lsgd::DetectorOptions options;
    options.search.min_gap = 50;
    lsgd::io::Database db = std::filesystem::exists(path)
                                ? lsgd::io::Database::open(path)
                                : lsgd::io::Database::create(path, options);
    lsgd::Detector detector(db.options());  // the stored options
    db.restore(detector);  // the stored frames, as if never stopped
    std::printf("%s holds %lld frames\n", path.c_str(), static_cast<long long>(db.frames()));

    const lsgd::io::Sequence sequence = lsgd::io::open_sequence(argv[2]);
    const std::size_t first = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 0;
    const std::size_t count = argc > 4 ? std::strtoull(argv[4], nullptr, 10) : sequence.images.size();
    const std::int64_t session = db.last_session() + 1;  // this run's frames
    for (std::size_t i = first; i < sequence.images.size() && i < first + count; ++i) {
      const cv::Mat image = lsgd::io::read_image(sequence.images[i]);
      const lsgd::Result r = detector.process(image);
      db.append(detector, r, session, sequence.images[i]);  // one transaction per frame
      if (r.loop) {
        std::printf("frame %lld closes a loop with frame %lld\n",
                    static_cast<long long>(r.frame), static_cast<long long>(r.best.frame));
      }
    }
    std::printf("%s holds %lld frames\n", path.c_str(), static_cast<long long>(db.frames()));
    return 0;
  } catch (const lsgd::Error& e) {  // IoError, FormatError, InvalidArgument, each naming the file
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
