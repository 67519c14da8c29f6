// MAT v4 sparse matrices built byte by byte (eval/gt_formats.h read_mat):
// what scipy.io.savemat(..., format='4') writes for a scipy.sparse matrix,
// in both byte orders and every value type, and last rows, indices and
// sizes that disagree with the data. matio describes such a matrix by its
// stored triplets (nonzeros + 1 rows by 3 columns), so it was refused as
// "no square matrix" before lsgd read v4 sparse matrices itself.
#include "lsgd/eval/gt_formats.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "gt_formats_test_support.h"
#include "test_util.h"

namespace fs = std::filesystem;
using lsgd::test::message_of;

namespace {

using gt_formats_test_support::contains;
using gt_formats_test_support::kN;
using gt_formats_test_support::kPairs;
using gt_formats_test_support::Pairs;
using gt_formats_test_support::pairs_of;
using gt_formats_test_support::write_file;

struct Triplet {
  double row, col, value;  // 1-based, as stored
};

// A v4 variable: header, name, then its rows x cols values column by column.
struct V4Writer {
  bool big_endian = false;
  int precision = 0;  // P: 0 double, 1 single, 2 int32, 3 int16, 4 uint16, 5 uint8

  std::string word(std::uint32_t v) const {
    std::string b(4, '\0');
    for (int i = 0; i < 4; ++i) b[i] = static_cast<char>(v >> (big_endian ? 24 - 8 * i : 8 * i));
    return b;
  }
  std::string value(double v) const {
    unsigned char b[8];
    std::size_t n = 0;
    const auto put = [&](const auto x) {
      n = sizeof(x);
      std::memcpy(b, &x, n);
    };
    switch (precision) {
      case 0: put(v); break;
      case 1: put(static_cast<float>(v)); break;
      case 2: put(static_cast<std::int32_t>(v)); break;
      case 3: put(static_cast<std::int16_t>(v)); break;
      case 4: put(static_cast<std::uint16_t>(v)); break;
      default: put(static_cast<std::uint8_t>(v)); break;
    }
    std::string out(n, '\0');
    for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<char>(b[big_endian ? n - 1 - i : i]);
    return out;
  }
  // Type T = 2 (sparse): the triplets and the last row (rows, cols, 0).
  std::string sparse(const std::string& name, const std::vector<Triplet>& nonzeros, double rows,
                     double cols) const {
    std::vector<Triplet> all = nonzeros;
    all.push_back({rows, cols, 0});
    std::string b = word((big_endian ? 1000 : 0) + precision * 10 + 2) +
                    word(static_cast<std::uint32_t>(all.size())) + word(3) + word(0) +
                    word(static_cast<std::uint32_t>(name.size() + 1)) + name + std::string(1, '\0');
    for (const Triplet& t : all) b += value(t.row);
    for (const Triplet& t : all) b += value(t.col);
    for (const Triplet& t : all) b += value(t.value);
    return b;
  }
  // Type T = 0 (full), every value `fill`.
  std::string full(const std::string& name, std::uint32_t rows, std::uint32_t cols, double fill) const {
    std::string b = word((big_endian ? 1000 : 0) + precision * 10) + word(rows) + word(cols) +
                    word(0) + word(static_cast<std::uint32_t>(name.size() + 1)) + name +
                    std::string(1, '\0');
    for (std::uint32_t k = 0; k < rows * cols; ++k) b += value(fill);
    return b;
  }
};

// kPairs as the lower triangle, 1-based, as scipy writes them.
std::vector<Triplet> pair_triplets() {
  std::vector<Triplet> out;
  for (const auto& [q, m] : kPairs) out.push_back({static_cast<double>(q + 1), static_cast<double>(m + 1), 1});
  return out;
}

std::string read_error(const fs::path& p) {
  return message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
}

TEST(ReadMatV4, SparseMatricesInEitherByteOrderAndEveryValueType) {
  for (const bool big : {false, true}) {
    for (int precision = 0; precision <= 5; ++precision) {
      SCOPED_TRACE(testing::Message() << (big ? "big" : "little") << "-endian, P " << precision);
      const V4Writer w{big, precision};
      const fs::path p = write_file("v4sparse.mat", w.sparse("truth", pair_triplets(), kN, kN));
      const lsgd::eval::GroundTruth gt = lsgd::eval::read_mat(p.string());
      EXPECT_EQ(gt.frames(), static_cast<std::int64_t>(kN));
      EXPECT_EQ(pairs_of(gt), kPairs);
    }
  }
}

TEST(ReadMatV4, ZerosAndTheUpperTriangleAsInDenseFiles) {
  std::vector<Triplet> t = pair_triplets();
  t.push_back({5, 20, 0});  // a stored zero is no loop
  t.push_back({3, 13, 1});  // the upper triangle (13, 3 transposed: already a pair)
  const fs::path p = write_file("v4zeros.mat", V4Writer{}.sparse("gt", t, kN, kN));
  EXPECT_EQ(pairs_of(lsgd::eval::read_mat(p.string())), kPairs);
  // No nonzero at all: an empty ground truth of its size.
  const fs::path e = write_file("v4empty.mat", V4Writer{}.sparse("gt", {}, kN, kN));
  const lsgd::eval::GroundTruth empty = lsgd::eval::read_mat(e.string());
  EXPECT_EQ(empty.frames(), static_cast<std::int64_t>(kN));
  EXPECT_TRUE(pairs_of(empty).empty());
}

TEST(ReadMatV4, SparseChosenByNameAfterOtherVariables) {
  const V4Writer w;
  const std::string bytes = w.full("scores", 3, 7, 0.5) + w.sparse("other", {{2, 1, 1}}, kN, kN) +
                            w.sparse("gt", pair_triplets(), kN, kN);
  const fs::path p = write_file("v4three.mat", bytes);
  EXPECT_EQ(pairs_of(lsgd::eval::read_mat(p.string())), kPairs);                 // the one named gt
  EXPECT_EQ(pairs_of(lsgd::eval::read_mat(p.string(), -1, "other")), (Pairs{{1, 0}}));
  EXPECT_EQ(lsgd::eval::read_mat(p.string(), kN).frames(), static_cast<std::int64_t>(kN));
  const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string(), kN + 1); });
  EXPECT_TRUE(contains(e, "40x40") && contains(e, "41 frames")) << e;
}

