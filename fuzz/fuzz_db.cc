// libFuzzer target: the place database loader (lsgd::io::Database::open +
// restore) on a file written from the input. Only lsgd::Error may escape; a
// database that opens must restore into a detector that can go on.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include <opencv2/core.hpp>

#include "fuzz_util.h"
#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/io/database.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = lsgd::fuzz::temp_path(".db");
  lsgd::fuzz::write_file(path, data, size);
  try {
    const lsgd::io::Database db = lsgd::io::Database::open(path, lsgd::io::Database::Mode::kReadOnly);
    lsgd::Detector detector(db.options());
    db.restore(detector);
    if (detector.size() != db.frames()) std::abort();
    // The restored detector takes the next frame (sizes a fuzzed file may
    // claim beyond 4 Mpixel are left out: that is an allocation, not a bug).
    if (detector.size() > 0 &&
        static_cast<std::int64_t>(detector.width()) * detector.height() <= (4 << 20)) {
      const cv::Mat frame(detector.height(), detector.width(), CV_8UC1, cv::Scalar(90));
      const lsgd::Result r = detector.process(frame);
      if (r.frame != db.frames()) std::abort();
    }
  } catch (const lsgd::Error&) {
  }
  return 0;
}
