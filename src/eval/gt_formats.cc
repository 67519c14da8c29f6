#include "lsgd/io/files.h"
#include "lsgd/eval/gt_formats.h"

#include <matio.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <utility>

#include "internal/check.h"
#include "internal/registry.h"
#include "internal/numbers.h"
#include "lsgd/error.h"
#include "lsgd/io/sequence.h"
#include "lsgd/limits.h"

namespace lsgd::eval {

using internal::concat;

namespace {

// ---- text helpers ---------------------------------------------------------

std::ifstream open_text(const std::string& path, const char* what) {
  io::check_input_file(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(concat("cannot open ", what, " '", path, "'"));
  io::skip_utf8_bom(in);
  return in;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// Whitespace-separated fields of a line; empty for blank and '#' comment lines.
std::vector<std::string> fields_of(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t i = 0;
  while (true) {
    while (i < line.size() && is_space(line[i])) ++i;
    if (i == line.size() || (fields.empty() && line[i] == '#')) break;
    std::size_t end = i;
    while (end < line.size() && !is_space(line[end])) ++end;
    fields.push_back(line.substr(i, end - i));
    i = end;
  }
  return fields;
}

bool parse_int(const std::string& text, long long& value) { return internal::parses_as(text, value); }

bool parse_double(const std::string& text, double& value) { return internal::parses_as(text, value); }

// ---- detection --------------------------------------------------------------

bool has_mat_extension(const std::string& path) {
  if (path.size() < 4) return false;
  std::string ext = path.substr(path.size() - 4);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".mat";
}

// What the text lines of a file look like, gathered in one pass.
struct TextShape {
  std::int64_t lines = 0;       // data lines
  std::size_t columns = 0;      // fields per data line (all equal, else an error)
  bool integers = true;         // every field an integer
  bool minus_one = false;       // some second field is -1
  bool other_negative = false;  // some other negative value
  bool consecutive = true;      // data line k starts with k
  bool tabs = true;             // every data line contains a tab
};

TextShape text_shape(std::istream& in, const std::string& path) {
  TextShape shape;
  std::string line;
  for (std::int64_t number = 1; io::read_line(in, line, path, number); ++number) {
    const auto fields = fields_of(line);
    if (fields.empty()) continue;
    if (shape.lines == 0) shape.columns = fields.size();
    if (fields.size() != shape.columns) {
      throw FormatError(concat("cannot tell the ground-truth format of '", path, "': line ", number,
                               " has ", fields.size(), " fields, the first data line ",
                               shape.columns, "; pass the format explicitly"));
    }
    for (std::size_t f = 0; f < fields.size(); ++f) {
      long long iv = 0;
      double dv = 0;
      if (parse_int(fields[f], iv)) {
        if (f == 0 && iv != shape.lines) shape.consecutive = false;
        if (iv == -1 && f == 1) {
          shape.minus_one = true;
        } else if (iv < 0) {
          shape.other_negative = true;
        }
      } else if (parse_double(fields[f], dv)) {
        shape.integers = false;
      } else {
        throw FormatError(concat("cannot tell the ground-truth format of '", path, "': line ",
                                 number, ": '", fields[f], "' is not a number"));
      }
    }
    shape.tabs = shape.tabs && line.find('\t') != std::string::npos;
    ++shape.lines;
  }
  return shape;
}

// ---- pairs with the frame count taken from the file ------------------------

GroundTruth read_pairs_counted(const std::string& path, std::int64_t frames) {
  if (frames >= 0) return read_pairs(path, frames);
  std::ifstream in = open_text(path, "ground-truth file");
  long long max_id = -1;
  std::string line;
  for (std::int64_t number = 1; io::read_line(in, line, path, number); ++number) {
    const auto fields = fields_of(line);
    long long a = 0, b = 0;
    if (fields.size() == 2 && parse_int(fields[0], a) && parse_int(fields[1], b)) {
      max_id = std::max({max_id, a, b});
    }
  }
  if (max_id >= kMaxFrames) {
    throw FormatError(concat(path, ": frame id ", max_id, " is implausibly large (at most ",
                             kMaxFrames, " frames are supported)"));
  }
  // Malformed lines are left to read_pairs, which names them.
  return read_pairs(path, max_id + 1);
}

// ---- MAT files (matio) ------------------------------------------------------

// matio reports problems through a log callback (by default printed to
// stderr). We install one that keeps the last error of this thread instead, so
// a failed read becomes a FormatError quoting it; warnings are dropped.
thread_local std::string matio_last_message;

void matio_log(int level, char* message) {
  if (level & (MATIO_LOG_LEVEL_ERROR | MATIO_LOG_LEVEL_CRITICAL)) {
    matio_last_message = message ? message : "";
  }
}

std::string matio_detail() {
  return matio_last_message.empty() ? "" : concat(" (matio: ", matio_last_message, ")");
}

// ---- MAT container checks and the streaming fast path ------------------------
//
// Layouts from the MAT-file format reference (MathWorks, "MAT-File Format",
// 2019). v5: a 128-byte header, then top-level elements, each an 8-byte tag
// (uint32 type, uint32 byte count) and its bytes (padded to 8 unless
// compressed). A miCOMPRESSED element is a zlib stream holding one miMATRIX
// element: array flags (class in the low byte), dimensions, name, real part.
// A sub-element whose first word has nonzero upper 16 bits is "small": type
// in the low 16 bits, byte count in the high 16, data in the next 4 bytes.
// v4: per variable a 20-byte header (MOPT type, rows, cols, imagf, name
// length), the name and rows x cols values (twice when complex).

constexpr std::uint32_t kMiMatrix = 14, kMiCompressed = 15;

std::uint32_t u32(const unsigned char* p, bool swap) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  return swap ? __builtin_bswap32(v) : v;
}

struct V5Element {
  std::uint64_t offset;  // of the tag
  std::uint32_t type, bytes;
};

struct Container {
  bool swapped = false;             // v5 written with the other byte order
  std::vector<V5Element> elements;  // v5 top-level elements
};

// matio trusts the byte counts in a file: a truncated file reads as zeros
// (fewer loops) without an error. So every top-level element must fit first.
Container check_container(const std::string& path, mat_ft version) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  const auto size = static_cast<std::uint64_t>(in.tellg());
  const auto truncated = [&](std::uint64_t at, std::uint64_t need) {
    return FormatError(concat("'", path, "' is truncated or corrupt: the element at byte ", at,
                              " needs ", need, " bytes, the file has ", size - at));
  };
  const auto read_at = [&](std::uint64_t at, unsigned char* out, std::size_t n) {
    in.seekg(static_cast<std::streamoff>(at));
    in.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(n));
    if (!in) throw IoError(concat("error while reading '", path, "'"));
  };
  Container c;
  unsigned char b[20];
  if (version == MAT_FT_MAT5) {
    if (size < 128) throw truncated(0, 128);
    read_at(126, b, 2);
    c.swapped = b[0] == 'M' && b[1] == 'I';
    for (std::uint64_t pos = 128; pos < size;) {
      if (size - pos < 8) throw truncated(pos, 8);
      read_at(pos, b, 8);
      const V5Element e{pos, u32(b, c.swapped), u32(b + 4, c.swapped)};
      if (e.bytes > size - pos - 8) throw truncated(pos, std::uint64_t{e.bytes} + 8);
      if (e.type == kMiMatrix) {
        // matio allocates what the flags, dimensions and name sub-elements
        // claim before reading them: each must fit its matrix element.
        std::uint64_t at = pos + 8;
        const std::uint64_t end = at + e.bytes;
        for (int sub = 0; sub < 3 && at < end; ++sub) {
          if (end - at < 8) throw truncated(at, 8);
          read_at(at, b, 8);
          const std::uint32_t first = u32(b, c.swapped);
          if ((first >> 16) != 0) {  // small element: type and size in one word, data inline
            at += 8;
            continue;
          }
          const std::uint64_t bytes = u32(b + 4, c.swapped);
          if (bytes > end - at - 8) throw truncated(at, bytes + 8);
          at += 8 + (bytes + 7) / 8 * 8;
        }
      }
      c.elements.push_back(e);
      pos += 8 + std::uint64_t{e.bytes};
      if (e.type != kMiCompressed) pos = std::min(size, (pos + 7) / 8 * 8);
    }
  } else if (version == MAT_FT_MAT4) {
    for (std::uint64_t pos = 0; pos < size;) {
      if (size - pos < 20) throw truncated(pos, 20);
      read_at(pos, b, 20);
      const bool swap = u32(b, false) > 9999;  // MOPT with M = 1: big-endian
      const std::uint64_t type = u32(b, swap), rows = u32(b + 4, swap), cols = u32(b + 8, swap);
      const std::uint64_t parts = u32(b + 12, swap) ? 2 : 1, name = u32(b + 16, swap);
      static constexpr std::uint64_t kElem[] = {8, 4, 4, 2, 2, 1};
      const std::uint64_t p = (type / 10) % 10;
      if (p > 5 || rows * cols > (std::uint64_t{1} << 50)) {
        throw FormatError(concat("'", path, "': corrupt MAT v4 header at byte ", pos));
      }
      const std::uint64_t need = 20 + name + rows * cols * kElem[p] * parts;
      if (need > size - pos) throw truncated(pos, need);
      pos += need;
    }
  }
  return c;
}

// Pulls exact byte counts out of one zlib stream held in memory.
class Inflater {
 public:
  Inflater(const std::string& path, std::string compressed)
      : path_(path), input_(std::move(compressed)) {
    z_.next_in = reinterpret_cast<Bytef*>(input_.data());
    z_.avail_in = static_cast<uInt>(input_.size());
    if (inflateInit(&z_) != Z_OK) throw FormatError(concat("zlib cannot start on '", path, "'"));
  }
  ~Inflater() { inflateEnd(&z_); }
  Inflater(const Inflater&) = delete;
  Inflater& operator=(const Inflater&) = delete;

