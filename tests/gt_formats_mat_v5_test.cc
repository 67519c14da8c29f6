// MAT v5 files built byte by byte (eval/gt_formats.h read_mat): the other
// byte order, headers, dimensions and sparse indices that disagree with the
// data, compressed streams that fail their check.
#include "lsgd/eval/gt_formats.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "gt_formats_test_support.h"
#include "test_util.h"

namespace fs = std::filesystem;
using lsgd::eval::GroundTruth;
using lsgd::eval::GtFormat;
using lsgd::eval::Pose;
using lsgd::test::message_of;

namespace {

std::string concat_trace(bool big, bool z) {
  return std::string(big ? "big-endian" : "little-endian") + (z ? ", compressed" : "");
}

using gt_formats_test_support::contains;
using gt_formats_test_support::Pairs;
using gt_formats_test_support::pairs_of;
using gt_formats_test_support::write_file;

// Files matio would not write: dimensions that disagree with the data, the
// other byte order, inconsistent sparse indices.

struct V5Writer {
  bool big_endian = false;
  std::string word(std::uint32_t v) const {
    std::string b(4, '\0');
    for (int i = 0; i < 4; ++i) b[i] = static_cast<char>(v >> (big_endian ? 24 - 8 * i : 8 * i));
    return b;
  }
  // A sub-element: tag, bytes, padding to 8.
  std::string element(std::uint32_t type, const std::string& bytes) const {
    return word(type) + word(static_cast<std::uint32_t>(bytes.size())) + bytes +
           std::string((8 - bytes.size() % 8) % 8, '\0');
  }
  std::string words(const std::vector<std::uint32_t>& v) const {
    std::string out;
    for (std::uint32_t x : v) out += word(x);
    return out;
  }
  // Doubles in this byte order.
  std::string doubles(const std::vector<double>& v) const {
    std::string out;
    for (double d : v) {
      std::uint64_t u;
      std::memcpy(&u, &d, 8);
      for (int i = 0; i < 8; ++i) out += static_cast<char>(u >> (big_endian ? 56 - 8 * i : 8 * i));
    }
    return out;
  }
  // A miMATRIX element of class `cls` with `dims`, name "GT" and `data`
  // (the sub-elements after the name).
  std::string matrix(std::uint32_t cls, const std::vector<std::uint32_t>& dims,
                     const std::string& data, const std::string& name = "GT") const {
    return matrix_of(element(6, words({cls, 0})), element(5, words(dims)), data, name);
  }
  // The same from its array flags and dimensions sub-elements as given.
  std::string matrix_of(const std::string& flags, const std::string& dims,
                        const std::string& data, const std::string& name = "GT") const {
    const std::string body = flags + dims + element(1, name) + data;
    return word(14) + word(static_cast<std::uint32_t>(body.size())) + body;
  }
  std::string file(const std::string& element, bool compressed) const {
    std::string header(116, ' ');
    header.replace(0, 19, "MATLAB 5.0 MAT-file");
    header += std::string(8, '\0');
    header += big_endian ? std::string("\x01\x00MI", 4) : std::string("\x00\x01IM", 4);
    if (!compressed) return header + element;
    uLongf size = compressBound(element.size());
    std::string z(size, '\0');
    EXPECT_EQ(compress(reinterpret_cast<Bytef*>(z.data()), &size,
                       reinterpret_cast<const Bytef*>(element.data()), element.size()),
              Z_OK);
    z.resize(size);
    return header + word(15) + word(static_cast<std::uint32_t>(z.size())) + z;
  }
};

// A 4x4 double matrix with GT(3, 0) = GT(2, 1) = 1, column-major.
std::vector<double> four_by_four() {
  std::vector<double> m(16, 0.0);
  m[0 * 4 + 3] = 1;
  m[1 * 4 + 2] = 1;
  return m;
}

TEST(ReadMatV5, BothByteOrdersCompressedOrNotAreReadByLsgd) {
  for (bool big : {false, true}) {
    for (bool z : {false, true}) {
      const V5Writer w{big};
      const std::string bytes =
          w.file(w.matrix(6, {4, 4}, w.element(9, w.doubles(four_by_four()))), z);
      const fs::path p = write_file("order.mat", bytes);
      const GroundTruth gt = lsgd::eval::read_mat(p.string());
      EXPECT_EQ(pairs_of(gt), (Pairs{{3, 0}, {2, 1}})) << "big " << big << " z " << z;
      // Sparse: the same loops as (row, column) entries, with values.
      const std::string sparse = w.element(5, w.words({3, 2})) +
                                 w.element(5, w.words({0, 1, 2, 2, 2})) +
                                 w.element(9, w.doubles({1, 1}));
      const fs::path ps = write_file("order-sparse.mat", w.file(w.matrix(5, {4, 4}, sparse), z));
      EXPECT_EQ(pairs_of(lsgd::eval::read_mat(ps.string())), (Pairs{{3, 0}, {2, 1}}))
          << "sparse big " << big << " z " << z;
    }
  }
}

// A fuzzer find: an uncompressed variable whose array flags claim 9 bytes
// made matio read its rank from the wrong place and ask for 8 GB; like a
// compressed one's, its header is checked before matio reads it.
TEST(ReadMatV5, CorruptUncompressedHeaderIsFormatErrorBeforeMatioAllocates) {
  for (bool big : {false, true}) {
    SCOPED_TRACE(big ? "big-endian" : "little-endian");
    V5Writer w;
    w.big_endian = big;
    const std::string data = w.element(9, w.doubles(four_by_four()));
    const std::string flags9 = w.element(6, w.words({6, 0}) + std::string(1, '\xff'));
    const fs::path p = write_file("flags9.mat", w.file(w.matrix_of(flags9, w.element(5, w.words({4, 4})), data), false));
    std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string(), 4); });
    EXPECT_TRUE(contains(e, p.string()) && contains(e, "array flags of 9 bytes")) << e;
    // Dimensions of 300 values (the element holds them): refused as well.
    const std::string flags = w.element(6, w.words({6, 0}));
    const fs::path q = write_file("rank300.mat", w.file(w.matrix_of(flags, w.element(5, w.words(std::vector<std::uint32_t>(300, 4))), data), false));
    e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(q.string(), 4); });
    EXPECT_TRUE(contains(e, q.string()) && contains(e, "claims 1200 bytes of dimensions")) << e;
  }
}

