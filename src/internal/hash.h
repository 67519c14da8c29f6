// FNV-1a, 64 bits: a short, stable name for a text (the describing options'
// key, a temporary file's name). Not for security. Header-only.
#pragma once

#include <cstdint>
#include <string_view>

namespace lsgd::internal {

constexpr std::uint64_t kFnvOffset = 14695981039346656037ULL;

// The hash of `text` continued from `h` (kFnvOffset for a new one), so that
// several texts can be hashed as one.
inline std::uint64_t fnv1a(std::string_view text, std::uint64_t h = kFnvOffset) {
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ULL;
  }
  return h;
}

}  // namespace lsgd::internal