  // Fills out[0, n) or throws FormatError (corrupt or truncated stream).
  void read(void* out, std::size_t n) {
    z_.next_out = static_cast<Bytef*>(out);
    z_.avail_out = static_cast<uInt>(n);
    while (z_.avail_out > 0) {
      const int rc = inflate(&z_, Z_NO_FLUSH);
      if (rc == Z_OK) continue;
      if (rc == Z_STREAM_END && z_.avail_out == 0) break;
      const bool early = rc == Z_STREAM_END || (rc == Z_BUF_ERROR && z_.avail_in == 0);
      throw FormatError(concat("'", path_, "' is corrupt: compressed data ",
                               early ? "ends early" : "does not inflate", " (zlib ", rc,
                               z_.msg ? concat(": ", z_.msg) : "", ")"));
    }
  }
  // Reads the rest of the stream, at most `limit` bytes, to its end, where
  // zlib checks the stream's Adler-32: a damaged stream that still inflated
  // to plausible bytes is a FormatError here.
  void finish(std::uint64_t limit) {
    char buffer[4096];
    for (;;) {
      z_.next_out = reinterpret_cast<Bytef*>(buffer);
      z_.avail_out = sizeof buffer;
      const int rc = inflate(&z_, Z_NO_FLUSH);
      const std::uint64_t produced = sizeof buffer - z_.avail_out;
      if (rc == Z_STREAM_END && produced <= limit) return;
      if (rc == Z_OK && produced <= limit && produced > 0) {
        limit -= produced;
        continue;
      }
      throw FormatError(concat("'", path_, "' is corrupt: compressed data ",
                               produced > limit ? "holds more than its variable" :
                               rc == Z_DATA_ERROR ? "fails its check" : "ends early",
                               " (zlib ", rc, z_.msg ? concat(": ", z_.msg) : "", ")"));
    }
  }
  // Reads one sub-element tag: {type, byte count, inline data, 1 if small}.
  std::array<std::uint32_t, 4> tag() {
    std::uint32_t w[2];
    read(w, 8);
    if (w[0] >> 16) return {w[0] & 0xFFFF, w[0] >> 16, w[1], 1};
    return {w[0], w[1], 0, 0};
  }
  void skip(std::size_t n) {
    char buffer[256];
    for (; n > 0; n -= std::min(n, sizeof buffer)) read(buffer, std::min(n, sizeof buffer));
  }

 private:
  std::string path_;
  std::string input_;
  z_stream z_{};
};

// The zlib stream of a compressed v5 element (after its 8-byte tag).
std::string compressed_bytes(const std::string& path, const V5Element& e) {
  std::string bytes(e.bytes, '\0');
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(e.offset + 8));
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!in) throw IoError(concat("error while reading '", path, "'"));
  return bytes;
}

// Calls f(T{}) with the C++ type of a MAT numeric data type; false for others.
template <typename F>
bool with_value_type(std::uint32_t type, F&& f) {
  switch (type) {
    case MAT_T_DOUBLE:
      f(double{});
      return true;
    case MAT_T_SINGLE:
      f(float{});
      return true;
    case MAT_T_INT8:
      f(std::int8_t{});
      return true;
    case MAT_T_UINT8:
      f(std::uint8_t{});
      return true;
    case MAT_T_INT16:
      f(std::int16_t{});
      return true;
    case MAT_T_UINT16:
      f(std::uint16_t{});
      return true;
    case MAT_T_INT32:
      f(std::int32_t{});
      return true;
    case MAT_T_UINT32:
      f(std::uint32_t{});
      return true;
    case MAT_T_INT64:
      f(std::int64_t{});
      return true;
    case MAT_T_UINT64:
      f(std::uint64_t{});
      return true;
    default:
      return false;
  }
}

