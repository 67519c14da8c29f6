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

// A little-endian v5 file by hand: a cell of `cells` elements (one stored)
// named "c", then a 4x4 double "GT" with GT(3, 0) = 1. matio's
// Mat_VarReadNextInfo callocs `cells` pointers for the cell before reading
// it: a CI run found 0x30000004 (6 GB) this way; read_mat() now lists v5
// variables itself.
std::string v5_with_cell(std::uint32_t cells) {
  auto word = [](std::uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  auto element = [&](std::uint32_t type, const std::string& bytes) {
    return word(type) + word(static_cast<std::uint32_t>(bytes.size())) + bytes +
           std::string((8 - bytes.size() % 8) % 8, '\0');
  };
  auto matrix = [&](std::uint32_t cls, std::uint32_t rows, std::uint32_t cols,
                    const std::string& name, const std::string& data) {
    const std::string body = element(6, word(cls) + word(0)) + element(5, word(rows) + word(cols)) +
                             element(1, name) + data;
    return word(14) + word(static_cast<std::uint32_t>(body.size())) + body;
  };
  std::string header = "MATLAB 5.0 MAT-file";
  header.resize(116, ' ');
  header += std::string(8, '\0') + std::string("\x00\x01IM", 4);
  std::vector<double> gt(16, 0.0);
  gt[3] = 1;
  const std::string values(reinterpret_cast<const char*>(gt.data()), gt.size() * 8);
  return header + matrix(1, cells, 1, "c", matrix(6, 0, 0, "", "")) +
         matrix(6, 4, 4, "GT", element(9, values));
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
  const std::string mat4(1, static_cast<char>(4 << 1 | 1));
  put(out / "gt" / "v5cell.mat", mat4 + v5_with_cell(1));
  put(out / "gt" / "v5cell-claims-6GB.mat", mat4 + v5_with_cell(0x30000004));
  return 0;
}