// Found by the issue 15 audit: matio sized its read from the dimensions and
// left the rest of the matrix uninitialised (valgrind), so loops came from
// whatever the heap held. The data must hold exactly the declared values.
TEST(ReadMatV5, DimensionsBeyondTheDataAreFormatErrors) {
  for (bool big : {false, true}) {
    for (bool z : {false, true}) {
      const V5Writer w{big};
      const std::string data = w.element(9, w.doubles(four_by_four()));  // 16 values
      const fs::path p = write_file("dims.mat", w.file(w.matrix(6, {5, 5}, data), z));
      const std::string e =
          message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
      EXPECT_TRUE(contains(e, p.string()) &&
                  contains(e, "declared 5x5 (25 values) but its data holds 16 values"))
          << "big " << big << " z " << z << ": " << e;
      // More data than declared is as corrupt.
      std::vector<double> more = four_by_four();
      more.resize(20, 0.0);
      const fs::path q =
          write_file("dims2.mat", w.file(w.matrix(6, {4, 4}, w.element(9, w.doubles(more))), z));
      EXPECT_TRUE(contains(message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(q.string()); }),
                           "data holds 20 values"));
      // A data element claiming more bytes than its matrix holds.
      std::string cut = w.matrix(6, {4, 4}, w.element(9, w.doubles(four_by_four())));
      cut.resize(cut.size() - 64);
      const std::string body = cut.substr(8);
      const std::string fixed = w.word(14) + w.word(static_cast<std::uint32_t>(body.size())) + body;
      const fs::path r = write_file("dims3.mat", w.file(fixed, z));
      const std::string e3 =
          message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(r.string()); });
      EXPECT_TRUE(contains(e3, r.string()) && contains(e3, "ends before its values")) << e3;
    }
  }
}

TEST(ReadMatV5, InconsistentSparseIndicesAreFormatErrors) {
  const V5Writer w;
  const auto read = [&](const std::string& data) {
    const fs::path p = write_file("sparse-bad.mat", w.file(w.matrix(5, {4, 4}, data), true));
    return message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
  };
  // The column index counts 3 entries, the row index holds 2.
  EXPECT_TRUE(contains(read(w.element(5, w.words({3, 2})) + w.element(5, w.words({0, 1, 2, 3, 3})) +
                            w.element(9, w.doubles({1, 1, 1}))),
                       "counts 3 entries, its row index holds 2"));
  // Fewer values than entries.
  EXPECT_TRUE(contains(read(w.element(5, w.words({3, 2})) + w.element(5, w.words({0, 1, 2, 2, 2})) +
                            w.element(9, w.doubles({1}))),
                       "holds 1 values for 2 entries"));
  // A row beyond the matrix, a column index of the wrong length, decreasing.
  EXPECT_TRUE(contains(read(w.element(5, w.words({9, 2})) + w.element(5, w.words({0, 1, 2, 2, 2})) +
                            w.element(9, w.doubles({1, 1}))),
                       "row index 10 is beyond its 4 rows"));
  EXPECT_TRUE(contains(read(w.element(5, w.words({3, 2})) + w.element(5, w.words({0, 1, 2, 2})) +
                            w.element(9, w.doubles({1, 1}))),
                       "column index has 4 entries"));
  EXPECT_TRUE(contains(read(w.element(5, w.words({3, 2})) + w.element(5, w.words({0, 2, 1, 2, 2})) +
                            w.element(9, w.doubles({1, 1}))),
                       "column 2 ends before it starts"));
}