// True when GT(r, c) = v is a loop; a NaN entry is a FormatError.
template <typename T>
bool is_loop_value(T v, std::size_t r, std::size_t c, const std::string& path) {
  if constexpr (std::is_floating_point_v<T>) {
    if (std::isnan(v)) {
      throw FormatError(concat("'", path, "': entry (", r + 1, ", ", c + 1, ") is NaN"));
    }
  }
  return v != T(0);
}

// Adds the loop GT(k % n, k / n) for each nonzero values[i], k = k0 + i
// (MATLAB stores column-major). Published matrices are >99.9% zeros, so
// 1-byte types (uint8, logical) skip zeros eight at a time.
template <typename T>
void add_nonzero(const T* values, std::size_t count, std::size_t k0, std::size_t n, GroundTruth& gt,
                 const std::string& path) {
  for (std::size_t i = 0; i < count; ++i) {
    if constexpr (sizeof(T) == 1) {
      std::uint64_t word = 1;
      if (i + 8 <= count) std::memcpy(&word, values + i, 8);
      if (word == 0) {
        i += 7;
        continue;
      }
    }
    const std::size_t k = k0 + i;
    if (is_loop_value(values[i], k % n, k / n, path)) {
      gt.add(static_cast<std::int64_t>(k % n), static_cast<std::int64_t>(k / n));
    }
  }
}

// ---- MAT v5 variables, read by lsgd itself ------------------------------------
//
// matio sizes what it reads from a variable's dimensions and trusts the data
// sub-element to hold that much: a file whose dimensions exceed its data was
// read from uninitialised memory (valgrind). So the variable read_mat() chose
// is read here, from its bytes: its data must hold exactly the values its
// dimensions declare (dense) or what its column index needs (sparse), in
// either byte order, compressed or not. The dense matrix is streamed, never
// held: matio holds it all (693 MB for Bicocca's 26335^2 uint8).

constexpr std::uint32_t kMiInt32 = 5, kMiUint32 = 6;
constexpr std::uint32_t kClassFlagsComplex = 0x800;
// More nonzero entries than any ground truth has (KITTI-00's full matrix has
// ~1e5): a sparse matrix claiming more is refused before its index is held.
constexpr std::uint64_t kMaxSparseEntries = 100'000'000;

struct V5Tag {
  std::uint32_t type = 0;
  std::uint32_t bytes = 0;
  bool small = false;           // data inline in the tag's second word
  unsigned char inline_data[4]{};
};

// The bytes of one miMATRIX element, in order, from the file or from the zlib
// stream of a miCOMPRESSED element. At most `left` more bytes belong to it;
// reading past them is a FormatError, as is the end of the file or stream.
class V5Source {
 public:
  V5Source(const std::string& path, std::uint64_t element, bool swapped)
      : path_(path), element_(element), swapped_(swapped) {}
  virtual ~V5Source() = default;
  V5Source(const V5Source&) = delete;
  V5Source& operator=(const V5Source&) = delete;

  void limit(std::uint64_t bytes) { left_ = bytes; }
  bool swapped() const { return swapped_; }
  const std::string& path() const { return path_; }
  std::uint64_t element() const { return element_; }

  void read(void* out, std::size_t n, const char* what) {
    if (n > left_) {
      throw FormatError(concat("'", path_, "' is corrupt: the variable at byte ", element_,
                               " ends before its ", what, " (", n, " bytes needed, ", left_,
                               " left)"));
    }
    pull(out, n);
    left_ -= n;
  }
  void skip(std::uint64_t n, const char* what) {
    char buffer[256];
    while (n > 0) {
      const std::size_t step = static_cast<std::size_t>(std::min<std::uint64_t>(n, sizeof buffer));
      read(buffer, step, what);
      n -= step;
    }
  }
  std::uint32_t word(const char* what) {
    unsigned char b[4];
    read(b, 4, what);
    return u32(b, swapped_);
  }
  V5Tag tag(const char* what) {
    unsigned char b[8];
    read(b, 8, what);
    V5Tag t;
    const std::uint32_t first = u32(b, swapped_);
    if ((first >> 16) != 0) {
      t.type = first & 0xFFFF;
      t.bytes = first >> 16;
      t.small = true;
      std::memcpy(t.inline_data, b + 4, 4);
      if (t.bytes > 4) {
        throw FormatError(concat("'", path_, "' is corrupt: the variable at byte ", element_,
                                 " has a small ", what, " element of ", t.bytes, " bytes"));
      }
    } else {
      t.type = first;
      t.bytes = u32(b + 4, swapped_);
    }
    return t;
  }
  // Skips the padding after a (not small) sub-element of `bytes` bytes.
  void skip_padding(std::uint64_t bytes, const char* what) { skip((8 - bytes % 8) % 8, what); }
  // After the variable was read: a compressed stream must end (and pass its
  // check) within what the variable declared.
  virtual void finish() {}
  std::uint64_t left() const { return left_; }

 protected:
  virtual void pull(void* out, std::size_t n) = 0;

 private:
  std::string path_;
  std::uint64_t element_;
  bool swapped_;
  std::uint64_t left_ = 8;  // the miMATRIX tag of a compressed element
};

class V5FileSource final : public V5Source {
 public:
  V5FileSource(const std::string& path, const V5Element& e, bool swapped)
      : V5Source(path, e.offset, swapped), in_(path, std::ios::binary) {
    in_.seekg(static_cast<std::streamoff>(e.offset + 8));
    limit(e.bytes);  // fits the file (check_container)
  }

 private:
  void pull(void* out, std::size_t n) override {
    in_.read(static_cast<char*>(out), static_cast<std::streamsize>(n));
    if (!in_) throw IoError(concat("error while reading '", path(), "'"));
  }
  std::ifstream in_;
};

class V5ZlibSource final : public V5Source {
 public:
  V5ZlibSource(const std::string& path, const V5Element& e, bool swapped)
      : V5Source(path, e.offset, swapped), z_(path, compressed_bytes(path, e)) {}

 private:
  void pull(void* out, std::size_t n) override { z_.read(out, n); }
  void finish() override { z_.finish(left()); }
  Inflater z_;
};

