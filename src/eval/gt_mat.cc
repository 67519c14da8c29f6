// MATLAB loop matrices (read_mat, lsgd/eval/gt_formats.h): matio, and a
// streaming reader of v5 variables for the published files.
#include "lsgd/eval/gt_formats.h"

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

#include "eval/mat_internal.h"

namespace lsgd::eval {

using internal::concat;
using namespace mat;  // mat_internal.h

namespace {

// ---- MAT files (matio) ------------------------------------------------------

// matio reports problems through a log callback (by default printed to
// stderr). We install one that keeps the last error of this thread instead, so
// a failed read becomes a FormatError quoting it; warnings are dropped.
thread_local std::string matio_last_message;

void matio_log(int level, char* message) {
  if (level & (MATIO_LOG_LEVEL_ERROR | MATIO_LOG_LEVEL_CRITICAL)) {
    matio_last_message = message ? message : "";
  }
}

std::string matio_detail() {
  return matio_last_message.empty() ? "" : concat(" (matio: ", matio_last_message, ")");
}

struct MatCloser {
  void operator()(mat_t* mat) const { Mat_Close(mat); }
};
struct VarFreer {
  void operator()(matvar_t* var) const { Mat_VarFree(var); }
};
using MatFile = std::unique_ptr<mat_t, MatCloser>;
using MatVar = std::unique_ptr<matvar_t, VarFreer>;

// `c` as a file holds it: any byte, not only a matio_classes value.
bool is_matrix_class(int c) {
  return c == MAT_C_SPARSE || (c >= MAT_C_DOUBLE && c <= MAT_C_UINT64);
}

// A variable as read_mat() sees it: matio's description (v4, v7.3) or lsgd's
// (v5, mat_v5.cc), with a v4 sparse matrix's size from its last row (matio
// describes it by its stored triplets, nonzeros + 1 rows by 3 columns).
struct Variable {
  std::string name;
  std::string text;      // name, size, class: for messages
  bool square = false;   // a square 2-D real numeric, logical or sparse matrix
  std::size_t n = 0;     // its size when square
  int cls = 0;           // matio_classes
  const V4Variable* v4_sparse = nullptr;
};

Variable make_variable(const char* name, const std::vector<std::uint64_t>& dims, int cls,
                       bool logical, bool complex) {
  Variable out;
  out.name = name ? name : "";
  std::string shape;
  for (std::size_t i = 0; i < dims.size(); ++i) shape += (i ? "x" : "") + std::to_string(dims[i]);
  out.text = concat(name ? name : "?", " ", shape, " class ", cls, logical ? " logical" : "",
                    complex ? " complex" : "");
  out.square = dims.size() == 2 && dims[0] == dims[1] &&
               is_matrix_class(cls) && !complex;
  out.n = dims.size() == 2 ? static_cast<std::size_t>(dims[0]) : 0;
  out.cls = cls;
  return out;
}

Variable describe(const matvar_t& v, const Container& c, const std::string& path) {
  std::vector<std::uint64_t> dims;
  for (int i = 0; i < v.rank && v.dims; ++i) dims.push_back(v.dims[i]);
  bool complex = v.isComplex != 0;
  const V4Variable* v4_sparse = nullptr;
  if (v.class_type == MAT_C_SPARSE && v.name && !c.v4.empty()) {
    v4_sparse = find_v4(c, v.name);
    if (v4_sparse) {
      const V4Shape shape = v4_sparse_shape(path, *v4_sparse);
      dims = {shape.rows, shape.cols};
      complex = shape.complex;
    }
  }
  Variable out = make_variable(v.name, dims, v.class_type, v.isLogical != 0, complex);
  out.v4_sparse = v4_sparse;
  return out;
}

Variable describe(const V5Header& h) {
  return make_variable(h.name.c_str(), {h.dims.begin(), h.dims.end()},
                       static_cast<int>(h.flags & 0xFF), (h.flags & kClassFlagsLogical) != 0,
                       (h.flags & kClassFlagsComplex) != 0);
}

// Every variable of the file, in order: from lsgd's own header reader for v5
// (matio's would allocate what a cell or struct claims), from matio for the
// others (v4's headers are checked before Mat_Open).
std::vector<Variable> list_variables(mat_t* mat, mat_ft version, const Container& c,
                                     const std::string& path) {
  std::vector<Variable> out;
  if (version == MAT_FT_MAT5) {
    for (const V5Header& h : matrix_headers(path, c)) out.push_back(describe(h));
    return out;
  }
  while (MatVar info{Mat_VarReadNextInfo(mat)}) out.push_back(describe(*info, c, path));
  return out;
}

bool looks_like_gt_name(const std::string& name) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return lower.find("gt") != std::string::npos || lower.find("truth") != std::string::npos;
}

// The variable read_mat() reads (see the header for the rule).
Variable choose_variable(const std::vector<Variable>& vars, const std::string& path) {
  const Variable *first = nullptr, *named = nullptr;
  std::string seen;
  for (const Variable& var : vars) {
    seen += (seen.empty() ? "" : ", ") + var.text;
    if (!var.square || var.name.empty()) continue;
    if (!first) first = &var;
    if (!named && looks_like_gt_name(var.name)) named = &var;
  }
  if (vars.empty()) {
    throw FormatError(concat("'", path, "' holds no readable MAT variable (truncated or corrupt?)",
                             matio_detail()));
  }
  if (!first) {
    throw FormatError(concat("'", path, "' has no square 2-D real numeric, logical or sparse ",
                             "matrix (variables: ", seen, ")"));
  }
  return named ? *named : *first;
}

// Sparse (compressed column): rows ir[jc[c] .. jc[c+1]) of column c, with
// values (absent for an all-true logical matrix written without data).
template <typename T>
void add_sparse(const matvar_t& v, std::size_t n, GroundTruth& gt, const std::string& path) {
  const auto* s = static_cast<const mat_sparse_t*>(v.data);
  const auto corrupt = [&](const char* why) {
    return FormatError(concat("'", path, "': sparse matrix '", v.name, "' is corrupt: ", why));
  };
  if (!s || !s->jc || s->njc != n + 1) throw corrupt("column index has the wrong length");
  const T* values = static_cast<const T*>(s->data);
  for (std::size_t c = 0; c < n; ++c) {
    const std::size_t begin = s->jc[c], end = s->jc[c + 1];
    if (begin > end || end > s->nir || (end > 0 && !s->ir)) throw corrupt("bad column pointers");
    for (std::size_t k = begin; k < end; ++k) {
      const std::size_t r = s->ir[k];
      if (r >= n) throw corrupt("row index out of range");
      if (values && k < s->ndata && !is_loop_value(values[k], r, c, path)) continue;
      gt.add(static_cast<std::int64_t>(r), static_cast<std::int64_t>(c));
    }
  }
}

void add_matrix(const matvar_t& v, std::size_t n, GroundTruth& gt, const std::string& path) {
  const bool sparse = v.class_type == MAT_C_SPARSE;
  if (!sparse && (!v.data || v.nbytes < n * n * Mat_SizeOf(v.data_type))) {
    throw FormatError(concat("'", path, "': variable '", v.name, "' holds fewer values than its ",
                             n, "x", n, " size (truncated?)", matio_detail()));
  }
  const bool known = with_value_type(v.data_type, [&](auto t) {
    using T = decltype(t);
    if (sparse) return add_sparse<T>(v, n, gt, path);
    add_nonzero(static_cast<const T*>(v.data), n * n, 0, n, gt, path);
  });
  if (!known) {
    throw FormatError(concat("'", path, "': variable '", v.name, "' has unsupported data type ",
                             static_cast<int>(v.data_type)));
  }
}

// matio 1.5.23 reads a file as v5 / v7.3 only when its 128-byte header has
// the endian mark ("IM" or "MI" at byte 126) and, in that byte order, version
// 0x0100 or 0x0200 at byte 124; anything else it takes for MAT v4 and, inside
// Mat_Open, mallocs and fills what the first v4 header claims (a 2 GB name,
// 755 MB behind a v5 header with version 0x0108, 1.9 GB of a bogus sparse
// matrix: all found by fuzz/fuzz_gt). So a file matio will read as v4 must
// have every v4 header fit in it first (check_container's v4 walk).
bool matio_reads_as_v4(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::array<unsigned char, 128> head{};
  in.read(reinterpret_cast<char*>(head.data()), head.size());
  if (static_cast<std::size_t>(in.gcount()) != head.size()) return true;
  const bool little = head[126] == 'I' && head[127] == 'M';
  const bool big = head[126] == 'M' && head[127] == 'I';
  if (!little && !big) return true;
  const unsigned version = little ? head[124] | (head[125] << 8) : (head[124] << 8) | head[125];
  return version != 0x0100 && version != 0x0200;
}

void check_v4_before_matio(const std::string& path) {
  if (!matio_reads_as_v4(path)) return;  // v5 / v7.3: checked after Mat_Open (check_container, HDF5)
  std::error_code ec;
  if (std::filesystem::file_size(path, ec) < 20 && !ec) return;  // matio refuses a header this short
  check_container(path, MAT_FT_MAT4);
}

}  // namespace