// Found by the issue 15 re-run: a flipped byte in a compressed variable can
// still inflate to plausible matrices (made-up pairs) unless the stream is
// read to its end, where zlib checks its Adler-32; and a sparse matrix whose
// values claim more bytes than the variable holds was read as if intact.
TEST(ReadMatV5, CompressedStreamsPassTheirCheckAndClaimedValuesExist) {
  const V5Writer w;
  const std::string sparse = w.element(5, w.words({3, 2})) + w.element(5, w.words({0, 1, 2, 2, 2})) +
                             w.element(9, w.doubles({1, 1}));
  for (const std::string& data : {w.element(9, w.doubles(four_by_four())), sparse}) {
    const std::uint32_t cls = data == sparse ? 5 : 6;
    std::string bytes = w.file(w.matrix(cls, {4, 4}, data), true);
    bytes[bytes.size() - 2] ^= 0x5A;  // inside the Adler-32 at the stream's end
    const fs::path p = write_file("adler.mat", bytes);
    const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
    EXPECT_TRUE(contains(e, p.string()) && contains(e, "incorrect data check")) << e;
  }
  for (bool z : {false, true}) {
    // Values of 3 doubles claimed, 2 present: the claim runs past the variable.
    const std::string claimed = w.element(5, w.words({3, 2})) +
                                w.element(5, w.words({0, 1, 2, 2, 2})) + w.word(9) + w.word(24) +
                                w.doubles({1, 1});
    const fs::path p = write_file("claims.mat", w.file(w.matrix(5, {4, 4}, claimed), z));
    const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
    EXPECT_TRUE(contains(e, p.string()) && contains(e, "values")) << "z " << z << ": " << e;
  }
}

// Found by CI's fuzz_gt: matio's Mat_VarReadNextInfo callocs what a cell
// claims (0x30000004 elements: 6 GB) before it reads one, at any depth, so
// read_mat() lists a v5 file's variables from its own header reader: a file
// with such a cell beside its ground truth reads, and the cell is described
// (never allocated) when it is named or is all the file has. The allocation
// itself is caught by fuzz_gt's seed v5cell-claims-6GB.mat (-malloc_limit_mb).
TEST(ReadMatV5, CellsAndStructsAreListedWithoutAllocatingWhatTheyClaim) {
  for (bool big : {false, true}) {
    for (bool z : {false, true}) {
      SCOPED_TRACE(concat_trace(big, z));
      const V5Writer w{big};
      const std::string empty = w.matrix(6, {0, 0}, "", "");
      const std::string cell = w.matrix(1, {0x30000004, 1}, empty, "c");
      const std::string nested = w.matrix(1, {1, 1}, w.matrix(1, {0x30000004, 1}, empty, ""), "n");
      const std::string gt = w.matrix(6, {4, 4}, w.element(9, w.doubles(four_by_four())));
      std::string file = w.file(cell, z);
      file += w.file(nested, z).substr(128) + w.file(gt, z).substr(128);
      const fs::path p = write_file("cells.mat", file);
      EXPECT_EQ(pairs_of(lsgd::eval::read_mat(p.string(), 4)), (Pairs{{3, 0}, {2, 1}}));
      std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string(), 4, "c"); });
      EXPECT_TRUE(contains(e, p.string()) && contains(e, "variable c 805306372x1 class 1 is not a square"))
          << e;
      const fs::path q = write_file("only-cells.mat", w.file(cell, z) + w.file(nested, z).substr(128));
      e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(q.string()); });
      EXPECT_TRUE(contains(e, "(variables: c 805306372x1 class 1, n 1x1 class 1)")) << e;
    }
  }
  // Logical and complex flags are described as matio did.
  const V5Writer w;
  const std::string flags = w.element(6, w.words({6 | 0x200 | 0x800, 0}));
  const fs::path r = write_file("flags.mat", w.file(w.matrix_of(flags, w.element(5, w.words({3, 5})), "", "x"), false));
  const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(r.string()); });
  EXPECT_TRUE(contains(e, "(variables: x 3x5 class 6 logical complex)")) << e;
}

}  // namespace