// Reverses the bytes of each of the `count` values of `size` bytes at `p`.
void swap_values(unsigned char* p, std::size_t count, std::size_t size) {
  if (size == 1) return;
  for (std::size_t i = 0; i < count; ++i, p += size) std::reverse(p, p + size);
}

// The `count` values of the data sub-element `t` (its tag already read), in
// chunks of at most 1M: f(const T* values, std::size_t m, std::size_t k0).
template <typename T, typename F>
void for_each_chunk(V5Source& src, const V5Tag& t, std::size_t count, const char* what, F&& f) {
  if (t.small) {
    T values[4 / sizeof(T) + 1];
    std::memcpy(values, t.inline_data, count * sizeof(T));
    if (src.swapped()) swap_values(reinterpret_cast<unsigned char*>(values), count, sizeof(T));
    f(static_cast<const T*>(values), count, std::size_t{0});
    return;
  }
  constexpr std::size_t kChunk = std::size_t{1} << 20;
  std::vector<T> buffer(std::min(kChunk, count));
  for (std::size_t k0 = 0; k0 < count; k0 += kChunk) {
    const std::size_t m = std::min(kChunk, count - k0);
    src.read(buffer.data(), m * sizeof(T), what);
    if (src.swapped()) swap_values(reinterpret_cast<unsigned char*>(buffer.data()), m, sizeof(T));
    f(static_cast<const T*>(buffer.data()), m, k0);
  }
}

// The number of values of type size `size` in a data sub-element of `bytes`.
std::uint64_t value_count(const V5Source& src, const std::string& name, const V5Tag& t,
                          const char* what) {
  const std::size_t size = Mat_SizeOf(static_cast<matio_types>(t.type));
  if (size == 0 || !with_value_type(t.type, [](auto) {})) {
    throw FormatError(concat("'", src.path(), "': variable '", name, "' has ", what,
                             " of unsupported data type ", t.type));
  }
  if (t.bytes % size != 0) {
    throw FormatError(concat("'", src.path(), "' is corrupt: variable '", name, "' has ", what,
                             " of ", t.bytes, " bytes, not a whole number of ", size,
                             "-byte values"));
  }
  return t.bytes / size;
}

// The 32-bit integers of an ir or jc sub-element.
std::vector<std::uint32_t> read_index(V5Source& src, const std::string& name, const char* what,
                                      std::uint64_t max_count) {
  const V5Tag t = src.tag(what);
  if (t.type != kMiInt32 && t.type != kMiUint32) {
    throw FormatError(concat("'", src.path(), "' is corrupt: sparse matrix '", name, "' has ",
                             what, " of data type ", t.type, " (32-bit integers expected)"));
  }
  const std::uint64_t count = t.bytes / 4;
  if (t.bytes % 4 != 0 || count > max_count) {
    throw FormatError(concat("'", src.path(), "' is corrupt: sparse matrix '", name, "' has ",
                             what, " of ", t.bytes, " bytes (at most ", max_count,
                             " 32-bit entries expected)"));
  }
  std::vector<std::uint32_t> v(static_cast<std::size_t>(count));
  if (t.small) {
    std::memcpy(v.data(), t.inline_data, t.bytes);
    if (src.swapped()) swap_values(reinterpret_cast<unsigned char*>(v.data()), v.size(), 4);
    return v;
  }
  for_each_chunk<std::uint32_t>(src, t, v.size(), what,
                                [&](const std::uint32_t* p, std::size_t m, std::size_t k0) {
                                  std::copy(p, p + m, v.begin() + static_cast<std::ptrdiff_t>(k0));
                                });
  src.skip_padding(t.bytes, what);
  return v;
}

// Reads the data of sparse matrix `name` (n x n) after its name sub-element.
void read_v5_sparse(V5Source& src, const std::string& name, std::size_t n, GroundTruth& gt) {
  const auto corrupt = [&](const std::string& why) {
    return FormatError(
        concat("'", src.path(), "': sparse matrix '", name, "' is corrupt: ", why));
  };
  const std::vector<std::uint32_t> ir = read_index(src, name, "row index", kMaxSparseEntries);
  const std::vector<std::uint32_t> jc = read_index(src, name, "column index", n + 1);
  if (jc.size() != n + 1) {
    throw corrupt(concat("its column index has ", jc.size(), " entries, its ", n,
                         " columns need ", n + 1));
  }
  if (jc[0] != 0) throw corrupt("its column index does not start at 0");
  for (std::size_t c = 0; c < n; ++c) {
    if (jc[c] > jc[c + 1]) throw corrupt(concat("column ", c + 1, " ends before it starts"));
  }
  const std::size_t nnz = jc[n];
  if (nnz > ir.size()) {
    throw corrupt(concat("its column index counts ", nnz, " entries, its row index holds ",
                         ir.size()));
  }
  for (std::size_t k = 0; k < nnz; ++k) {
    if (ir[k] >= n) throw corrupt(concat("row index ", ir[k] + 1, " is beyond its ", n, " rows"));
  }
  // Values: one per entry, or none (an all-true logical matrix written without data).
  const V5Tag values = src.tag("values");
  const std::uint64_t count = value_count(src, name, values, "values");
  if (count != 0 && count < nnz) {
    throw corrupt(concat("it holds ", count, " values for ", nnz, " entries"));
  }
  std::size_t column = 0;  // of entry k: jc[column] <= k < jc[column + 1]
  const auto column_of = [&](std::size_t k) {
    while (jc[column + 1] <= k) ++column;  // ends below n: k < jc[n]
    return column;
  };
  if (count == 0) {
    for (std::size_t k = 0; k < nnz; ++k) {
      gt.add(static_cast<std::int64_t>(ir[k]), static_cast<std::int64_t>(column_of(k)));
    }
    return;
  }
  with_value_type(values.type, [&](auto t) {
    using T = decltype(t);
    for_each_chunk<T>(src, values, nnz, "values", [&](const T* v, std::size_t m, std::size_t k0) {
      for (std::size_t i = 0; i < m; ++i) {
        const std::size_t k = k0 + i, c = column_of(k);
        if (is_loop_value(v[i], ir[k], c, src.path())) {
          gt.add(static_cast<std::int64_t>(ir[k]), static_cast<std::int64_t>(c));
        }
      }
    });
    // Values beyond the entries (a larger nzmax) must be there too: a count
    // that claims more than the variable holds is damage, not slack.
    if (!values.small) src.skip((count - nnz) * sizeof(T), "values");
  });
}