GroundTruth read_mat(const std::string& path, std::int64_t frames, const std::string& variable) {
  static std::once_flag log_once;
  std::call_once(log_once, [] { Mat_LogInitFunc("lsgd", matio_log); });
  io::check_input_file(path, "MAT file");
  if (!std::ifstream(path)) throw IoError(concat("cannot open MAT file '", path, "'"));
  check_v4_before_matio(path);
  matio_last_message.clear();
  MatFile mat{Mat_Open(path.c_str(), MAT_ACC_RDONLY)};
  if (!mat) {
    throw FormatError(concat("'", path, "' is not a readable MAT file", matio_detail()));
  }
  const mat_ft version = Mat_GetVersion(mat.get());
  const Container container = check_container(path, version);
  const std::vector<Variable> vars = list_variables(mat.get(), version, container, path);
  Variable chosen;
  if (variable.empty()) {
    chosen = choose_variable(vars, path);
  } else {
    const auto it = std::find_if(vars.begin(), vars.end(),
                                 [&](const Variable& v) { return v.name == variable; });
    if (it == vars.end()) throw FormatError(concat("'", path, "' has no variable '", variable, "'"));
    if (!it->square) {
      throw FormatError(concat("'", path, "': variable ", it->text,
                               " is not a square 2-D real numeric, logical or sparse matrix"));
    }
    chosen = *it;
  }
  const std::string& name = chosen.name;
  const std::size_t n = chosen.n;
  if (frames >= 0 && n != static_cast<std::size_t>(frames)) {
    throw FormatError(concat("'", path, "': matrix '", name, "' is ", n, "x", n,
                             " but the sequence has ", frames, " frames"));
  }
  if (n > 1'000'000) {
    throw FormatError(
        concat("'", path, "': matrix '", name, "' is ", n, "x", n, ": more than 1e6 frames"));
  }
  GroundTruth gt(static_cast<std::int64_t>(n));
  if (version == MAT_FT_MAT5) {
    read_v5(path, container, name, n, gt);  // checks the data against the dimensions
    return gt;
  }
  if (chosen.v4_sparse) {  // matio would allocate the column index the last row claims
    read_v4_sparse(path, *chosen.v4_sparse, n, gt);
    return gt;
  }
  if (chosen.cls != MAT_C_SPARSE &&
      static_cast<double>(n) * n * Mat_SizeOfClass(static_cast<matio_classes>(chosen.cls)) > 16e9) {
    throw FormatError(concat("'", path, "': matrix '", name, "' is ", n, "x", n,
                             ": too large to read densely (limit 16 GB)"));
  }
  matio_last_message.clear();
  MatVar var{Mat_VarRead(mat.get(), name.c_str())};
  if (!var || !matio_last_message.empty()) {
    throw FormatError(concat("cannot read variable '", name, "' from '", path,
                             "' (truncated or corrupt?)", matio_detail()));
  }
  add_matrix(*var, n, gt, path);
  return gt;
}

}  // namespace lsgd::eval
