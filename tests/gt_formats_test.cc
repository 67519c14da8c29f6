// Tests of the ground-truth readers, format detection, KITTI poses -> loops and
// statistics (eval/gt_formats.h): generated files of every format (MAT files
// written here with matio), broken files, and the real files of
// ../shared/groundtruth when present (skipped with a message otherwise).
#include "lsgd/eval/gt_formats.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <matio.h>
#include <zlib.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "lsgd/error.h"
#include "test_util.h"

namespace fs = std::filesystem;
using lsgd::eval::GroundTruth;
using lsgd::eval::GtFormat;
using lsgd::eval::Pose;
using lsgd::test::message_of;

namespace {

const fs::path kTmp = fs::path(LSGD_TEST_TMP) / ("gtf-" + std::to_string(getpid()));
const fs::path kGt = fs::path(LSGD_SHARED_DIR) / "groundtruth";

using Pairs = std::set<std::pair<std::int64_t, std::int64_t>>;  // (q, m), q > m

fs::path write_file(const std::string& name, const std::string& text) {
  fs::create_directories(kTmp);
  const fs::path path = kTmp / name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

Pairs pairs_of(const GroundTruth& gt) {
  Pairs out;
  for (std::int64_t q = 0; q < gt.frames(); ++q) {
    for (std::int64_t m : gt.matches(q)) out.emplace(q, m);
  }
  return out;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// ---- MAT files written with matio ---------------------------------------------

enum class Layout { kLower, kUpper, kFull };

// Column-major n x n matrix with `one` at each pair, placed per layout.
template <typename T>
std::vector<T> dense(std::size_t n, const Pairs& pairs, Layout layout, T one = T(1)) {
  std::vector<T> m(n * n, T(0));
  for (const auto& [q, mm] : pairs) {
    const auto r = static_cast<std::size_t>(q), c = static_cast<std::size_t>(mm);
    if (layout != Layout::kUpper) m[c * n + r] = one;  // GT(q, m), below the diagonal
    if (layout != Layout::kLower) m[r * n + c] = one;  // GT(m, q), above
  }
  return m;
}

struct MatVarSpec {
  std::string name;
  matio_classes cls;
  matio_types type;
  std::size_t rows, cols;
  void* data;
  int flags = 0;
};

// Writes the variables; false when this matio cannot create the version.
bool write_mat(const fs::path& path, const std::vector<MatVarSpec>& vars,
               mat_ft version = MAT_FT_MAT5, matio_compression z = MAT_COMPRESSION_ZLIB) {
  fs::create_directories(path.parent_path());
  fs::remove(path);
  mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, version);
  if (!mat) return false;
  bool ok = true;
  for (const auto& v : vars) {
    std::size_t dims[2] = {v.rows, v.cols};
    matvar_t* var = Mat_VarCreate(v.name.c_str(), v.cls, v.type, 2, dims, v.data,
                                  v.flags | MAT_F_DONT_COPY_DATA);
    ok = ok && var && Mat_VarWrite(mat, var, z) == 0;
    Mat_VarFree(var);
  }
  Mat_Close(mat);
  return ok;
}

// A 40-frame ground truth with loops at several gaps, including (39, 0).
const std::size_t kN = 40;
const Pairs kPairs = {{12, 2}, {13, 3}, {30, 10}, {31, 10}, {39, 0}, {25, 24}};

fs::path write_dense_u8(const std::string& name, Layout layout, bool logical,
                        matio_compression z = MAT_COMPRESSION_ZLIB) {
  auto m = dense<std::uint8_t>(kN, kPairs, layout);
  const fs::path p = kTmp / name;
  EXPECT_TRUE(write_mat(
      p, {{"GT", MAT_C_UINT8, MAT_T_UINT8, kN, kN, m.data(), logical ? MAT_F_LOGICAL : 0}},
      MAT_FT_MAT5, z));
  return p;
}

TEST(ReadMat, LowerUpperAndFullLogicalGiveTheSamePairs) {
  for (Layout layout : {Layout::kLower, Layout::kUpper, Layout::kFull}) {
    const fs::path p = write_dense_u8("logical.mat", layout, true);
    const GroundTruth gt = lsgd::eval::read_mat(p.string());
    EXPECT_EQ(gt.frames(), static_cast<std::int64_t>(kN));
    EXPECT_EQ(pairs_of(gt), kPairs) << "layout " << static_cast<int>(layout);
  }
}

TEST(ReadMat, EveryNumericClassCompressedOrNot) {
  auto d = dense<double>(kN, kPairs, Layout::kLower, 1.0);
  auto f = dense<float>(kN, kPairs, Layout::kUpper, 0.5f);
  auto i8 = dense<std::int8_t>(kN, kPairs, Layout::kLower, -1);
  auto u16 = dense<std::uint16_t>(kN, kPairs, Layout::kFull, 7);
  auto i32 = dense<std::int32_t>(kN, kPairs, Layout::kLower, 3);
  auto u64 = dense<std::uint64_t>(kN, kPairs, Layout::kUpper, 1);
  const std::vector<MatVarSpec> specs = {
      {"d", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN, d.data()},
      {"f", MAT_C_SINGLE, MAT_T_SINGLE, kN, kN, f.data()},
      {"i8", MAT_C_INT8, MAT_T_INT8, kN, kN, i8.data()},
      {"u16", MAT_C_UINT16, MAT_T_UINT16, kN, kN, u16.data()},
      {"i32", MAT_C_INT32, MAT_T_INT32, kN, kN, i32.data()},
      {"u64", MAT_C_UINT64, MAT_T_UINT64, kN, kN, u64.data()},
  };
  for (auto z : {MAT_COMPRESSION_NONE, MAT_COMPRESSION_ZLIB}) {
    for (const auto& spec : specs) {
      const fs::path p = kTmp / ("class-" + spec.name + ".mat");
      ASSERT_TRUE(write_mat(p, {spec}, MAT_FT_MAT5, z)) << spec.name;
      EXPECT_EQ(pairs_of(lsgd::eval::read_mat(p.string())), kPairs) << spec.name << " z=" << z;
    }
  }
  const fs::path u8 = write_dense_u8("uint8.mat", Layout::kLower, false, MAT_COMPRESSION_NONE);
  EXPECT_EQ(pairs_of(lsgd::eval::read_mat(u8.string())), kPairs);
}

TEST(ReadMat, SparseDoubleAndLogical) {
  // Lower-triangular sparse: column c holds rows q of pairs (q, c), ascending.
  std::vector<mat_uint32_t> ir, jc(kN + 1, 0);
  for (std::size_t c = 0; c < kN; ++c) {
    for (const auto& [q, m] : kPairs) {
      if (static_cast<std::size_t>(m) == c) ir.push_back(static_cast<mat_uint32_t>(q));
    }
    jc[c + 1] = static_cast<mat_uint32_t>(ir.size());
  }
  std::vector<double> values(ir.size(), 1.0);
  values[0] = 0.0;  // an explicit zero is no loop
  std::vector<std::uint8_t> flags(ir.size(), 1);
  mat_sparse_t sd{};
  sd.nzmax = sd.nir = sd.ndata = static_cast<mat_uint32_t>(ir.size());
  sd.ir = ir.data();
  sd.jc = jc.data();
  sd.njc = static_cast<mat_uint32_t>(jc.size());
  sd.data = values.data();
  mat_sparse_t sl = sd;
  sl.data = flags.data();
  const fs::path p = kTmp / "sparse.mat";
  ASSERT_TRUE(write_mat(p, {{"sd", MAT_C_SPARSE, MAT_T_DOUBLE, kN, kN, &sd}}));
  Pairs expected = kPairs;
  expected.erase({39, 0});  // stored first (column 0) with the explicit zero
  EXPECT_EQ(pairs_of(lsgd::eval::read_mat(p.string())), expected);
  ASSERT_TRUE(write_mat(p, {{"sl", MAT_C_SPARSE, MAT_T_UINT8, kN, kN, &sl, MAT_F_LOGICAL}}));
  EXPECT_EQ(pairs_of(lsgd::eval::read_mat(p.string())), kPairs);
}

TEST(ReadMat, Version73AndVersion4) {
  auto d = dense<double>(kN, kPairs, Layout::kLower);
  const fs::path v73 = kTmp / "v73.mat";
  if (write_mat(v73, {{"gt", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN, d.data()}}, MAT_FT_MAT73)) {
    EXPECT_EQ(lsgd::eval::detect_gt_format(v73.string()), std::string(lsgd::eval::kMatGtFormat));
    EXPECT_EQ(pairs_of(lsgd::eval::read_mat(v73.string())), kPairs);
  } else {
    std::cout << "this matio cannot write MAT v7.3 (no HDF5): v7.3 not tested\n";
  }
  const fs::path v4 = kTmp / "v4.mat";
  ASSERT_TRUE(write_mat(v4, {{"gt", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN, d.data()}}, MAT_FT_MAT4,
                        MAT_COMPRESSION_NONE));
  EXPECT_EQ(lsgd::eval::detect_gt_format(v4.string()), std::string(lsgd::eval::kMatGtFormat));  // by its extension
  EXPECT_EQ(pairs_of(lsgd::eval::read_mat(v4.string())), kPairs);
}

TEST(ReadMat, ChoosesTheVariableByNameThenOrder) {
  auto other = dense<double>(kN, {{5, 1}}, Layout::kLower);
  auto gt = dense<double>(kN, kPairs, Layout::kLower);
  std::vector<double> row(kN, 1.0);
  const fs::path p = kTmp / "vars.mat";
  ASSERT_TRUE(write_mat(p, {{"row", MAT_C_DOUBLE, MAT_T_DOUBLE, 1, kN, row.data()},
                            {"scores", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN, other.data()},
                            {"myGroundTruth", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN, gt.data()}}));
  EXPECT_EQ(pairs_of(lsgd::eval::read_mat(p.string())), kPairs);  // "truth" in the name wins
  EXPECT_EQ(pairs_of(lsgd::eval::read_mat(p.string(), -1, "scores")), (Pairs{{5, 1}}));
  const std::string missing =
      message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string(), -1, "nothere"); });
  EXPECT_TRUE(contains(missing, "nothere") && contains(missing, p.string())) << missing;
  EXPECT_THROW(lsgd::eval::read_mat(p.string(), -1, "row"), lsgd::FormatError);  // 1 x N

  ASSERT_TRUE(write_mat(p, {{"row", MAT_C_DOUBLE, MAT_T_DOUBLE, 1, kN, row.data()},
                            {"a", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN, other.data()},
                            {"b", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN, gt.data()}}));
  EXPECT_EQ(pairs_of(lsgd::eval::read_mat(p.string())), (Pairs{{5, 1}}));  // first square one
  ASSERT_TRUE(write_mat(p, {{"row", MAT_C_DOUBLE, MAT_T_DOUBLE, 1, kN, row.data()}}));
  const std::string none = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
  EXPECT_TRUE(contains(none, p.string()) && contains(none, "row 1x40")) << none;
}

