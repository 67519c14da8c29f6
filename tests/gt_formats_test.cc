// Tests of the ground-truth readers, format detection, KITTI poses -> loops and
// statistics (eval/gt_formats.h): generated files of every format (MAT files
// written here with matio), broken files, and the real files of
// ../shared/groundtruth when present (skipped with a message otherwise).
// This file: MAT files written with matio, broken MAT files. MAT v5 files
// built byte by byte: gt_formats_mat_v5_test.cc; KITTI poses and loopinf:
// gt_formats_poses_test.cc; detection, options, dispatch and statistics:
// gt_formats_dispatch_test.cc; ../shared/groundtruth: gt_formats_shared_test.cc.
#include "lsgd/eval/gt_formats.h"

#include <gtest/gtest.h>
#include <matio.h>
#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
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

using gt_formats_test_support::contains;
using gt_formats_test_support::dense;
using gt_formats_test_support::kN;
using gt_formats_test_support::kPairs;
using gt_formats_test_support::kTmp;
using gt_formats_test_support::Layout;
using gt_formats_test_support::MatVarSpec;
using gt_formats_test_support::Pairs;
using gt_formats_test_support::pairs_of;
using gt_formats_test_support::write_dense_u8;
using gt_formats_test_support::write_file;
using gt_formats_test_support::write_mat;

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
  auto f = dense<float>(kN, kPairs, Layout::kUpper, 1.0f);
  auto i8 = dense<std::int8_t>(kN, kPairs, Layout::kLower, 1);
  auto u16 = dense<std::uint16_t>(kN, kPairs, Layout::kFull, 1);
  auto i32 = dense<std::int32_t>(kN, kPairs, Layout::kLower, 1);
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

