// MAT v4 files read by lsgd itself: the header walk every v4 file passes
// before matio opens it, and the sparse matrices matio describes by their
// stored triplets (an N+1 x 3 matrix) instead of their size.
//
// Layout (MathWorks, "MAT-File Format", 2019, "Level 4 MAT-Files"): per
// variable a 20-byte header (MOPT type, rows, cols, imagf, name length), the
// name, then rows x cols values column by column (twice when complex). MOPT
// is M * 1000 + O * 100 + P * 10 + T: P the value type (0 double, 1 single,
// 2 int32, 3 int16, 4 uint16, 5 uint8), T the matrix type (0 full, 1 text,
// 2 sparse). A sparse matrix is stored as its nonzeros' (row, column, value)
// triplets, 1-based, one per row of a rows x 3 matrix (4 when complex), and a
// last row (m, n, 0) holding its size.
#include "eval/mat_internal.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "internal/check.h"
#include "lsgd/error.h"

namespace lsgd::eval::mat {

namespace {

constexpr std::uint64_t kElem[] = {8, 4, 4, 2, 2, 1};  // bytes of a value, by P

// Value k of a column read from the file (type P, byte order swapped or not).
double value_at(const unsigned char* p, std::uint32_t precision, bool swap) {
  unsigned char b[8];
  const std::size_t n = kElem[precision];
  for (std::size_t i = 0; i < n; ++i) b[i] = p[swap ? n - 1 - i : i];
  switch (precision) {
    case 0: {
      double v;
      std::memcpy(&v, b, 8);
      return v;
    }
    case 1: {
      float v;
      std::memcpy(&v, b, 4);
      return v;
    }
    case 2: {
      std::int32_t v;
      std::memcpy(&v, b, 4);
      return v;
    }
    case 3: {
      std::int16_t v;
      std::memcpy(&v, b, 2);
      return v;
    }
    case 4: {
      std::uint16_t v;
      std::memcpy(&v, b, 2);
      return v;
    }
    default:
      return b[0];
  }
}

class V4Reader {
 public:
  V4Reader(const std::string& path, const V4Variable& v)
      : path_(path), v_(v), in_(path, std::ios::binary), elem_(kElem[v.type / 10 % 10]) {
    if (!in_) throw IoError(concat("cannot open MAT file '", path, "'"));
  }
  // Values [first, first + count) of column `column`.
  void read(std::uint64_t column, std::uint64_t first, std::uint64_t count, std::vector<double>& out) {
    bytes_.resize(static_cast<std::size_t>(count * elem_));
    in_.seekg(static_cast<std::streamoff>(v_.data + (column * v_.rows + first) * elem_));
    in_.read(reinterpret_cast<char*>(bytes_.data()), static_cast<std::streamsize>(bytes_.size()));
    if (!in_) throw IoError(concat("error while reading '", path_, "'"));
    out.resize(static_cast<std::size_t>(count));
    const auto precision = static_cast<std::uint32_t>(v_.type / 10 % 10);
    for (std::uint64_t k = 0; k < count; ++k) {
      out[k] = value_at(bytes_.data() + k * elem_, precision, v_.swapped);
    }
  }

