// Writes the seed corpora of the fuzz targets: make_seeds <out-dir> creates
// <out-dir>/{config,pairs,gt}/ with small valid and near-valid inputs. MAT
// seeds (v5 compressed and uncompressed, v4; dense logical, double, sparse) are
// written with matio, so no binary file lives in the repository.
#include <matio.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "lsgd/detector.h"
#include "lsgd/io/config.h"
#include "lsgd/io/database.h"

namespace fs = std::filesystem;

namespace {

void put(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
  if (!out) {
    std::fprintf(stderr, "make_seeds: cannot write %s\n", path.c_str());
    std::exit(1);
  }
}

// A small valid place database (64x48 frames, the given verification) as bytes.
std::string db_bytes(const fs::path& scratch, const char* stages, int frames) {
  fs::remove(scratch);
  fs::remove(scratch.string() + "-wal");
  fs::remove(scratch.string() + "-shm");
  lsgd::DetectorOptions options;
  options.segmentation.superpixel_size = 8;
  options.search.min_gap = 1;
  lsgd::parse_verification_stages(stages, options.verification);
  {
    lsgd::io::Database db = lsgd::io::Database::create(scratch.string(), options);
    lsgd::Detector detector(options);
    for (int i = 0; i < frames; ++i) {
      cv::Mat frame(48, 64, CV_8UC1);
      cv::randu(frame, 0, 255);
      frame.at<unsigned char>(0, 0) = static_cast<unsigned char>(i % 2);
      const lsgd::Result r = detector.process(frame);
      db.append(detector, r, 0, "frame" + std::to_string(i));
    }
  }  // closed: the WAL is checkpointed into the file
  std::ifstream in(scratch, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A 6 x 6 loop matrix (pairs {4,0}, {5,1}) as a MAT file read back as bytes;
// empty when this matio cannot write the version.
std::string mat_bytes(const fs::path& scratch, mat_ft version, matio_compression z,
                      bool sparse) {
  constexpr std::size_t kN = 6;
  std::vector<double> dense(kN * kN, 0.0);
  dense[0 * kN + 4] = 1;  // column-major (row 4, column 0)
  dense[1 * kN + 5] = 1;
  std::vector<mat_uint32_t> ir = {4, 5}, jc = {0, 1, 2, 2, 2, 2, 2};
  std::vector<double> values = {1, 1};
  mat_sparse_t sp{};
  sp.nzmax = sp.nir = sp.ndata = 2;
  sp.ir = ir.data();
  sp.jc = jc.data();
  sp.njc = static_cast<mat_uint32_t>(jc.size());
  sp.data = values.data();
  fs::remove(scratch);
  mat_t* mat = Mat_CreateVer(scratch.c_str(), nullptr, version);
  if (!mat) return {};
  std::size_t dims[2] = {kN, kN};
  matvar_t* var = sparse ? Mat_VarCreate("gt", MAT_C_SPARSE, MAT_T_DOUBLE, 2, dims, &sp, 0)
                         : Mat_VarCreate("GT", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, dense.data(), 0);
  const bool ok = var && Mat_VarWrite(mat, var, z) == 0;
  if (var) Mat_VarFree(var);
  Mat_Close(mat);
  if (!ok) return {};
  std::ifstream in(scratch, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_seeds <out-dir>\n");
    return 2;
  }
  const fs::path out = argv[1];
  for (const char* d : {"config", "pairs", "gt", "db", "description"}) fs::create_directories(out / d);
  // description: frames described under fuzz_description's options (and one compact, refused).
  for (const char* storage : {"exact", "compact"}) {
    lsgd::DetectorOptions options;
    options.segmentation.superpixel_size = 8;
    options.search.min_gap = 1;
    options.descriptor.storage = lsgd::parse_histogram_storage(storage);
    lsgd::Detector detector(options);
    for (int i = 0; i < (storage[0] == 'e' ? 2 : 1); ++i) {
      cv::Mat frame(48, 64, CV_8UC1);
      cv::randu(frame, 0, 255);
      const std::vector<std::uint8_t> bytes = lsgd::encode_frame_description(detector.describe_frame(frame));
      put(out / "description" / (std::string(storage) + std::to_string(i)),
          std::string(bytes.begin(), bytes.end()));
    }
  }
  put(out / "db" / "temporal", db_bytes(out / "scratch.db", "temporal", 4));
  put(out / "db" / "none", db_bytes(out / "scratch.db", "none", 2));
  put(out / "db" / "geometric", db_bytes(out / "scratch.db", "temporal,geometric", 3));

  // config: the defaults as written by to_yaml, and a flow-style partial file.
  put(out / "config" / "defaults.yaml", lsgd::io::to_yaml(lsgd::DetectorOptions{}));
  put(out / "config" / "paper.yaml",
      "segmentation:\n  superpixel_size: 40\n  iterations: 10\n  intensity_scale: 2.3\n"
      "similarity:\n  metric: reference\nsearch:\n  min_gap: 50\n"
      "  nodes: {threshold_0: 0.9, alpha: 0.8, beta: 1.0}\nverification:\n  stages: none\n"
      "decision: {threshold: 7.0, geometric_bonus: 3.5, continuity_bonus: 2.5}\n");
  put(out / "config" / "bad.yaml", "search: {min_gap: -3}\nunknown_key: 1\n");

  // pairs: first byte = expected frames (255: -1).
  put(out / "pairs" / "ok", std::string(1, '\x0a') + "# q m\n5 1\n9 2\n\n7 0\n");
  put(out / "pairs" / "auto", std::string(1, '\xff') + "3 0\n4 1\n");
  put(out / "pairs" / "bad", std::string(1, '\x04') + "1 2 3\n9 1\n");

  // gt: first byte = frames << 1 | (1: name *.mat).
  auto txt = [](int frames) { return std::string(1, static_cast<char>(frames << 1)); };
  const std::string mat_auto(1, static_cast<char>(6 << 1 | 1));
  put(out / "gt" / "pairs", txt(6) + "# loops\n4 0\n5 1\n");
  put(out / "gt" / "loopinf", txt(4) + "0\t-1\n1\t-1\n2\t0\n3\t1\n");
  std::string poses;
  for (int i = 0; i < 4; ++i)
    poses += "1 0 0 " + std::to_string(i % 2) + " 0 1 0 0 0 0 1 0\n";
  put(out / "gt" / "kitti", txt(4) + poses);
  put(out / "gt" / "kitti13", txt(1) + "0.0 1 0 0 0 0 1 0 0 0 0 1 0\n");
  const fs::path scratch = out / "scratch.mat";
  struct MatSeed {
    const char* name;
    mat_ft version;
    matio_compression z;
    bool sparse;
  };
  for (const MatSeed& s : {MatSeed{"v5z.mat", MAT_FT_MAT5, MAT_COMPRESSION_ZLIB, false},
                           MatSeed{"v5.mat", MAT_FT_MAT5, MAT_COMPRESSION_NONE, false},
                           MatSeed{"v5sparse.mat", MAT_FT_MAT5, MAT_COMPRESSION_ZLIB, true},
                           MatSeed{"v4.mat", MAT_FT_MAT4, MAT_COMPRESSION_NONE, false},
                           MatSeed{"v4sparse.mat", MAT_FT_MAT4, MAT_COMPRESSION_NONE, true}}) {
    const std::string bytes = mat_bytes(scratch, s.version, s.z, s.sparse);
    if (!bytes.empty()) put(out / "gt" / s.name, mat_auto + bytes);
  }
  fs::remove(scratch);
  return 0;
}