// Reads the n x n values of dense matrix `name` after its name sub-element.
void read_v5_dense(V5Source& src, const std::string& name, std::size_t n, GroundTruth& gt) {
  const V5Tag real = src.tag("values");
  const std::uint64_t count = value_count(src, name, real, "values");
  if (count != std::uint64_t{n} * n) {
    throw FormatError(concat("'", src.path(), "' is corrupt: matrix '", name, "' is declared ", n,
                             "x", n, " (", std::uint64_t{n} * n, " values) but its data holds ",
                             count, " values"));
  }
  with_value_type(real.type, [&](auto t) {
    using T = decltype(t);
    for_each_chunk<T>(src, real, static_cast<std::size_t>(count), "values",
                      [&](const T* v, std::size_t m, std::size_t k0) {
                        add_nonzero(v, m, k0, n, gt, src.path());
                      });
  });
}

struct V5Header {
  std::uint32_t flags = 0;  // class in the low byte
  std::vector<std::uint32_t> dims;
  std::string name;
};

// Reads a matrix element's array flags, dimensions and name. A header claiming
// more than MATLAB writes (names have at most 63 characters, ground truth 2
// dimensions) is corrupt: matio would allocate what it claims (fuzzing found
// 3-4 GB callocs).
V5Header read_v5_header(V5Source& src) {
  const auto corrupt = [&](const std::string& why) {
    return FormatError(concat("'", src.path(), "' is corrupt: the variable at byte ",
                              src.element(), " ", why));
  };
  V5Header h;
  const V5Tag flags_tag = src.tag("array flags");
  if (flags_tag.small || flags_tag.bytes != 8) {
    throw corrupt(concat("has array flags of ", flags_tag.bytes, " bytes"));
  }
  h.flags = src.word("array flags");
  src.word("array flags");  // nzmax: the column index says how many entries are used
  const V5Tag dims_tag = src.tag("dimensions");
  if (dims_tag.bytes % 4 != 0 || dims_tag.bytes > 1024) {
    throw corrupt(concat("claims ", dims_tag.bytes, " bytes of dimensions"));
  }
  h.dims.resize(dims_tag.bytes / 4);
  if (dims_tag.small) {
    std::memcpy(h.dims.data(), dims_tag.inline_data, dims_tag.bytes);
    if (src.swapped()) swap_values(reinterpret_cast<unsigned char*>(h.dims.data()), h.dims.size(), 4);
  } else {
    for (std::uint32_t& d : h.dims) d = src.word("dimensions");
    src.skip_padding(dims_tag.bytes, "dimensions");
  }
  const V5Tag name_tag = src.tag("name");
  if (name_tag.small) {
    h.name.assign(reinterpret_cast<const char*>(name_tag.inline_data), name_tag.bytes);
  } else {
    if (name_tag.bytes > 4096) throw corrupt(concat("claims a name of ", name_tag.bytes, " bytes"));
    h.name.resize(name_tag.bytes);
    src.read(h.name.data(), h.name.size(), "name");
    src.skip_padding(name_tag.bytes, "name");
  }
  return h;
}

// Opens element `e` as a matrix: nullptr when it is not one (compressed
// elements hold a matrix too, after their own tag).
std::unique_ptr<V5Source> open_v5_matrix(const std::string& path, const Container& c,
                                         const V5Element& e) {
  if (e.type == kMiMatrix) return std::make_unique<V5FileSource>(path, e, c.swapped);
  if (e.type != kMiCompressed) return nullptr;
  auto src = std::make_unique<V5ZlibSource>(path, e, c.swapped);
  const V5Tag matrix = src->tag("matrix tag");
  if (matrix.small || matrix.type != kMiMatrix) return nullptr;
  src->limit(matrix.bytes);
  return src;
}

// matio sizes its allocations from a variable's header (array flags,
// dimensions, name) before it looks at the data, compressed or not (array
// flags of 9 bytes made it read the rank from the wrong place and ask for
// 8 GB): every matrix's header is read here first (read_v5_header).
void check_matrix_headers(const std::string& path, const Container& c) {
  for (const V5Element& e : c.elements) {
    if (const auto src = open_v5_matrix(path, c, e)) read_v5_header(*src);
  }
}

// Reads the variable of `src` when it is called `name`: true when it was.
bool read_v5_variable(V5Source& src, const std::string& name, std::size_t n, GroundTruth& gt) {
  const V5Header h = read_v5_header(src);
  const std::uint32_t flags = h.flags;
  const std::vector<std::uint32_t>& dims = h.dims;
  const std::string& var = h.name;
  if (var != name) return false;
  if (dims.size() != 2 || dims[0] != n || dims[1] != n || (flags & kClassFlagsComplex)) {
    throw FormatError(concat("'", src.path(), "': variable '", name,
                             "' is not the square real matrix its header announced"));
  }
  const std::uint32_t cls = flags & 0xFF;
  if (cls == MAT_C_SPARSE) {
    read_v5_sparse(src, name, n, gt);
  } else if (cls >= MAT_C_DOUBLE && cls <= MAT_C_UINT64) {
    read_v5_dense(src, name, n, gt);
  } else {
    throw FormatError(concat("'", src.path(), "': variable '", name, "' has class ", cls,
                             ", not a numeric, logical or sparse matrix"));
  }
  src.finish();
  return true;
}

// Reads top-level variable `name` (n x n) of a v5 file into `gt`.
void read_v5(const std::string& path, const Container& c, const std::string& name, std::size_t n,
             GroundTruth& gt) {
  for (const V5Element& e : c.elements) {
    const auto src = open_v5_matrix(path, c, e);
    if (src && read_v5_variable(*src, name, n, gt)) return;
  }
  throw FormatError(concat("'", path, "': variable '", name, "' was not found among its ",
                           c.elements.size(), " top-level elements (corrupt?)"));
}

struct MatCloser {
  void operator()(mat_t* mat) const { Mat_Close(mat); }
};
struct VarFreer {
  void operator()(matvar_t* var) const { Mat_VarFree(var); }
};
using MatFile = std::unique_ptr<mat_t, MatCloser>;
using MatVar = std::unique_ptr<matvar_t, VarFreer>;

bool is_matrix_class(matio_classes c) {
  return c == MAT_C_SPARSE || (c >= MAT_C_DOUBLE && c <= MAT_C_UINT64);
}

bool is_square_matrix(const matvar_t& v) {
  return v.rank == 2 && v.dims && v.dims[0] == v.dims[1] && is_matrix_class(v.class_type) &&
         !v.isComplex;
}

std::string describe(const matvar_t& v) {
  std::string dims;
  for (int i = 0; i < v.rank && v.dims; ++i) dims += (i ? "x" : "") + std::to_string(v.dims[i]);
  return concat(v.name ? v.name : "?", " ", dims, " class ", static_cast<int>(v.class_type),
                v.isLogical ? " logical" : "", v.isComplex ? " complex" : "");
}