TEST(ReadMat, FrameCountMismatchNamesBoth) {
  const fs::path p = write_dense_u8("count.mat", Layout::kLower, true);
  EXPECT_EQ(lsgd::eval::read_mat(p.string(), 40).frames(), 40);
  const std::string e =
      message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string(), 41); });
  EXPECT_TRUE(contains(e, p.string()) && contains(e, "40x40") && contains(e, "41")) << e;
}

TEST(ReadMat, RejectsNonSquareComplexAndNaN) {
  std::vector<double> rect(kN * (kN + 1), 0.0);
  const fs::path p = kTmp / "bad.mat";
  ASSERT_TRUE(write_mat(p, {{"GT", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN + 1, rect.data()}}));
  EXPECT_THROW(lsgd::eval::read_mat(p.string()), lsgd::FormatError);

  std::vector<double> re(kN * kN, 0.0), im(kN * kN, 0.0);
  mat_complex_split_t split{re.data(), im.data()};
  ASSERT_TRUE(write_mat(p, {{"GT", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN, &split, MAT_F_COMPLEX}}));
  EXPECT_THROW(lsgd::eval::read_mat(p.string()), lsgd::FormatError);

  auto d = dense<double>(kN, kPairs, Layout::kLower);
  d[3 * kN + 20] = std::nan("");
  ASSERT_TRUE(write_mat(p, {{"GT", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN, d.data()}}));
  const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
  EXPECT_TRUE(contains(e, "NaN") && contains(e, "(21, 4)")) << e;
}

