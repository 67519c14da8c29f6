#include "io/wal_check.h"

#include <sys/stat.h>

#include <array>
#include <cstring>
#include <fstream>
#include <vector>

#include "internal/check.h"

namespace lsgd::io::wal {
namespace {

using lsgd::internal::concat;

constexpr std::uint32_t kMagicLittle = 0x377f0682, kMagicBig = 0x377f0683;
constexpr std::size_t kHeaderBytes = 32, kFrameHeaderBytes = 24;

std::uint32_t be32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

// SQLite's WAL checksum over `n` bytes (a multiple of 8), continuing s.
void checksum(const unsigned char* p, std::size_t n, bool big, std::array<std::uint32_t, 2>& s) {
  for (std::size_t i = 0; i < n; i += 8) {
    std::uint32_t x0, x1;
    if (big) {
      x0 = be32(p + i);
      x1 = be32(p + i + 4);
    } else {
      std::memcpy(&x0, p + i, 4);
      std::memcpy(&x1, p + i + 4, 4);
      if constexpr (__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__) {
        x0 = __builtin_bswap32(x0);
        x1 = __builtin_bswap32(x1);
      }
    }
    s[0] += x0 + s[1];
    s[1] += x1 + s[0];
  }
}

}  // namespace

WalCheck check_wal(const std::string& wal_path) {
  WalCheck out;
  struct stat st {};
  if (::stat(wal_path.c_str(), &st) != 0) return out;
  out.bytes = static_cast<std::int64_t>(st.st_size);
  if (out.bytes == 0) return out;
  if (!S_ISREG(st.st_mode)) {
    out.damage = concat("its write-ahead log '", wal_path, "' is not a regular file");
    return out;
  }
  std::ifstream in(wal_path, std::ios::binary);
  unsigned char header[kHeaderBytes];
  if (!in.read(reinterpret_cast<char*>(header), kHeaderBytes)) {
    // A header cut short holds no frame: SQLite ignores it, nothing is lost.
    return out;
  }
  const std::uint32_t magic = be32(header);
  const std::uint32_t page = be32(header + 8);
  const bool page_ok = page >= 512 && page <= 65536 && (page & (page - 1)) == 0;
  std::array<std::uint32_t, 2> sum{0, 0};
  const bool big = magic == kMagicBig;
  if (magic == kMagicLittle || magic == kMagicBig) checksum(header, 24, big, sum);
  const bool header_ok = (magic == kMagicLittle || magic == kMagicBig) && page_ok &&
                         sum[0] == be32(header + 24) && sum[1] == be32(header + 28);
  if (!header_ok) {
    if (static_cast<std::uint64_t>(out.bytes) > kHeaderBytes) {
      out.damage = concat("its write-ahead log '", wal_path, "' (", out.bytes,
                          " bytes) has a damaged header: SQLite would ignore every frame in it");
    }
    return out;
  }
  const std::uint32_t salt1 = be32(header + 16), salt2 = be32(header + 20);
  const std::size_t frame_bytes = kFrameHeaderBytes + page;
  std::vector<unsigned char> frame(frame_bytes);
  std::int64_t index = 0;
  bool chain = true;  // every frame so far was valid
  for (;; ++index) {
    if (!in.read(reinterpret_cast<char*>(frame.data()), static_cast<std::streamsize>(frame_bytes))) {
      break;  // end of the log, or a frame cut short (a writer killed mid-write)
    }
    const bool current = be32(frame.data() + 8) == salt1 && be32(frame.data() + 12) == salt2;
    const bool commit = be32(frame.data() + 4) != 0;
    if (chain) {
      std::array<std::uint32_t, 2> next = sum;
      checksum(frame.data(), 8, big, next);
      checksum(frame.data() + kFrameHeaderBytes, page, big, next);
      if (current && next[0] == be32(frame.data() + 16) && next[1] == be32(frame.data() + 20)) {
        sum = next;
        ++out.valid_frames;
        if (commit) out.committed_frames = out.valid_frames;
        continue;
      }
      chain = false;  // SQLite stops here
      continue;
    }
    if (current && commit) {
      out.damage = concat("its write-ahead log '", wal_path, "' is damaged at byte ",
                          kHeaderBytes + static_cast<std::uint64_t>(out.valid_frames) * frame_bytes,
                          " (frame ", out.valid_frames + 1,
                          "): SQLite would silently drop the transactions committed after it, up "
                          "to frame ",
                          index + 1);
      return out;
    }
  }
  return out;
}

}  // namespace lsgd::io::wal