bool looks_like_gt_name(const char* name) {
  std::string lower = name ? name : "";
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return lower.find("gt") != std::string::npos || lower.find("truth") != std::string::npos;
}

// The name of the variable read_mat() reads (see the header for the rule).
std::string choose_variable(mat_t* mat, const std::string& path) {
  std::string first, named, seen;
  int count = 0;
  while (MatVar info{Mat_VarReadNextInfo(mat)}) {
    ++count;
    seen += (seen.empty() ? "" : ", ") + describe(*info);
    if (!is_square_matrix(*info) || !info->name) continue;
    if (first.empty()) first = info->name;
    if (named.empty() && looks_like_gt_name(info->name)) named = info->name;
  }
  if (count == 0) {
    throw FormatError(concat("'", path, "' holds no readable MAT variable (truncated or corrupt?)",
                             matio_detail()));
  }
  if (first.empty()) {
    throw FormatError(concat("'", path, "' has no square 2-D real numeric, logical or sparse ",
                             "matrix (variables: ", seen, ")"));
  }
  return named.empty() ? first : named;
}

// Sparse (compressed column): rows ir[jc[c] .. jc[c+1]) of column c, with
// values (absent for an all-true logical matrix written without data).
template <typename T>
void add_sparse(const matvar_t& v, std::size_t n, GroundTruth& gt, const std::string& path) {
  const auto* s = static_cast<const mat_sparse_t*>(v.data);
  const auto corrupt = [&](const char* why) {
    return FormatError(concat("'", path, "': sparse matrix '", v.name, "' is corrupt: ", why));
  };
  if (!s || !s->jc || s->njc != n + 1) throw corrupt("column index has the wrong length");
  const T* values = static_cast<const T*>(s->data);
  for (std::size_t c = 0; c < n; ++c) {
    const std::size_t begin = s->jc[c], end = s->jc[c + 1];
    if (begin > end || end > s->nir || (end > 0 && !s->ir)) throw corrupt("bad column pointers");
    for (std::size_t k = begin; k < end; ++k) {
      const std::size_t r = s->ir[k];
      if (r >= n) throw corrupt("row index out of range");
      if (values && k < s->ndata && !is_loop_value(values[k], r, c, path)) continue;
      gt.add(static_cast<std::int64_t>(r), static_cast<std::int64_t>(c));
    }
  }
}

void add_matrix(const matvar_t& v, std::size_t n, GroundTruth& gt, const std::string& path) {
  const bool sparse = v.class_type == MAT_C_SPARSE;
  if (!sparse && (!v.data || v.nbytes < n * n * Mat_SizeOf(v.data_type))) {
    throw FormatError(concat("'", path, "': variable '", v.name, "' holds fewer values than its ",
                             n, "x", n, " size (truncated?)", matio_detail()));
  }
  const bool known = with_value_type(v.data_type, [&](auto t) {
    using T = decltype(t);
    if (sparse) return add_sparse<T>(v, n, gt, path);
    add_nonzero(static_cast<const T*>(v.data), n * n, 0, n, gt, path);
  });
  if (!known) {
    throw FormatError(concat("'", path, "': variable '", v.name, "' has unsupported data type ",
                             static_cast<int>(v.data_type)));
  }
}

// ---- poses grid -------------------------------------------------------------