TEST(ReadMat, DiagonalIsIgnored) {
  auto d = dense<double>(kN, kPairs, Layout::kLower);
  for (std::size_t i = 0; i < kN; ++i) d[i * kN + i] = 1.0;
  const fs::path p = kTmp / "diag.mat";
  ASSERT_TRUE(write_mat(p, {{"GT", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN, d.data()}}));
  EXPECT_EQ(pairs_of(lsgd::eval::read_mat(p.string())), kPairs);
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Truncated files are FormatErrors naming the file; byte flips and garbage
// must throw an lsgd::Error or read, never crash.
TEST(ReadMat, TruncatedAndCorruptFiles) {
  for (auto z : {MAT_COMPRESSION_ZLIB, MAT_COMPRESSION_NONE}) {
    const std::string bytes = slurp(write_dense_u8("whole.mat", Layout::kLower, true, z));
    ASSERT_GT(bytes.size(), 200u);
    for (std::size_t keep :
         {std::size_t{0}, std::size_t{10}, std::size_t{127}, std::size_t{128}, std::size_t{140},
          std::size_t{200}, bytes.size() / 2, bytes.size() - 1}) {
      const fs::path p = write_file("cut.mat", bytes.substr(0, keep));
      const std::string e =
          message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
      EXPECT_TRUE(contains(e, p.string())) << "z=" << z << " keep " << keep << ": " << e;
    }
    std::uint64_t seed = 7;
    for (int trial = 0; trial < 60; ++trial) {
      std::string flipped = bytes;
      const std::size_t at = 116 + lsgd::test::splitmix64(seed) % (flipped.size() - 116);
      flipped[at] = static_cast<char>(flipped[at] ^ (1 + lsgd::test::splitmix64(seed) % 255));
      const fs::path p = write_file("flip.mat", flipped);
      const std::string e = message_of<lsgd::Error>([&] { lsgd::eval::read_mat(p.string()); });
      EXPECT_TRUE(e == "<no exception>" || contains(e, p.string()))
          << "flip at " << at << ": " << e;
    }
  }
  const fs::path text = write_file("text.mat", "1 2\n3 4\n");
  EXPECT_TRUE(contains(message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(text.string()); }),
                       text.string()));
  EXPECT_THROW(lsgd::eval::read_mat((kTmp / "absent.mat").string()), lsgd::IoError);
}

// Found by fuzz/fuzz_gt: without a v5 header matio reads MAT v4 and mallocs the
// first name length unchecked (here 0x756e696c, ~2 GB, from 104 bytes).
TEST(ReadMat, V4NameLengthBeyondTheFileIsFormatError) {
  std::string bytes(4, '\0');
  bytes += ": x86_64-pc-linu";  // mrows, ncols, imagf, namelen (little-endian)
  bytes += std::string(84, 'x');
  const fs::path p = write_file("v4name.mat", bytes);
  const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
  EXPECT_TRUE(contains(e, p.string()) && contains(e, "name length")) << e;
}

// A fuzzer find: a MAT v5 matrix whose dimensions sub-element claims more
// bytes than its matrix element holds; matio would allocate gigabytes for it.
TEST(ReadMat, V5SubElementBeyondItsMatrixIsFormatError) {
  static const char kBytes[] =
      "\x0d\x4d\x41\x54\x4c\x41\x42\x20\x35\x2e\x30\x20\x4d\x41\x54\x2d\x66\x69\x6c\x65\x26\x20\x50\x6c"
      "\x61\x74\x66\x6f\x72\x6d\x3a\x20\x78\x38\x36\x5f\x36\x34\x2d\x70\x63\x2d\x6c\x69\x6e\x75\x78\x2d"
      "\x67\x6e\x75\x2c\x20\x43\x72\x65\x61\x74\x65\x64\x20\x62\x79\x3a\x20\x6c\x69\x62\x6d\x61\x74\x69"
      "\x6f\x20\x76\x31\x2e\x35\x2e\x32\x33\x20\x6f\x6e\x20\x4d\x6f\x6e\x20\x4e\x6f\x76\x20\x32\x33\x20"
      "\x32\x32\x3a\x35\x34\x3a\x34\x32\x20\x32\x30\x32\x36\x0a\x00\x20\x20\x20\x20\x20\x20\x20\x20\x20"
      "\x20\x20\x20\x20\x20\x00\x01\x49\x4d\x0e\x00\x00\x00\x50\x01\x00\x00\x06\x00\x00\x00\x08\x00\x00"
      "\x00\x06\x00\x00\x00\x00\x00\x00\x00\x05\x00\x00\x00\x30\x2a\x30\xdf\xcf\xd1\x8b\x78\x74\x0a\x00"
      "\x00\x01\x00\x02\x00\x47\x54\x00\x00\x09\x00\x00\x00\x20\x01\x00\x00\x00\x00\x00\x00\x00\x00\x00"
      "\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00"
      "\x00\x00\x00\x00\x00\x00\x00\xf0\x3f\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00"
      "\x00\x00\x00\x00\x00\x00\x00\x00\x00\x4e\x34\x6c\x73\x67\x64\x35\x45\x72\x72\x0d\x4d\x41\x54\x4c"
      "\x41\x42\x20\x35\x2e\x30\x20\x4d\x41\x54\x2d\x66\x69\x6c\x65\x2c\x20\x50\x6c\x61\x74\x66\x6f\x72"
      "\x6d\x3a\x20\x78\x38\x36\x5f\x36\x34\x2d\x70\x63\x2d\x6c\x69\x6e\x75\x78\x2d\x67\x6e\x75\x2c\x20"
      "\x43\x72\x65\x61\x74\x65\x64\x20\x62\x79\x3a\x20\x6c\x69\x62\x6d\x61\x74\x61\x6f\x20\x76\x31\x2e"
      "\x35\x2e\x32\x33\x20\x6f\x6e\x20\x4d\x6f\x6e\x20\x4e\x6f\x76\x20\x32\x33\x20\x32\x32\x3a\x35\x34"
      "\x3a\x34\x32\x20\x32\x30\x32\x36\x0a\x00\x20\x20\x20\x20\x20\x20\x20\x20\x20\x20\x20\x20\x20\x20"
      "\x00\x01\x49\x4d\x0f\x00\x00\x00\x35\x00\x00\x00\x78\x9c\xe3\x63\x60\x60\x08\x60\x64\x60\x60\x03"
      "\xd2\x1c\x0c\x10\x1a\x04\x4e\x34\x6c\x73\x67\x64\x35\x45\x72\x72\x6f\x72\x45\x09\x64\x2b\x30\x32"
      "\x10\x09\x3e\xd8\x13\xab\x92\x3a\xfa\x06\x0f\x00\x00\xae\x6d\x03\xb3\x00\x00\x00\x00\x00\x00\x00"
      "\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00";
  // Byte 0 is the fuzzer's control byte (file suffix and frame count).
  const fs::path p = write_file("v5sub.mat", std::string(kBytes + 1, sizeof(kBytes) - 2));
  const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
  // Rejected by our check of the sub-element sizes, before matio allocates.
  EXPECT_TRUE(contains(e, p.string()) && contains(e, "element at byte 152 needs")) << e;
}

