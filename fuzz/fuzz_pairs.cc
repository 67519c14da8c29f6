// libFuzzer target: lsgd::eval::read_pairs on a file written from the input.
// The first byte picks the expected frame count (-1, or 0 .. 254); the rest is
// the file. Only lsgd::Error may escape.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "fuzz_util.h"
#include "lsgd/error.h"
#include "lsgd/eval/groundtruth.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::int64_t frames = data[0] == 255 ? -1 : static_cast<std::int64_t>(data[0]);
  static const std::string path = lsgd::fuzz::temp_path(".txt");
  lsgd::fuzz::write_file(path, data + 1, size - 1);
  try {
    const lsgd::eval::GroundTruth gt = lsgd::eval::read_pairs(path, frames);
    if (frames >= 0 && gt.frames() != frames) std::abort();
    for (std::int64_t q = 0; q < gt.frames(); ++q)
      for (std::int64_t m : gt.matches(q))
        if (m < 0 || m >= q || !gt.is_loop(q, m)) std::abort();
  } catch (const lsgd::Error&) {
  }
  return 0;
}
