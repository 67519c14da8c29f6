// MAT v5 files read by lsgd itself: the container checks and the streaming
// reader of the published loop matrices (compressed dense, sparse).
#include "eval/mat_internal.h"

#include "lsgd/io/files.h"
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

namespace lsgd::eval::mat {

namespace {

// ---- MAT container checks and the streaming fast path ------------------------
//
// Layouts from the MAT-file format reference (MathWorks, "MAT-File Format",
// 2019). v5: a 128-byte header, then top-level elements, each an 8-byte tag
// (uint32 type, uint32 byte count) and its bytes (padded to 8 unless
// compressed). A miCOMPRESSED element is a zlib stream holding one miMATRIX
// element: array flags (class in the low byte), dimensions, name, real part.
// A sub-element whose first word has nonzero upper 16 bits is "small": type
// in the low 16 bits, byte count in the high 16, data in the next 4 bytes.
// v4: mat_v4.cc.

constexpr std::uint32_t kMiMatrix = 14, kMiCompressed = 15;

}  // namespace

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
    check_v4_container(path, size, c);
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

// Every matrix's header, read by lsgd (read_v5_header): matio sizes its
// allocations from them before it looks at the data, compressed or not (array
// flags of 9 bytes made it read the rank from the wrong place and ask for
// 8 GB; a cell's element count, 6 GB).
std::vector<V5Header> matrix_headers(const std::string& path, const Container& c) {
  std::vector<V5Header> out;
  for (const V5Element& e : c.elements) {
    if (const auto src = open_v5_matrix(path, c, e)) out.push_back(read_v5_header(*src));
  }
  return out;
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

}  // namespace lsgd::eval::mat