// A fuzzer find: a compressed MAT v5 variable whose header made matio calloc
// 4 GB before reading its data; the header is checked first now.
TEST(ReadMat, CorruptCompressedHeaderIsFormatErrorBeforeMatioAllocates) {
  static const char kBytes[] =
      "\x4d\x41\x54\x4c\x41\x42\x20\x35\x2e\x30\x20\x4d\x41\x54\x69\x2d\x66\x6c\x65\x2c\x20\x00\x00\x05"
      "\x00\x00\x00\x08\x00\x00\x00\x06\x00\x00\x00\x06\x00\x00\x00\x01\x00\x02\x00\x47\x54\x00\x00\x09"
      "\x00\x00\x00\x20\x01\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x40"
      "\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x01\x3f\x00\x00\x00\x00\xf0\x3f\x00"
      "\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x32\x36\x0a\x00\x20\x20\x20\x20\x20\x20\x20\x20\x20\x20"
      "\x20\x20\x20\x20\x00\x01\x49\x4d\x0f\x00\x00\x00\x35\x00\x00\x00\x78\x9c\xe3\x63\x60\x60\x08\x60"
      "\x64\x70\x60\x03\xd2\x1c\x0c\x10\x1a\x04\x58\x91\xf8\x20\xcc\xc8\xc0\xc4\xe0\x1e\xc2\xc0\xc0\x09"
      "\x64\x2b\x30\x34\x10\x09\x3e\xd8\x13\xab\x92\x2b\x00\x00\x00\x00\x00\xae\x6d\x03\xb3";
  const fs::path p = write_file("v5z.mat", std::string(kBytes, sizeof(kBytes) - 1));
  const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
  EXPECT_TRUE(contains(e, p.string()) && contains(e, "is corrupt")) << e;
}

// ---- MAT v5 files built byte by byte ---------------------------------------------
//
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
                     const std::string& data) const {
    return matrix_of(element(6, words({cls, 0})), element(5, words(dims)), data);
  }
  // The same from its array flags and dimensions sub-elements as given.
  std::string matrix_of(const std::string& flags, const std::string& dims,
                        const std::string& data) const {
    const std::string body = flags + dims + element(1, "GT") + data;
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

// ---- KITTI poses ------------------------------------------------------------------

std::string pose_line(double x, double y, double z, bool timestamp, double t = 0) {
  std::ostringstream s;
  s.precision(17);
  if (timestamp) s << t << ' ';
  s << "1 0 0 " << x << " 0 1 0 " << y << " 0 0 1 " << z << '\n';
  return s.str();
}

TEST(ReadKittiPoses, TwelveAndThirteenColumns) {
  std::string twelve, thirteen;
  for (int i = 0; i < 5; ++i) {
    twelve += pose_line(i, -0.5 * i, 2.0 * i, false);
    thirteen += pose_line(i, -0.5 * i, 2.0 * i, true, 0.1 * i);
  }
  const auto a = lsgd::eval::read_kitti_poses(write_file("p12.txt", twelve).string());
  const auto b =
      lsgd::eval::read_kitti_poses(write_file("p13.txt", "# c\n" + thirteen + "\n").string());
  ASSERT_EQ(a.size(), 5u);
  ASSERT_EQ(b.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_DOUBLE_EQ(a[i].x, i);
    EXPECT_DOUBLE_EQ(a[i].y, -0.5 * i);
    EXPECT_DOUBLE_EQ(a[i].z, 2.0 * i);
    EXPECT_DOUBLE_EQ(b[i].x, a[i].x);
    EXPECT_DOUBLE_EQ(b[i].y, a[i].y);
    EXPECT_DOUBLE_EQ(b[i].z, a[i].z);
  }
}

TEST(ReadKittiPoses, ErrorsNameFileAndLine) {
  const auto expect_line = [](const std::string& name, const std::string& text, int line) {
    const fs::path p = write_file(name, text);
    const std::string e =
        message_of<lsgd::FormatError>([&] { lsgd::eval::read_kitti_poses(p.string()); });
    EXPECT_TRUE(contains(e, p.string() + ":" + std::to_string(line))) << e;
  };
  const std::string ok = pose_line(1, 2, 3, false);
  expect_line("p11.txt", ok + "1 2 3 4 5 6 7 8 9 10 11\n", 2);
  expect_line("pmix.txt", ok + ok + pose_line(1, 2, 3, true), 3);
  expect_line("pword.txt", "\n" + ok + "1 0 0 x 0 1 0 2 0 0 1 3\n", 3);
  expect_line("pinf.txt", "1 0 0 inf 0 1 0 2 0 0 1 3\n", 1);
  EXPECT_THROW(lsgd::eval::read_kitti_poses(write_file("pnone.txt", "# nothing\n").string()),
               lsgd::FormatError);
  EXPECT_THROW(lsgd::eval::read_kitti_poses((kTmp / "absent.txt").string()), lsgd::IoError);
}

// Brute force, the definition: i - j > gap and |c_i - c_j| < d.
Pairs brute_force(const std::vector<Pose>& poses, double d, std::int64_t gap) {
  Pairs out;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const double dx = poses[i].x - poses[j].x, dy = poses[i].y - poses[j].y,
                   dz = poses[i].z - poses[j].z;
      if (static_cast<std::int64_t>(i - j) > gap && std::sqrt(dx * dx + dy * dy + dz * dz) < d) {
        out.emplace(static_cast<std::int64_t>(i), static_cast<std::int64_t>(j));
      }
    }
  }
  return out;
}

TEST(GroundTruthFromPoses, MatchesBruteForceOnALoopingWalk) {
  // A walk around a 60 m square, three laps with lateral noise: many revisits.
  std::vector<Pose> poses;
  std::uint64_t seed = 3;
  for (int k = 0; k < 720; ++k) {
    const double s = std::fmod(k * 1.0, 240.0), side = std::floor(s / 60), t = s - 60 * side;
    const double noise = (static_cast<double>(lsgd::test::splitmix64(seed) % 1000) / 1000 - 0.5);
    double x = side == 0 ? t : side == 1 ? 60 : side == 2 ? 60 - t : 0;
    double z = side == 0 ? 0 : side == 1 ? t : side == 2 ? 60 : 60 - t;
    poses.push_back(
        {x + noise, 0.3 * noise - 1000, z - noise});  // far from the origin: negative cells
  }
  for (double d : {0.7, 3.0, 10.0, 25.0}) {
    for (std::int64_t gap : {0, 50, 300}) {
      const Pairs expected = brute_force(poses, d, gap);
      EXPECT_EQ(pairs_of(lsgd::eval::groundtruth_from_poses(poses, d, gap)), expected)
          << "d " << d << " gap " << gap;
      if (d == 3.0 && gap == 50) {
        EXPECT_GT(expected.size(), 1000u);
      }
    }
  }
}