struct Cell {
  std::int64_t x, y, z;
  bool operator==(const Cell& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellHash {
  std::size_t operator()(const Cell& c) const {
    std::uint64_t h = static_cast<std::uint64_t>(c.x) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(c.y) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(c.z) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return static_cast<std::size_t>(h);
  }
};

}  // namespace

// ---- names and options ------------------------------------------------------

namespace {

GroundTruth open_pairs(const std::string& path, const GtOptions& options) {
  return read_pairs_counted(path, options.frames);
}
GroundTruth open_mat(const std::string& path, const GtOptions& options) {
  return read_mat(path, options.frames, options.mat_variable);
}
GroundTruth open_loopinf(const std::string& path, const GtOptions& options) {
  return read_loopinf(path, options.frames);
}
GroundTruth open_kitti_poses(const std::string& path, const GtOptions& options) {
  const auto poses = read_kitti_poses(path);
  const auto n = static_cast<std::int64_t>(poses.size());
  if (options.frames >= 0 && n != options.frames) {
    throw FormatError(concat("'", path, "' has ", n, " poses but the sequence has ",
                             options.frames, " frames"));
  }
  return groundtruth_from_poses(poses, options.poses_distance, options.poses_min_gap);
}

// The formats, built-in ones first (register_gt_format()).
internal::Registry<GtFormatType>& registry() {
  static internal::Registry<GtFormatType> formats(
      "ground-truth format",
      {
          {kPairsGtFormat, "'q m' per line, 0-based", open_pairs},
          {kMatGtFormat, "a MATLAB N x N loop matrix", open_mat},
          {kKittiPosesGtFormat, "KITTI poses, a loop within 10 m and 100 frames by default",
           open_kitti_poses},
          {kLoopinfGtFormat, "the LSGDDN authors' 'frame<TAB>loop_frame', -1 = none",
           open_loopinf},
      });
  return formats;
}

// The built-in formats are told apart by detect_gt_format() itself.
bool builtin(const GtFormatType& t) {
  for (const char* name : {kPairsGtFormat, kMatGtFormat, kKittiPosesGtFormat, kLoopinfGtFormat}) {
    if (std::strcmp(t.name, name) == 0) return true;
  }
  return false;
}

}  // namespace

std::vector<GtFormatType> gt_format_types() { return registry().entries(); }

void register_gt_format(const GtFormatType& format) {
  registry().add(format, "register_gt_format", kAutoGtFormat);
}

std::vector<std::string> gt_format_names() {
  std::vector<std::string> names{kAutoGtFormat};
  for (const GtFormatType& t : gt_format_types()) names.emplace_back(t.name);
  return names;
}

GtFormat parse_gt_format(const std::string& name) {
  if (name == kAutoGtFormat) return name;
  for (const GtFormatType& t : gt_format_types()) {
    if (name == t.name) return name;
  }
  std::string all;
  const std::vector<std::string> names = gt_format_names();
  for (std::size_t k = 0; k < names.size(); ++k) {
    all += (k == 0 ? "" : k + 1 == names.size() ? " or " : ", ") + names[k];
  }
  internal::throw_invalid("ground-truth format '", name, "' is unknown: expected ", all);
}

void GtOptions::check() const {
  internal::check_range<std::int64_t>("ground truth frames", frames, -1, kMaxFrames);
  internal::check_range_open_low("ground truth poses_distance", poses_distance, 0.0, 1e6, "metres");
  internal::check_range<std::int64_t>("ground truth poses_min_gap", poses_min_gap, 0, kMaxWindowFrames,
                                      "frames");
  parse_gt_format(format);
}

// ---- detection and dispatch ---------------------------------------------------

GtFormat detect_gt_format(const std::string& path) {
  io::check_input_file(path, "ground-truth file");
  for (const GtFormatType& t : gt_format_types()) {
    if (!builtin(t) && t.detect != nullptr && t.detect(path)) return t.name;
  }
  std::ifstream in = open_text(path, "ground-truth file");
  std::string head(128, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  if (head.rfind("MATLAB", 0) == 0 && head.find("MAT-file") < 116) return kMatGtFormat;
  if (head.find('\0') != std::string::npos) {
    if (has_mat_extension(path)) return kMatGtFormat;  // MAT v4: no text header
    throw FormatError(concat("cannot tell the ground-truth format of '", path,
                             "': a binary file without a MAT-file header"));
  }
  in.clear();
  in.seekg(0);
  io::skip_utf8_bom(in);
  const TextShape shape = text_shape(in, path);
  if (shape.lines == 0) {
    throw FormatError(concat("cannot tell the ground-truth format of '", path,
                             "': no data lines (empty or only comments)"));
  }
  if (shape.columns == 12 || shape.columns == 13) return kKittiPosesGtFormat;
  if (shape.columns == 2 && shape.integers) {
    if (shape.consecutive && !shape.other_negative && (shape.minus_one || shape.tabs)) {
      return kLoopinfGtFormat;
    }
    if (!shape.minus_one && !shape.other_negative) return kPairsGtFormat;
  }
  throw FormatError(concat("cannot tell the ground-truth format of '", path, "': ", shape.columns,
                           shape.integers ? " integer" : " numeric",
                           " fields per line fit neither pairs ('q m'), loopinf ('k<TAB>j' on line "
                           "k) nor KITTI poses (12 or 13 numbers)"));
}

GroundTruth load_groundtruth(const std::string& path, const GtOptions& options) {
  options.check();
  const GtFormat format =
      options.format == kAutoGtFormat ? detect_gt_format(path) : options.format;
  return registry().find(format).open(path, options);
}

namespace {

// matio 1.5.23 takes a file without a v5 / v7.3 header for MAT v4 and mallocs
// the first variable's name length unchecked: 20 corrupt bytes can ask for
// gigabytes (found by fuzz/fuzz_gt). A v4 name must fit in the file.
void check_v4_name_length(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::array<unsigned char, 128> head{};
  in.read(reinterpret_cast<char*>(head.data()), head.size());
  const std::size_t got = static_cast<std::size_t>(in.gcount());
  if (got == head.size() && ((head[126] == 'I' && head[127] == 'M') ||
                             (head[126] == 'M' && head[127] == 'I'))) {
    return;  // v5 / v7.3 header: matio checks those itself
  }
  if (got < 20) return;  // matio rejects a header this short
  auto int32_at = [&](std::size_t at, bool little) {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= std::uint32_t{head[at + (little ? i : 3 - i)]} << (8 * i);
    return static_cast<std::int32_t>(v);
  };
  // The type field (MOPT, < 5000) tells the byte order, as in matio.
  const std::int32_t type_le = int32_at(0, true);
  const bool little = type_le >= 0 && type_le < 5000;
  const std::int64_t name_length = int32_at(16, little);
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw IoError(concat("cannot read MAT file '", path, "': ", ec.message()));
  if (name_length < 1 || static_cast<std::uint64_t>(name_length) > size - 20) {
    throw FormatError(concat("'", path, "' is not a readable MAT file: v4 variable name length ",
                             name_length, " does not fit in the file's ", size, " bytes"));
  }
}

}  // namespace

// ---- readers --------------------------------------------------------------------

GroundTruth read_mat(const std::string& path, std::int64_t frames, const std::string& variable) {
  static std::once_flag log_once;
  std::call_once(log_once, [] { Mat_LogInitFunc("lsgd", matio_log); });
  io::check_input_file(path, "MAT file");
  if (!std::ifstream(path)) throw IoError(concat("cannot open MAT file '", path, "'"));
  check_v4_name_length(path);
  matio_last_message.clear();
  MatFile mat{Mat_Open(path.c_str(), MAT_ACC_RDONLY)};
  if (!mat) {
    throw FormatError(concat("'", path, "' is not a readable MAT file", matio_detail()));
  }
  const mat_ft version = Mat_GetVersion(mat.get());
  const Container container = check_container(path, version);
  if (version == MAT_FT_MAT5) check_matrix_headers(path, container);
  std::string name = variable;
  if (name.empty()) {
    name = choose_variable(mat.get(), path);
  } else {
    MatVar info{Mat_VarReadInfo(mat.get(), name.c_str())};
    if (!info) throw FormatError(concat("'", path, "' has no variable '", name, "'"));
    if (!is_square_matrix(*info)) {
      throw FormatError(concat("'", path, "': variable ", describe(*info),
                               " is not a square 2-D real numeric, logical or sparse matrix"));
    }
  }
  MatVar info{Mat_VarReadInfo(mat.get(), name.c_str())};
  if (!info) {
    throw FormatError(
        concat("cannot read variable '", name, "' from '", path, "'", matio_detail()));
  }
  const std::size_t n = info->dims[0];
  if (frames >= 0 && n != static_cast<std::size_t>(frames)) {
    throw FormatError(concat("'", path, "': matrix '", name, "' is ", n, "x", n,
                             " but the sequence has ", frames, " frames"));
  }
  if (n > 1'000'000) {
    throw FormatError(
        concat("'", path, "': matrix '", name, "' is ", n, "x", n, ": more than 1e6 frames"));
  }
  GroundTruth gt(static_cast<std::int64_t>(n));
  if (version == MAT_FT_MAT5) {
    read_v5(path, container, name, n, gt);  // checks the data against the dimensions
    return gt;
  }
  if (info->class_type != MAT_C_SPARSE &&
      static_cast<double>(n) * n * Mat_SizeOfClass(info->class_type) > 16e9) {
    throw FormatError(concat("'", path, "': matrix '", name, "' is ", n, "x", n,
                             ": too large to read densely (limit 16 GB)"));
  }
  matio_last_message.clear();
  MatVar var{Mat_VarRead(mat.get(), name.c_str())};
  if (!var || !matio_last_message.empty()) {
    throw FormatError(concat("cannot read variable '", name, "' from '", path,
                             "' (truncated or corrupt?)", matio_detail()));
  }
  add_matrix(*var, n, gt, path);
  return gt;
}

std::vector<Pose> read_kitti_poses(const std::string& path) {
  std::ifstream in = open_text(path, "poses file");
  std::vector<Pose> poses;
  std::size_t columns = 0;
  std::string line;
  for (std::int64_t number = 1; io::read_line(in, line, path, number); ++number) {
    const auto fields = fields_of(line);
    if (fields.empty()) continue;
    if (columns == 0) columns = fields.size();
    if ((fields.size() != 12 && fields.size() != 13) || fields.size() != columns) {
      throw FormatError(concat(path, ":", number, ": expected ",
                               columns == fields.size() ? "12 or 13" : std::to_string(columns),
                               " numbers (a 3x4 pose, optionally after a timestamp), got ",
                               fields.size()));
    }
    std::array<double, 13> v{};
    for (std::size_t f = 0; f < fields.size(); ++f) {
      if (!parse_double(fields[f], v[f]) || !std::isfinite(v[f])) {
        throw FormatError(concat(path, ":", number, ": field ", f + 1, " '", fields[f],
                                 "' is not a finite number"));
      }
    }
    const std::size_t t = columns - 12;  // skip the timestamp
    poses.push_back({v[t + 3], v[t + 7], v[t + 11]});
  }
  if (in.bad()) throw IoError(concat("error while reading '", path, "'"));
  if (poses.empty()) throw FormatError(concat("'", path, "' holds no poses"));
  return poses;
}

GroundTruth groundtruth_from_poses(const std::vector<Pose>& poses, double distance,
                                   std::int64_t min_gap) {
  internal::check_range_open_low("poses distance", distance, 0.0, 1e6, "metres");
  internal::check_range<std::int64_t>("poses min_gap", min_gap, 0, kMaxWindowFrames, "frames");
  const auto n = static_cast<std::int64_t>(poses.size());
  GroundTruth gt(n);
  const auto cell_of = [distance](const Pose& p) {
    const auto index = [distance](double v) {
      const double c = std::floor(v / distance);
      if (!(std::abs(c) < 1e15)) {
        internal::throw_invalid("camera centre coordinate ", v, " is not finite or too large");
      }
      return static_cast<std::int64_t>(c);
    };
    return Cell{index(p.x), index(p.y), index(p.z)};
  };
  // Cells of side `distance`: a pair closer than that lies in adjacent cells.
  std::unordered_map<Cell, std::vector<std::int64_t>, CellHash> grid;
  const double d2 = distance * distance;
  for (std::int64_t i = 0; i < n; ++i) {
    const Pose& p = poses[static_cast<std::size_t>(i)];
    const Cell c = cell_of(p);
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({c.x + dx, c.y + dy, c.z + dz});
          if (it == grid.end()) continue;
          for (std::int64_t j : it->second) {  // ascending, all < i
            if (i - j <= min_gap) break;
            const Pose& o = poses[static_cast<std::size_t>(j)];
            const double ex = p.x - o.x, ey = p.y - o.y, ez = p.z - o.z;
            if (ex * ex + ey * ey + ez * ez < d2) gt.add(i, j);
          }
        }
      }
    }
    grid[c].push_back(i);
  }
  return gt;
}

