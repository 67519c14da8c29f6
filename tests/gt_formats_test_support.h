// Helpers of the tests of the ground-truth readers (gt_formats_test,
// gt_formats_mat_v5_test, gt_formats_poses_test, gt_formats_dispatch_test,
// gt_formats_shared_test): a scratch folder and files in it, pairs of a ground
// truth, MAT files written with matio, KITTI pose lines and the brute-force
// loops of poses. Header-only.
#pragma once

#include <gtest/gtest.h>
#include <matio.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "lsgd/eval/gt_formats.h"
#include "test_util.h"

namespace gt_formats_test_support {

namespace fs = std::filesystem;
using lsgd::eval::GroundTruth;
using lsgd::eval::Pose;

inline const fs::path kTmp =
    lsgd::test::removed_at_exit(fs::path(LSGD_TEST_TMP) / ("gtf-" + std::to_string(getpid())));

using Pairs = std::set<std::pair<std::int64_t, std::int64_t>>;  // (q, m), q > m

inline fs::path write_file(const std::string& name, const std::string& text) {
  fs::create_directories(kTmp);
  const fs::path path = kTmp / name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

inline Pairs pairs_of(const GroundTruth& gt) {
  Pairs out;
  for (std::int64_t q = 0; q < gt.frames(); ++q) {
    for (std::int64_t m : gt.matches(q)) out.emplace(q, m);
  }
  return out;
}

inline bool contains(const std::string& text, const std::string& part) {
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
inline bool write_mat(const fs::path& path, const std::vector<MatVarSpec>& vars,
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
inline const std::size_t kN = 40;
inline const Pairs kPairs = {{12, 2}, {13, 3}, {30, 10}, {31, 10}, {39, 0}, {25, 24}};

inline fs::path write_dense_u8(const std::string& name, Layout layout, bool logical,
                               matio_compression z = MAT_COMPRESSION_ZLIB) {
  auto m = dense<std::uint8_t>(kN, kPairs, layout);
  const fs::path p = kTmp / name;
  EXPECT_TRUE(write_mat(
      p, {{"GT", MAT_C_UINT8, MAT_T_UINT8, kN, kN, m.data(), logical ? MAT_F_LOGICAL : 0}},
      MAT_FT_MAT5, z));
  return p;
}

// ---- KITTI poses

inline std::string pose_line(double x, double y, double z, bool timestamp, double t = 0) {
  std::ostringstream s;
  s.precision(17);
  if (timestamp) s << t << ' ';
  s << "1 0 0 " << x << " 0 1 0 " << y << " 0 0 1 " << z << '\n';
  return s.str();
}

// Brute force, the definition: i - j > gap and |c_i - c_j| < d.
inline Pairs brute_force(const std::vector<Pose>& poses, double d, std::int64_t gap) {
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

}  // namespace gt_formats_test_support