TEST(GroundTruthFromPoses, BoundsAreStrict) {
  const std::vector<Pose> poses = {{0, 0, 0}, {5, 0, 0}, {0, 0, 2}, {0, 0, 0.5}};
  const auto gt = lsgd::eval::groundtruth_from_poses(poses, 2.0, 1);
  EXPECT_EQ(pairs_of(gt), (Pairs{{3, 0}}));  // (2, 0): distance 2 is not < 2; (3, 2): gap 1
  EXPECT_EQ(lsgd::eval::groundtruth_from_poses({}, 1.0, 0).frames(), 0);
  EXPECT_THROW(lsgd::eval::groundtruth_from_poses(poses, 0.0, 1), lsgd::InvalidArgument);
  EXPECT_THROW(lsgd::eval::groundtruth_from_poses(poses, std::nan(""), 1), lsgd::InvalidArgument);
  EXPECT_THROW(lsgd::eval::groundtruth_from_poses(poses, 1.0, -1), lsgd::InvalidArgument);
  EXPECT_THROW(lsgd::eval::groundtruth_from_poses({{1e300, 0, 0}}, 1.0, 0), lsgd::InvalidArgument);
}

// ---- loopinf -------------------------------------------------------------------------

TEST(ReadLoopinf, ReadsLoopsBothWays) {
  const fs::path p = write_file("li.txt", "0\t5\n1\t-1\n2\t-1\n3\t-1\n4\t-1\n5\t0\n6\t1\n7\t-1");
  const GroundTruth gt = lsgd::eval::read_loopinf(p.string());
  EXPECT_EQ(gt.frames(), 8);
  EXPECT_EQ(pairs_of(gt), (Pairs{{5, 0}, {6, 1}}));
  EXPECT_EQ(lsgd::eval::read_loopinf(p.string(), 8).pairs(), 2);
  const std::string e =
      message_of<lsgd::FormatError>([&] { lsgd::eval::read_loopinf(p.string(), 9); });
  EXPECT_TRUE(contains(e, p.string()) && contains(e, "8") && contains(e, "9")) << e;
}

TEST(ReadLoopinf, ErrorsNameFileAndLine) {
  const auto expect_line = [](const std::string& name, const std::string& text, int line) {
    const fs::path p = write_file(name, text);
    const std::string e =
        message_of<lsgd::FormatError>([&] { lsgd::eval::read_loopinf(p.string()); });
    EXPECT_TRUE(contains(e, p.string() + ":" + std::to_string(line))) << e;
  };
  expect_line("li-order.txt", "0\t-1\n2\t-1\n", 2);
  expect_line("li-range.txt", "0\t-1\n1\t-1\n2\t3\n", 3);
  expect_line("li-neg.txt", "0\t-2\n", 1);
  expect_line("li-word.txt", "0\t-1\n1\tx\n", 2);
  expect_line("li-three.txt", "0\t-1\t4\n", 1);
  EXPECT_THROW(lsgd::eval::read_loopinf((kTmp / "absent.txt").string()), lsgd::IoError);
}

// ---- detection, options, dispatch, statistics ------------------------------------------------

TEST(DetectGtFormat, TellsEachFormatByContent) {
  using lsgd::eval::detect_gt_format;
  EXPECT_EQ(detect_gt_format(write_file("d-pairs", "# c\n12 2\n13 3\n\n4 30\n").string()),
            std::string(lsgd::eval::kPairsGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-pairs-tab", "5\t1\n9\t2\n").string()), std::string(lsgd::eval::kPairsGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-li", "0\t-1\n1\t-1\n2\t0\n").string()),
            std::string(lsgd::eval::kLoopinfGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-li-space", "0 -1\n1 -1\n").string()),
            std::string(lsgd::eval::kLoopinfGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-li-tab", "0\t3\n1\t4\n2\t5\n").string()),
            std::string(lsgd::eval::kLoopinfGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-12", pose_line(1, 2, 3, false)).string()),
            std::string(lsgd::eval::kKittiPosesGtFormat));
  EXPECT_EQ(detect_gt_format(write_file("d-13", pose_line(1, 2, 3, true)).string()),
            std::string(lsgd::eval::kKittiPosesGtFormat));
  EXPECT_EQ(detect_gt_format(write_dense_u8("d.dat", Layout::kLower, true).string()),
            std::string(lsgd::eval::kMatGtFormat));  // by the header, whatever the name
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"d-three", "1 2 3\n"},
           {"d-empty", ""},
           {"d-comments", "# only\n\n"},
           {"d-mixed", "1 2\n1 2 3\n"},
           {"d-words", "a b\n"},
           {"d-neg", "3 -1\n4 -1\n"},  // -1 but not one line per frame
           {"d-binary", std::string("\x01\x00\x02\x03", 4)}}) {
    const fs::path p = write_file(name, text);
    const std::string e = message_of<lsgd::FormatError>([&] { detect_gt_format(p.string()); });
    EXPECT_TRUE(contains(e, p.string())) << name << ": " << e;
  }
  EXPECT_THROW(detect_gt_format((kTmp / "absent").string()), lsgd::IoError);
}

TEST(GtFormatNames, RoundTripAndRejectUnknown) {
  for (const char* f : {"auto", "pairs", "mat", "kitti-poses", "loopinf"}) {
    EXPECT_EQ(lsgd::eval::parse_gt_format(f), f);
  }
  const std::vector<std::string> names = lsgd::eval::gt_format_names();
  ASSERT_GE(names.size(), 5u);
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + 5),
            (std::vector<std::string>{"auto", "pairs", "mat", "kitti-poses", "loopinf"}));
  const std::string e =
      message_of<lsgd::InvalidArgument>([] { lsgd::eval::parse_gt_format("matlab"); });
  EXPECT_TRUE(contains(e, "'matlab'")) << e;
  EXPECT_TRUE(contains(e, "auto, pairs, mat, kitti-poses")) << e;
}

// docs/design.md's recipe from outside the library: a format of one's own
// ("ranges": "q first last" per line, q revisits every frame first..last),
// registered, detected by "auto" before the built-in formats, read by name.
GroundTruth read_ranges(const std::string& path, const lsgd::eval::GtOptions& options) {
  std::ifstream in(path);
  std::string tag;
  std::getline(in, tag);  // "# ranges"
  std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
  std::int64_t q = 0, first = 0, last = 0, frames = 0;
  while (in >> q >> first >> last) {
    for (std::int64_t m = first; m <= last; ++m) pairs.emplace_back(q, m);
    frames = std::max(frames, q + 1);
  }
  GroundTruth gt(options.frames >= 0 ? options.frames : frames);
  for (const auto& [a, b] : pairs) gt.add(a, b);
  return gt;
}
bool detect_ranges(const std::string& path) {
  std::ifstream in(path);
  std::string tag;
  return std::getline(in, tag) && tag == "# ranges";
}