// A loop matrix holds 0 or 1. A matrix of distances, scores, counts or soft
// labels (-1, 0.5, 7) was read as loops wherever it was nonzero: refused,
// naming the entry and its value, in every class, compressed or not, dense
// (the 1-byte fast path too) or sparse.
TEST(ReadMat, EntriesOtherThanZeroOrOneAreRefused) {
  const std::size_t at = 3 * kN + 20;  // GT(21, 4), 1-based
  auto f = dense<float>(kN, kPairs, Layout::kLower);
  f[at] = 0.5f;
  auto i8 = dense<std::int8_t>(kN, kPairs, Layout::kLower);
  i8[at] = -1;
  auto u8 = dense<std::uint8_t>(kN, kPairs, Layout::kLower);
  u8[at] = 255;
  auto u16 = dense<std::uint16_t>(kN, kPairs, Layout::kLower);
  u16[at] = 7;
  auto d = dense<double>(kN, kPairs, Layout::kLower);
  d[at] = 2.0;
  struct Case {
    MatVarSpec spec;
    const char* value;
  };
  const std::vector<Case> cases = {
      {{"GT", MAT_C_SINGLE, MAT_T_SINGLE, kN, kN, f.data()}, "is 0.5"},
      {{"GT", MAT_C_INT8, MAT_T_INT8, kN, kN, i8.data()}, "is -1"},
      {{"GT", MAT_C_UINT8, MAT_T_UINT8, kN, kN, u8.data()}, "is 255"},
      {{"GT", MAT_C_UINT16, MAT_T_UINT16, kN, kN, u16.data()}, "is 7"},
      {{"GT", MAT_C_DOUBLE, MAT_T_DOUBLE, kN, kN, d.data()}, "is 2"},
  };
  const fs::path p = kTmp / "values.mat";
  for (auto z : {MAT_COMPRESSION_NONE, MAT_COMPRESSION_ZLIB}) {
    for (const Case& c : cases) {
      SCOPED_TRACE(std::string(c.value) + (z == MAT_COMPRESSION_ZLIB ? " compressed" : ""));
      ASSERT_TRUE(write_mat(p, {c.spec}, MAT_FT_MAT5, z));
      const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
      EXPECT_TRUE(contains(e, p.string()) && contains(e, "(21, 4)") && contains(e, c.value) &&
                  contains(e, "0 (no loop) or 1 (a loop)"))
          << e;
    }
  }
  // Sparse: the stored values are checked as the dense ones.
  std::vector<mat_uint32_t> ir = {5}, jc(kN + 1, 1);
  jc[0] = 0;
  std::vector<double> values = {-1.0};
  mat_sparse_t sparse{};
  sparse.nzmax = sparse.nir = sparse.ndata = 1;
  sparse.ir = ir.data();
  sparse.jc = jc.data();
  sparse.njc = static_cast<mat_uint32_t>(jc.size());
  sparse.data = values.data();
  ASSERT_TRUE(write_mat(p, {{"GT", MAT_C_SPARSE, MAT_T_DOUBLE, kN, kN, &sparse}}));
  const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
  EXPECT_TRUE(contains(e, "(6, 1)") && contains(e, "is -1")) << e;
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

// CI's fuzz_gt run of 2026-12-05: a file without a v5 header whose first v4
// header (big-endian, int16 sparse) claims 805,974,304 x 807,415,840 values in
// 202 bytes; matio's Mat_Open filled 1.9 GB for it. Every v4 header must fit
// the file before matio opens it, in both byte orders.
TEST(ReadMat, V4ValuesBeyondTheFileAreFormatErrorBeforeMatioOpens) {
  std::string bytes("\x00\x00\x00\x20" "0\n1 0 0 0\x00\x00\x00\x00\x00\x00\x63", 20);
  bytes += std::string(182, 'x');
  const fs::path p = write_file("v4values.mat", bytes);
  const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
  EXPECT_TRUE(contains(e, p.string()) && contains(e, "corrupt MAT v4 header at byte 0")) << e;
  // The same claim little-endian (type 32 read as is), and a second variable
  // that does not fit after a first one that does.
  std::string little("\x20\x00\x00\x00" "\x20\x31\x0a\x30" "\x20\x30\x20\x30" "\x00\x00\x00\x00"
                     "\x02\x00\x00\x00", 20);
  little += std::string(182, 'x');
  const fs::path q = write_file("v4values_le.mat", little);
  EXPECT_TRUE(contains(message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(q.string()); }),
                       q.string()));
  std::string two("\x00\x00\x00\x00" "\x01\x00\x00\x00" "\x01\x00\x00\x00" "\x00\x00\x00\x00"
                  "\x02\x00\x00\x00", 20);
  two += std::string("g\0", 2) + std::string(8, '\0');            // gt = [0], 1 x 1 double
  two += std::string("\x00\x00\x00\x00" "\xff\xff\x00\x00" "\xff\xff\x00\x00" "\x00\x00\x00\x00"
                     "\x02\x00\x00\x00", 20);                   // 65535 x 65535 doubles
  two += std::string("h\0", 2) + std::string(64, '\0');
  const fs::path r = write_file("v4second.mat", two);
  const std::string e2 = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(r.string()); });
  EXPECT_TRUE(contains(e2, r.string()) && contains(e2, "byte 30")) << e2;
}

// The fuzzer's next find: a v5-looking header ("IM" at byte 126) whose version
// is not 0x0100 / 0x0200 is read by matio as MAT v4 (a 755 MB malloc); the v4
// headers are checked whatever the endian mark says.
TEST(ReadMat, V5MarkWithAnotherVersionIsCheckedAsV4) {
  std::string bytes("\x00\x00\x00\x00" "\x01\x00\x00\x00" "\x01\x00\x00\x00" "\x00\x00\x00\x00"
                    "\xff\xff\xff\x7f", 20);  // name length 2^31 - 1
  bytes += std::string(104, ' ');
  bytes += std::string("\x08\x01IM", 4);  // version 0x0108, little-endian mark
  bytes += std::string(64, '\0');
  const fs::path p = write_file("v5mark_v4.mat", bytes);
  const std::string e = message_of<lsgd::FormatError>([&] { lsgd::eval::read_mat(p.string()); });
  EXPECT_TRUE(contains(e, p.string()) && contains(e, "name length 2147483647")) << e;
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

}  // namespace