TEST(ReadMatV4, SizesAndIndicesThatDisagreeAreFormatErrors) {
  const V4Writer w;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    const char* label;
    std::string bytes;
    const char* expect;
  };
  const std::vector<Case> cases = {
      {"not square", w.sparse("gt", pair_triplets(), kN, kN + 1), "no square"},
      {"a row beyond the size", w.sparse("gt", {{kN + 1, 1, 1}}, kN, kN), "outside its 40 x 40"},
      {"a column beyond the size", w.sparse("gt", {{2, kN + 1, 1}}, kN, kN), "outside its 40 x 40"},
      {"index 0", w.sparse("gt", {{0, 1, 1}}, kN, kN), "outside"},
      {"a fractional index", w.sparse("gt", {{2.5, 1, 1}}, kN, kN), "outside"},
      {"a NaN index", w.sparse("gt", {{nan, 1, 1}}, kN, kN), "outside"},
      {"a NaN value", w.sparse("gt", {{2, 1, nan}}, kN, kN), "NaN"},
      {"a value -1", w.sparse("gt", {{2, 1, -1}}, kN, kN), "(2, 1) is -1"},
      {"a value 0.5", w.sparse("gt", {{3, 1, 0.5}}, kN, kN), "(3, 1) is 0.5"},
      {"a NaN size", w.sparse("gt", {}, nan, nan), "not two whole numbers"},
      {"a negative size", w.sparse("gt", {}, -4, -4), "not two whole numbers"},
      // A size matio would allocate a column index for (8 GB): refused first.
      {"size 2^31 - 1", w.sparse("gt", {{2, 1, 1}}, 2147483647.0, 2147483647.0), "more than 1e6 frames"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.label);
    const fs::path p = write_file("v4bad.mat", c.bytes);
    const std::string e = read_error(p);
    EXPECT_TRUE(contains(e, p.string()) && contains(e, c.expect)) << e;
  }
  // Stored as rows x 2: not triplets.
  std::string two = w.word(2) + w.word(2) + w.word(2) + w.word(0) + w.word(3) + std::string("gt\0", 3);
  for (int k = 0; k < 4; ++k) two += w.value(1);
  const fs::path p = write_file("v4pairs.mat", two);
  const std::string e = read_error(p);
  EXPECT_TRUE(contains(e, p.string()) && contains(e, "triplets")) << e;
}

}  // namespace