TEST(GtFormatRegistry, AFormatRegisteredFromOutsideIsDetectedAndRead) {
  static const bool registered = [] {
    lsgd::eval::register_gt_format({"ranges", "'q first last' per line", read_ranges, detect_ranges});
    return true;
  }();
  ASSERT_TRUE(registered);
  // Three integers a line would fit no built-in format; "auto" asks "ranges" first.
  const fs::path p = write_file("ranges.txt", "# ranges\n9 2 4\n12 5 5\n");
  EXPECT_EQ(lsgd::eval::detect_gt_format(p.string()), "ranges");
  const GroundTruth gt = lsgd::eval::load_groundtruth(p.string());
  EXPECT_EQ(gt.frames(), 13);
  EXPECT_EQ(gt.pairs(), 4);
  EXPECT_TRUE(gt.is_loop(9, 3));
  lsgd::eval::GtOptions by_name;
  by_name.format = lsgd::eval::parse_gt_format("ranges");
  by_name.frames = 20;
  EXPECT_EQ(lsgd::eval::load_groundtruth(p.string(), by_name).frames(), 20);
  // A built-in file is still told apart as before.
  EXPECT_EQ(lsgd::eval::detect_gt_format(write_file("r-pairs", "5 1\n").string()), "pairs");
  const std::vector<std::string> names = lsgd::eval::gt_format_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "ranges"), names.end());
  EXPECT_TRUE(contains(message_of<lsgd::InvalidArgument>([] {
                         lsgd::eval::register_gt_format({"ranges", "again", read_ranges});
                       }),
                       "already registered"));
  EXPECT_TRUE(contains(message_of<lsgd::InvalidArgument>([] {
                         lsgd::eval::register_gt_format({"auto", "no", read_ranges});
                       }),
                       "'auto' is not a ground-truth format name"));
}

TEST(GtOptions, CheckNamesTheField) {
  lsgd::eval::GtOptions o;
  EXPECT_NO_THROW(o.check());
  o.frames = -2;
  EXPECT_TRUE(contains(message_of<lsgd::InvalidArgument>([&] { o.check(); }), "frames"));
  o = {};
  o.poses_distance = 0;
  EXPECT_TRUE(contains(message_of<lsgd::InvalidArgument>([&] { o.check(); }), "poses_distance"));
  o = {};
  o.poses_min_gap = -1;
  EXPECT_TRUE(contains(message_of<lsgd::InvalidArgument>([&] { o.check(); }), "poses_min_gap"));
}

TEST(LoadGroundtruth, DispatchesAndTakesFramesFromTheFile) {
  lsgd::eval::GtOptions o;
  const fs::path pairs = write_file("l-pairs.txt", "12 2\n3 13\n");
  GroundTruth gt = lsgd::eval::load_groundtruth(pairs.string(), o);
  EXPECT_EQ(gt.frames(), 14);  // max id + 1
  EXPECT_EQ(pairs_of(gt), (Pairs{{12, 2}, {13, 3}}));
  o.frames = 20;
  EXPECT_EQ(lsgd::eval::load_groundtruth(pairs.string(), o).frames(), 20);
  o.frames = 10;
  EXPECT_THROW(lsgd::eval::load_groundtruth(pairs.string(), o), lsgd::FormatError);

  std::string walk;
  for (int i = 0; i < 30; ++i) walk += pose_line(i < 15 ? i : 29 - i, 0, 0, true, i);
  const fs::path poses = write_file("l-poses.txt", walk);
  o = {};
  o.poses_distance = 0.5;
  o.poses_min_gap = 2;
  gt = lsgd::eval::load_groundtruth(poses.string(), o);
  EXPECT_EQ(pairs_of(gt), brute_force(lsgd::eval::read_kitti_poses(poses.string()), 0.5, 2));
  EXPECT_EQ(gt.pairs(), 14);  // i and 29 - i, i < 14 (14 and 15 are 1 frame apart)
  o.frames = 31;
  EXPECT_THROW(lsgd::eval::load_groundtruth(poses.string(), o), lsgd::FormatError);

  o = {};
  o.format = std::string(lsgd::eval::kLoopinfGtFormat);  // forced: the detector would say pairs
  const fs::path li = write_file("l-li.txt", "0\t2\n1\t3\n2\t0\n3\t1\n");
  EXPECT_EQ(pairs_of(lsgd::eval::load_groundtruth(li.string(), o)), (Pairs{{2, 0}, {3, 1}}));
  o.format = std::string(lsgd::eval::kMatGtFormat);
  EXPECT_THROW(lsgd::eval::load_groundtruth(li.string(), o), lsgd::FormatError);
  o = {};
  o.poses_distance = -1;
  EXPECT_THROW(lsgd::eval::load_groundtruth(li.string(), o), lsgd::InvalidArgument);
}

// A UTF-8 byte-order mark (Windows editors) at the start of a text ground
// truth is not part of its first number, in every text format.
TEST(LoadGroundtruth, AByteOrderMarkIsSkippedInEveryTextFormat) {
  const std::string bom = "\xEF\xBB\xBF";
  lsgd::eval::GtOptions o;
  const fs::path pairs = write_file("bom-pairs.txt", bom + "12 2\n13 3\n");
  EXPECT_EQ(lsgd::eval::detect_gt_format(pairs.string()), std::string(lsgd::eval::kPairsGtFormat));
  EXPECT_EQ(pairs_of(lsgd::eval::load_groundtruth(pairs.string(), o)), (Pairs{{12, 2}, {13, 3}}));
  EXPECT_EQ(pairs_of(lsgd::eval::read_pairs(pairs.string(), 20)), (Pairs{{12, 2}, {13, 3}}));
  const fs::path li = write_file("bom-li.txt", bom + "0\t2\n1\t3\n2\t0\n3\t1\n");
  o.format = std::string(lsgd::eval::kLoopinfGtFormat);
  EXPECT_EQ(pairs_of(lsgd::eval::load_groundtruth(li.string(), o)), (Pairs{{2, 0}, {3, 1}}));
  const fs::path poses = write_file("bom-poses.txt", bom + pose_line(1, 2, 3, false));
  const auto p = lsgd::eval::read_kitti_poses(poses.string());
  ASSERT_EQ(p.size(), 1u);
  EXPECT_DOUBLE_EQ(p[0].x, 1);
}

// A frame id or count from a file is bounded before memory is committed: a
// 12-byte file naming frame 199,999,999 is a FormatError naming the file and
// the id, not an allocation of gigabytes; a pipe is refused, not waited on.
TEST(LoadGroundtruth, HugeIdsAndSpecialFilesAreRefused) {
  lsgd::eval::GtOptions o;
  const fs::path huge = write_file("huge.txt", "199999999 0\n");
  const std::string m = message_of<lsgd::FormatError>(
      [&] { lsgd::eval::load_groundtruth(huge.string(), o); });
  EXPECT_NE(m.find(huge.string()), std::string::npos) << m;
  EXPECT_NE(m.find("199999999"), std::string::npos) << m;
  o.frames = lsgd::kMaxFrames + 1;
  EXPECT_THROW(lsgd::eval::load_groundtruth(huge.string(), o), lsgd::InvalidArgument);
  // Up to the limit a ground truth costs what its pairs cost, not its frames.
  const fs::path far = write_file("far.txt", "9999999 3\n");
  o = {};
  const GroundTruth gt = lsgd::eval::load_groundtruth(far.string(), o);
  EXPECT_EQ(gt.frames(), lsgd::kMaxFrames);
  EXPECT_EQ(gt.queries(), (std::vector<std::int64_t>{9999999}));
  EXPECT_EQ(lsgd::eval::gt_stats(gt, 0).frames_in_loops, 2);
  const fs::path fifo = fs::path(write_file("dummy", "")).parent_path() / "pipe.txt";
  fs::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(message_of<lsgd::IoError>([&] { lsgd::eval::load_groundtruth(fifo.string(), o); })
                .find("not a regular file"),
            std::string::npos);
}