GroundTruth read_loopinf(const std::string& path, std::int64_t frames) {
  std::ifstream in = open_text(path, "loopinf file");
  std::vector<std::pair<long long, std::int64_t>> loops;  // (loop frame, line number) per frame
  std::string line;
  for (std::int64_t number = 1; io::read_line(in, line, path, number); ++number) {
    const auto fields = fields_of(line);
    if (fields.empty()) continue;
    long long k = 0, j = 0;
    if (fields.size() != 2 || !parse_int(fields[0], k) || !parse_int(fields[1], j)) {
      throw FormatError(
          concat(path, ":", number, ": expected 'frame<TAB>loop_frame', got '", line, "'"));
    }
    if (k != static_cast<long long>(loops.size())) {
      throw FormatError(concat(path, ":", number, ": expected frame ", loops.size(), ", got ", k,
                               " (loopinf has one line per frame, in order)"));
    }
    if (j < -1) throw FormatError(concat(path, ":", number, ": loop frame ", j, " is negative"));
    loops.emplace_back(j, number);
  }
  if (in.bad()) throw IoError(concat("error while reading '", path, "'"));
  const auto lines = static_cast<std::int64_t>(loops.size());
  if (frames >= 0 && lines != frames) {
    throw FormatError(
        concat("'", path, "' has ", lines, " frames (lines) but the sequence has ", frames));
  }
  GroundTruth gt(lines);
  for (std::int64_t k = 0; k < lines; ++k) {
    const auto [j, number] = loops[static_cast<std::size_t>(k)];
    if (j == -1) continue;
    if (j >= lines) {
      throw FormatError(concat(path, ":", number, ": loop frame ", j, " of frame ", k,
                               " is outside the ", lines, " frames"));
    }
    gt.add(k, j);
  }
  return gt;
}

// ---- statistics ---------------------------------------------------------------------

GtStats gt_stats(const GroundTruth& gt, std::int64_t min_gap) {
  internal::check_range<std::int64_t>("min_gap", min_gap, 0, kMaxWindowFrames, "frames");
  GtStats s;
  s.frames = gt.frames();
  s.pairs = gt.pairs();
  s.min_gap = min_gap;
  std::vector<std::int64_t> gaps;
  gaps.reserve(static_cast<std::size_t>(gt.pairs()));
  std::vector<std::int64_t> in_loop;  // every frame of every pair, then made unique
  for (const std::int64_t q : gt.queries()) {
    const auto& matches = gt.matches(q);
    ++s.positives;
    if (gt.has_loop(q, min_gap)) ++s.window_positives;
    in_loop.push_back(q);
    for (std::int64_t m : matches) {
      in_loop.push_back(m);
      gaps.push_back(q - m);
      if (q - m > min_gap) ++s.window_pairs;
    }
  }
  std::sort(in_loop.begin(), in_loop.end());
  s.frames_in_loops =
      std::unique(in_loop.begin(), in_loop.end()) - in_loop.begin();
  if (!gaps.empty()) {
    std::sort(gaps.begin(), gaps.end());
    const std::size_t h = gaps.size() / 2;
    s.gap_min = gaps.front();
    s.gap_max = gaps.back();
    s.gap_median = gaps.size() % 2 ? static_cast<double>(gaps[h])
                                   : 0.5 * static_cast<double>(gaps[h - 1] + gaps[h]);
  }
  return s;
}

}  // namespace lsgd::eval