 private:
  const std::string& path_;
  const V4Variable& v_;
  std::ifstream in_;
  std::uint64_t elem_;
  std::vector<unsigned char> bytes_;
};

// A 1-based index or size read as a double: a whole number in [lowest, 2^31).
bool whole(double x, double lowest) {
  return std::isfinite(x) && x >= lowest && x < 2147483648.0 && x == std::floor(x);
}

}  // namespace

void check_v4_container(const std::string& path, std::uint64_t size, Container& c) {
  std::ifstream in(path, std::ios::binary);
  const auto truncated = [&](std::uint64_t at, std::uint64_t need) {
    return FormatError(concat("'", path, "' is truncated or corrupt: the element at byte ", at,
                              " needs ", need, " bytes, the file has ", size - at));
  };
  unsigned char b[20];
  for (std::uint64_t pos = 0; pos < size;) {
    if (size - pos < 20) throw truncated(pos, 20);
    in.seekg(static_cast<std::streamoff>(pos));
    in.read(reinterpret_cast<char*>(b), 20);
    if (!in) throw IoError(concat("error while reading '", path, "'"));
    // matio's rule: a MOPT type outside 0..4052 is read byte-swapped.
    const bool swap = u32(b, false) > 4052;
    const std::uint64_t type = u32(b, swap), rows = u32(b + 4, swap), cols = u32(b + 8, swap);
    const std::uint64_t parts = u32(b + 12, swap) ? 2 : 1, name = u32(b + 16, swap);
    const std::uint64_t p = (type / 10) % 10;
    if (name < 1 || name > size - pos - 20) {
      throw FormatError(concat("'", path, "' is not a readable MAT file: v4 variable name length ",
                               name, " at byte ", pos, " does not fit in the file's ", size,
                               " bytes"));
    }
    if (p > 5 || rows * cols > (std::uint64_t{1} << 50)) {
      throw FormatError(concat("'", path, "': corrupt MAT v4 header at byte ", pos, " (", rows,
                               " x ", cols, " values of type ", type, ")"));
    }
    const std::uint64_t need = 20 + name + rows * cols * kElem[p] * parts;
    if (need > size - pos) throw truncated(pos, need);
    V4Variable v;
    v.name.resize(static_cast<std::size_t>(name));
    in.read(v.name.data(), static_cast<std::streamsize>(name));
    if (!in) throw IoError(concat("error while reading '", path, "'"));
    v.name.resize(std::strlen(v.name.c_str()));  // NUL-terminated in the file
    v.type = static_cast<std::uint32_t>(type);
    v.rows = rows;
    v.cols = cols;
    v.complex = parts == 2;
    v.swapped = swap;
    v.data = pos + 20 + name;
    c.v4.push_back(std::move(v));
    pos += need;
  }
}

const V4Variable* find_v4(const Container& c, const std::string& name) {
  for (const V4Variable& v : c.v4) {
    if (v.name == name) return &v;
  }
  return nullptr;
}

V4Shape v4_sparse_shape(const std::string& path, const V4Variable& v) {
  if (v.cols != 3 && v.cols != 4) {
    throw FormatError(concat("'", path, "': sparse matrix '", v.name, "' is stored as ", v.rows,
                             " x ", v.cols, " values, not as (row, column, value) triplets"));
  }
  if (v.rows < 1) {
    throw FormatError(concat("'", path, "': sparse matrix '", v.name,
                             "' has no last row holding its size"));
  }
  V4Reader reader(path, v);
  std::vector<double> m, n;
  reader.read(0, v.rows - 1, 1, m);
  reader.read(1, v.rows - 1, 1, n);
  if (!whole(m[0], 0) || !whole(n[0], 0)) {
    throw FormatError(concat("'", path, "': sparse matrix '", v.name, "' is corrupt: its size (",
                             m[0], " x ", n[0], ") is not two whole numbers"));
  }
  return {static_cast<std::uint64_t>(m[0]), static_cast<std::uint64_t>(n[0]),
          v.cols == 4 || v.complex};
}

void read_v4_sparse(const std::string& path, const V4Variable& v, std::size_t n, GroundTruth& gt) {
  const auto corrupt = [&](std::uint64_t k, const std::string& why) {
    return FormatError(concat("'", path, "': sparse matrix '", v.name, "' is corrupt: nonzero ",
                              k + 1, " ", why));
  };
  V4Reader reader(path, v);
  constexpr std::uint64_t kChunk = 65536;  // triplets read at a time: memory stays bounded
  std::vector<double> rows, cols, values;
  const std::uint64_t nonzeros = v.rows - 1;  // the last row is the size
  for (std::uint64_t first = 0; first < nonzeros; first += kChunk) {
    const std::uint64_t count = std::min(kChunk, nonzeros - first);
    reader.read(0, first, count, rows);
    reader.read(1, first, count, cols);
    reader.read(2, first, count, values);
    for (std::uint64_t i = 0; i < count; ++i) {
      const double r = rows[i], c = cols[i];
      if (!whole(r, 1) || !whole(c, 1) || r > static_cast<double>(n) || c > static_cast<double>(n)) {
        throw corrupt(first + i, concat("is at (", r, ", ", c, "), outside its ", n, " x ", n,
                                        " size"));
      }
      const auto row = static_cast<std::size_t>(r) - 1, col = static_cast<std::size_t>(c) - 1;
      if (is_loop_value(values[i], row, col, path)) {
        gt.add(static_cast<std::int64_t>(row), static_cast<std::int64_t>(col));
      }
    }
  }
}

}  // namespace lsgd::eval::mat