TEST(GtStats, CountsPairsPositivesAndGaps) {
  GroundTruth gt(100);
  gt.add(60, 5);   // gap 55
  gt.add(60, 50);  // gap 10
  gt.add(90, 10);  // gap 80
  gt.add(91, 89);  // gap 2
  auto s = lsgd::eval::gt_stats(gt, 50);
  EXPECT_EQ(s.frames, 100);
  EXPECT_EQ(s.pairs, 4);
  EXPECT_EQ(s.positives, 3);
  EXPECT_EQ(s.frames_in_loops, 7);
  EXPECT_EQ(s.gap_min, 2);
  EXPECT_DOUBLE_EQ(s.gap_median, 32.5);
  EXPECT_EQ(s.gap_max, 80);
  EXPECT_EQ(s.min_gap, 50);
  EXPECT_EQ(s.window_pairs, 2);
  EXPECT_EQ(s.window_positives, 2);
  gt.add(99, 0);  // gap 99: odd count, median 55
  EXPECT_DOUBLE_EQ(lsgd::eval::gt_stats(gt).gap_median, 55.0);
  EXPECT_EQ(lsgd::eval::gt_stats(gt).window_positives, 4);
  const auto empty = lsgd::eval::gt_stats(GroundTruth(3), 10);
  EXPECT_EQ(empty.pairs + empty.positives + empty.gap_max + empty.frames_in_loops, 0);
  EXPECT_THROW(lsgd::eval::gt_stats(gt, -1), lsgd::InvalidArgument);
}

// ---- the real files of ../shared/groundtruth ---------------------------------------------------

// Reads a "*.pairs.txt" twin: "# source X.mat var=V dims=NxN; ..." then "row col" per nonzero.
Pairs read_twin(const fs::path& path, std::int64_t& frames) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  const auto dims = line.find("dims=");
  frames = dims == std::string::npos ? -1 : std::stoll(line.substr(dims + 5));
  Pairs out;
  std::int64_t r = 0, c = 0;
  while (in >> r >> c) out.emplace(std::max(r, c), std::min(r, c));
  return out;
}

std::vector<std::string> published_mats() {
  std::vector<std::string> files;
  const fs::path dir = kGt / "published";
  if (fs::exists(dir)) {
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      if (e.path().extension() == ".mat") files.push_back(e.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) files.push_back("");  // one test that skips with a message
  return files;
}

class PublishedMat : public ::testing::TestWithParam<std::string> {};

// Every published MAT file equals its pairs twin (pairs compared unordered:
// the twin lists (row, col) as stored, and two kn-zhang files are upper-triangular).
TEST_P(PublishedMat, EqualsItsPairsTwin) {
  if (GetParam().empty()) GTEST_SKIP() << "no published ground truth under " << kGt / "published";
  const fs::path mat = GetParam();
  fs::path twin = mat;
  twin.replace_extension(".pairs.txt");
  ASSERT_TRUE(fs::exists(twin)) << twin;
  std::int64_t frames = -1;
  const Pairs expected = read_twin(twin, frames);
  EXPECT_EQ(lsgd::eval::detect_gt_format(mat.string()), std::string(lsgd::eval::kMatGtFormat));
  EXPECT_EQ(lsgd::eval::detect_gt_format(twin.string()), std::string(lsgd::eval::kPairsGtFormat));
  const GroundTruth gt = lsgd::eval::read_mat(mat.string());
  EXPECT_EQ(gt.frames(), frames);
  EXPECT_EQ(gt.pairs(), static_cast<std::int64_t>(expected.size()));
  EXPECT_TRUE(pairs_of(gt) == expected) << mat;
  std::cout << mat.filename().string() << ": " << gt.frames() << " frames, " << gt.pairs()
            << " pairs\n";
}

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = fs::path(info.param).parent_path().filename().string() + "_" +
                     fs::path(info.param).stem().string();
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return info.param.empty() ? "absent" : name;
}

INSTANTIATE_TEST_SUITE_P(Shared, PublishedMat, ::testing::ValuesIn(published_mats()), test_name);

// Every loopinf file: detected, and each line's loop present; a loop frame
// beyond the sequence (loopinf-kitti-09.txt has two) must be named by line.
TEST(SharedLoopinf, EveryFileReadsOrNamesTheBadLine) {
  const fs::path dir = kGt / "lsgddn-loopinf";
  if (!fs::exists(dir)) GTEST_SKIP() << "LSGDDN loopinf files not found at " << dir;
  int files = 0, rejected = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string path = entry.path().string();
    std::vector<std::int64_t> loop;
    std::ifstream in(path);
    std::int64_t k = 0, j = 0;
    while (in >> k >> j) loop.push_back(j);
    const auto n = static_cast<std::int64_t>(loop.size());
    std::int64_t bad_line = 0;
    for (std::int64_t i = 0; i < n && !bad_line; ++i) bad_line = loop[i] >= n ? i + 1 : 0;
    EXPECT_EQ(lsgd::eval::detect_gt_format(path), std::string(lsgd::eval::kLoopinfGtFormat)) << path;
    ++files;
    if (bad_line) {
      ++rejected;
      const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_loopinf(path); });
      EXPECT_TRUE(contains(e, path + ":" + std::to_string(bad_line))) << e;
      std::cout << entry.path().filename().string() << ": rejected: " << e << "\n";
      continue;
    }
    const GroundTruth gt = lsgd::eval::read_loopinf(path);
    EXPECT_EQ(gt.frames(), n) << path;
    std::int64_t with_loop = 0;
    for (std::int64_t i = 0; i < n; ++i) {
      if (loop[i] < 0 || loop[i] == i) continue;
      ++with_loop;
      EXPECT_TRUE(gt.is_loop(i, loop[i])) << path << " frame " << i;
    }
    EXPECT_LE(gt.pairs(), with_loop) << path;
    EXPECT_GT(gt.pairs(), 0) << path;
  }
  EXPECT_GE(files, 5);
  EXPECT_LE(rejected, 1);
}

