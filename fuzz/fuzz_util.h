// Shared helpers of the libFuzzer targets: a per-process temporary file that
// holds the input for readers that take a path.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace lsgd::fuzz {

// Path of this process's scratch file with the given suffix, in $TMPDIR or /tmp.
inline std::string temp_path(const std::string& suffix) {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir && *dir ? dir : "/tmp") + "/lsgd_fuzz_" + std::to_string(getpid()) +
         suffix;
}

// Writes the bytes to `path`; aborts when it cannot (an environment problem,
// not a finding).
inline void write_file(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size && std::fwrite(data, 1, size, f) != size) std::abort();
  if (std::fclose(f) != 0) std::abort();
}

}  // namespace lsgd::fuzz
