// libFuzzer target: lsgd::eval::load_groundtruth with format auto on a file
// written from the input: format detection, then the pairs, MAT (matio and the
// zlib stream reader), kitti-poses or loopinf reader. The first byte picks the
// file name's suffix (bit 0: .mat or .txt) and the expected frame count (bits
// 1..7: 0 .. 127); the rest is the file. Only lsgd::Error may escape.
// frames = -1 (count taken from the file) is not fuzzed: a 12-byte pairs file
// "999999999 0" then asks for a 1e9-frame GroundTruth (~24 GB), an
// out-of-memory that is a known, reported limitation (docs/reliability.md).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "fuzz_util.h"
#include "lsgd/error.h"
#include "lsgd/eval/gt_formats.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const std::string mat_path = lsgd::fuzz::temp_path(".mat");
  static const std::string txt_path = lsgd::fuzz::temp_path(".txt");
  const std::string& path = (data[0] & 1) ? mat_path : txt_path;
  lsgd::eval::GtOptions options;
  options.frames = data[0] >> 1;
  lsgd::fuzz::write_file(path, data + 1, size - 1);
  try {
    const lsgd::eval::GroundTruth gt = lsgd::eval::load_groundtruth(path, options);
    if (gt.frames() != options.frames) std::abort();
    const lsgd::eval::GtStats stats = lsgd::eval::gt_stats(gt, 1);
    if (stats.pairs != gt.pairs() || stats.frames != gt.frames()) std::abort();
  } catch (const lsgd::Error&) {
  }
  return 0;
}
