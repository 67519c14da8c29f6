// libFuzzer target: lsgd::decode_frame_description on the input, and a map
// (four stored frames) queried with what decodes: a description a robot
// sent over a network. Only lsgd::Error may escape; a query changes nothing.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include <opencv2/core.hpp>

#include "lsgd/detector.h"
#include "lsgd/error.h"

namespace {

// The options of the seeds (fuzz/make_seeds.cc, description_options()).
lsgd::Detector& map() {
  static lsgd::Detector* detector = [] {
    lsgd::DetectorOptions options;
    options.segmentation.superpixel_size = 8;
    options.search.min_gap = 1;
    auto* d = new lsgd::Detector(options);
    for (int i = 0; i < 4; ++i) {
      cv::Mat frame(48, 64, CV_8UC1);
      cv::randu(frame, 0, 255);
      d->process(frame);
    }
    return d;
  }();
  return *detector;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  lsgd::Detector& detector = map();
  try {
    const lsgd::FrameDescription d = lsgd::decode_frame_description(data, size);
    try {
      detector.query(d);
    } catch (const lsgd::InvalidArgument&) {
    }
  } catch (const lsgd::FormatError&) {
  }
  if (detector.size() != 4) std::abort();
  return 0;
}