TEST(SharedKittiPoses, EveryFileReads) {
  const fs::path dir = kGt / "kitti-poses";
  if (!fs::exists(dir)) GTEST_SKIP() << "KITTI poses not found at " << dir;
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string path = entry.path().string();
    std::ifstream in(path);
    const auto lines = std::count(std::istreambuf_iterator<char>(in), {}, '\n');
    EXPECT_EQ(lsgd::eval::detect_gt_format(path), std::string(lsgd::eval::kKittiPosesGtFormat)) << path;
    EXPECT_EQ(static_cast<std::int64_t>(lsgd::eval::read_kitti_poses(path).size()), lines) << path;
    ++files;
  }
  EXPECT_EQ(files, 11);
  const fs::path p00 = dir / "00.txt";
  if (!fs::exists(p00)) return;
  // Line 2 of 00.txt: "0.1037359 <r00 r01 r02> -0.04690294 ... -0.02839928 ... 0.8586941".
  const auto poses = lsgd::eval::read_kitti_poses(p00.string());
  EXPECT_DOUBLE_EQ(poses[1].x, -0.04690294);
  EXPECT_DOUBLE_EQ(poses[1].y, -0.02839928);
  EXPECT_DOUBLE_EQ(poses[1].z, 0.8586941);
}

// ---- KITTI-00: loops derived from the poses vs the published matrices ------------------------

struct Overlap {
  double pair_recall = 0;      // published pairs that are derived pairs
  double pair_precision = 0;   // derived pairs that are published pairs
  double query_recall = 0;     // published positive queries that are derived positives
  double query_precision = 0;  // derived positive queries that are published positives
  double median_distance = 0;  // camera distance of the published pairs, metres
  double p95_distance = 0, max_distance = 0;
};

Overlap overlap(const Pairs& published, const Pairs& derived, const std::vector<Pose>& poses) {
  std::size_t common = 0;
  std::set<std::int64_t> qp, qd;
  std::vector<double> dist;
  for (const auto& [q, m] : published) {
    common += derived.count({q, m});
    qp.insert(q);
    const Pose &a = poses[static_cast<std::size_t>(q)], &b = poses[static_cast<std::size_t>(m)];
    dist.push_back(std::hypot(a.x - b.x, a.y - b.y, a.z - b.z));
  }
  for (const auto& pair : derived) qd.insert(pair.first);
  std::size_t qcommon = 0;
  for (std::int64_t q : qp) qcommon += qd.count(q);
  std::sort(dist.begin(), dist.end());
  return {static_cast<double>(common) / published.size(),
          static_cast<double>(common) / derived.size(),
          static_cast<double>(qcommon) / qp.size(),
          static_cast<double>(qcommon) / qd.size(),
          dist[dist.size() / 2],
          dist[dist.size() * 95 / 100],
          dist.back()};
}

TEST(Kitti00, PosesAgreeWithThePublishedMatrices) {
  const fs::path poses_file = kGt / "kitti-poses" / "00.txt";
  const std::vector<fs::path> published = {kGt / "published/kn-zhang/groundTruth_KITTI00.mat",
                                           kGt / "published/tsintotas-botw/groundTruthKITTI00.mat"};
  for (const auto& p : std::vector<fs::path>{poses_file, published[0], published[1]}) {
    if (!fs::exists(p)) GTEST_SKIP() << p << " not found (../shared is absent)";
  }
  const auto poses = lsgd::eval::read_kitti_poses(poses_file.string());
  const auto start = std::chrono::steady_clock::now();
  const GroundTruth derived_gt = lsgd::eval::groundtruth_from_poses(poses, 10.0, 100);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::cout << "KITTI-00 from poses (d = 10 m, gap = 100): " << derived_gt.pairs() << " pairs, "
            << lsgd::eval::gt_stats(derived_gt).positives << " positive queries, " << ms << " ms\n";
  EXPECT_EQ(derived_gt.pairs(), 29698);  // the figure of ../shared/docs/evaluation.md
  EXPECT_LT(ms, 1000.0);
  const Pairs derived = pairs_of(derived_gt);

  // Controls: poses 5 frames late change the count; 50 frames late must fail
  // the overlap thresholds below.
  const auto late_by = [&](std::size_t s) {
    std::vector<Pose> late(poses.begin() + static_cast<std::ptrdiff_t>(s), poses.end());
    late.resize(poses.size(), poses.back());
    return pairs_of(lsgd::eval::groundtruth_from_poses(late, 10.0, 100));
  };
  const std::size_t late5 = late_by(5).size();
  std::cout << "control: poses 5 frames late give " << late5 << " pairs\n";
  EXPECT_NE(late5, 29698u);
  const Pairs shifted = late_by(50);

  const double min_pair_recall[] = {0.62, 0.58}, min_query_recall[] = {0.95, 0.90};
  for (std::size_t k = 0; k < published.size(); ++k) {
    const GroundTruth pub = lsgd::eval::read_mat(published[k].string(), 4541);
    const Overlap o = overlap(pairs_of(pub), derived, poses);
    const Overlap c = overlap(pairs_of(pub), shifted, poses);
    std::cout << published[k].parent_path().filename().string() << "/"
              << published[k].filename().string() << ": " << pub.pairs()
              << " pairs, camera distance of its pairs: median " << o.median_distance << " m, p95 "
              << o.p95_distance << " m, max " << o.max_distance << " m; pairs: recall "
              << o.pair_recall << " precision " << o.pair_precision << "; positive queries: recall "
              << o.query_recall << " precision " << o.query_precision
              << " | control (poses 50 frames late): pair recall " << c.pair_recall << " precision "
              << c.pair_precision << "\n";
    EXPECT_GE(o.pair_recall, min_pair_recall[k]);
    EXPECT_GE(o.pair_precision, 0.68);
    EXPECT_GE(o.query_recall, min_query_recall[k]);
    EXPECT_GE(o.query_precision, 0.82);
    EXPECT_GT(o.median_distance, 4.0);
    EXPECT_LT(o.median_distance, 10.0);
    EXPECT_TRUE(c.pair_recall < min_pair_recall[k] && c.pair_precision < 0.68)
        << "the control passed: the thresholds cannot catch misaligned poses";
    // For docs/evaluation.md: how the agreement moves with the distance d.
    for (double d : {5.0, 7.5, 10.0, 12.5, 15.0, 20.0}) {
      const Pairs at_d = pairs_of(lsgd::eval::groundtruth_from_poses(poses, d, 100));
      const Overlap od = overlap(pairs_of(pub), at_d, poses);
      std::cout << "  d = " << d << " m: " << at_d.size() << " pairs; pair recall "
                << od.pair_recall << " precision " << od.pair_precision << "; query recall "
                << od.query_recall << " precision " << od.query_precision << "\n";
    }
  }
}

}  // namespace
