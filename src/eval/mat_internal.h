// Internals of the MAT reader shared by gt_mat.cc (matio) and mat_v5.cc (the
// container checks and lsgd's own streaming reader of v5 variables). Not
// installed.
#pragma once

#include <matio.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "internal/check.h"
#include "lsgd/error.h"
#include "lsgd/eval/groundtruth.h"

namespace lsgd::eval::mat {

using internal::concat;

struct V5Element {
  std::uint64_t offset;  // of the tag
  std::uint32_t type, bytes;
};

// A MAT v4 variable's header (mat_v4.cc).
struct V4Variable {
  std::string name;
  std::uint32_t type = 0;      // MOPT: M * 1000 + O * 100 + P * 10 + T
  std::uint64_t rows = 0, cols = 0;
  bool complex = false;        // imagf: the values twice
  bool swapped = false;        // written with the other byte order
  std::uint64_t data = 0;      // offset of its first value
};

struct Container {
  bool swapped = false;             // v5 written with the other byte order
  std::vector<V5Element> elements;  // v5 top-level elements
  std::vector<V4Variable> v4;       // v4 variables
};

// The size a v4 sparse matrix holds in its last row.
struct V4Shape {
  std::uint64_t rows = 0, cols = 0;
  bool complex = false;
};

// Checks that every top-level element of a v5 file fits in it (matio trusts
// the byte counts: a truncated file would read as zeros); FormatError naming
// the file otherwise.
Container check_container(const std::string& path, mat_ft version);
// v4 (mat_v4.cc): checks that every variable's header, name and values fit
// in the file (`size` bytes; matio mallocs what a header claims) and lists
// the variables in c.v4.
void check_v4_container(const std::string& path, std::uint64_t size, Container& c);
// The v4 variable `name`, nullptr when there is none.
const V4Variable* find_v4(const Container& c, const std::string& name);
// The size of v4 sparse variable v (matio describes it by its stored triplets,
// rows x 3); FormatError when its last row is not a size.
V4Shape v4_sparse_shape(const std::string& path, const V4Variable& v);
// Reads v4 sparse variable v (n x n) into `gt`, checking every index.
void read_v4_sparse(const std::string& path, const V4Variable& v, std::size_t n, GroundTruth& gt);
// A v5 matrix's header: array flags, dimensions, name.
constexpr std::uint32_t kClassFlagsLogical = 0x200, kClassFlagsComplex = 0x800;
struct V5Header {
  std::uint32_t flags = 0;  // class (matio_classes) in the low byte, then the flags above
  std::vector<std::uint32_t> dims;
  std::string name;
};
// The headers of every top-level matrix of a v5 file, checked (FormatError
// naming the file and byte). read_mat() chooses its variable from these, not
// from matio: matio's Mat_VarReadNextInfo allocates what a cell or struct
// claims, at any depth, before it reads a byte of it (fuzz/fuzz_gt: 6 GB for
// a cell of 0x30000004 elements inside a file of a few hundred bytes).
std::vector<V5Header> matrix_headers(const std::string& path, const Container& c);
// Reads top-level variable `name` (n x n) of a v5 file into `gt`.
void read_v5(const std::string& path, const Container& c, const std::string& name, std::size_t n,
             GroundTruth& gt);

// The value readers: each .cc file that reads values has its own copies.
namespace {

// A 32-bit word of a file's bytes, in the other byte order when `swap`.
inline std::uint32_t u32(const unsigned char* p, bool swap) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  return swap ? __builtin_bswap32(v) : v;
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

// True when GT(r, c) = v is a loop: 1 is one, 0 is none. Any other value (a
// NaN, -1, 0.5, 7) is a FormatError naming the entry: a matrix of distances,
// scores, counts or soft labels is no loop matrix, and taking every nonzero
// entry for a loop would score against a ground truth nobody meant.
template <typename T>
bool is_loop_value(T v, std::size_t r, std::size_t c, const std::string& path) {
  if (v == T(0)) return false;
  if (v == T(1)) return true;
  std::string value;
  if constexpr (std::is_floating_point_v<T>) {
    value = std::isnan(v) ? std::string("NaN") : concat(static_cast<double>(v));
  } else {
    value = concat(+v);  // a 1-byte type as a number, not a character
  }
  throw FormatError(concat("'", path, "': entry (", r + 1, ", ", c + 1, ") is ", value,
                           ": a loop matrix holds 0 (no loop) or 1 (a loop); make it one "
                           "(in MATLAB, when every nonzero entry is a loop: GT = double(GT ~= 0)) or give the loops as pairs"));
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
      // GCC 12 inlines this into the small-element path of mat_v5.cc (a 5-byte
      // buffer, count <= 4) and warns, though i + 8 <= count never holds there.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Warray-bounds"
      if (i + 8 <= count) std::memcpy(&word, values + i, 8);
#pragma GCC diagnostic pop
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

}  // namespace

}  // namespace lsgd::eval::mat
