// The Python module lsgd._lsgd (pybind11): the detector, the place
// database, sequences, ground truth and the strict metrics, for
// /usr/bin/python3 with numpy. lsgd/__init__.py re-exports it; README,
// "Python", shows how to use it.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <filesystem>
#include <iomanip>
#include <map>
#include <opencv2/core.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/eval/dataset.h"
#include "lsgd/eval/detections.h"
#include "lsgd/eval/gt_formats.h"
#include "lsgd/eval/groundtruth.h"
#include "lsgd/eval/metrics.h"
#include "lsgd/eval/results_csv.h"
#include "lsgd/io/config.h"
#include "lsgd/io/database.h"
#include "lsgd/io/session.h"
#include "lsgd/io/files.h"
#include "lsgd/io/sequence.h"
#include "lsgd/options.h"
#include "lsgd/version.h"

namespace py = pybind11;

namespace {

// ---- paths: str, bytes or any os.PathLike (pathlib.Path), as os.fspath
// gives them; bytes as the file system encodes names (os.fsdecode). A NUL
// inside is refused (the C library would read the name up to it).
std::string path_of(const py::handle& value, const char* what = "path") {
  const py::module_ os = py::module_::import("os");
  py::object text;
  try {
    text = os.attr("fsdecode")(os.attr("fspath")(value));
  } catch (const py::error_already_set&) {
    throw lsgd::InvalidArgument(std::string(what) + ": " + std::string(py::str(py::type::of(value).attr("__name__"))) +
                                " is not a path (str, bytes or os.PathLike such as pathlib.Path)");
  }
  const std::string path = text.cast<std::string>();
  if (path.find('\0') != std::string::npos) {
    throw lsgd::InvalidArgument(std::string(what) + " '" + path.substr(0, path.find('\0')) +
                                "\\0...' has a NUL character inside: no file has such a name");
  }
  return path;
}

// ---- options: a dict with the YAML's names, nested ({"search": {"min_gap":
// 50}}) or dotted ({"search.min_gap": 50}), values as Python numbers or text.

std::string option_value_text(const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) {
    throw lsgd::InvalidArgument("an option value is a bool; options take numbers or names");
  }
  if (py::isinstance<py::float_>(value)) {
    return lsgd::format_real(value.cast<double>());
  }
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    std::string text;  // verification.stages as a list of names
    for (const py::handle& item : value) text += (text.empty() ? "" : ",") + py::str(item).cast<std::string>();
    return text.empty() ? "none" : text;
  }
  return py::str(value).cast<std::string>();
}

// `given`: the keys set so far from this dict, with their values: a key
// given twice ({"search": {"min_gap": 5}, "search.min_gap": 7}) is refused.
void set_options(lsgd::DetectorOptions& options, const py::dict& values, const std::string& prefix,
                 std::map<std::string, std::string>& given) {
  for (const auto& [k, v] : values) {
    const std::string key = prefix + py::str(k).cast<std::string>();
    if (py::isinstance<py::dict>(v)) {
      set_options(options, v.cast<py::dict>(), key + ".", given);
      continue;
    }
    const std::string text = option_value_text(v);
    const auto [at, added] = given.emplace(key, text);
    if (!added) {
      throw lsgd::InvalidArgument("option " + key + " is given twice (" + at->second + " and " + text +
                                  "), nested and dotted: give it once");
    }
    lsgd::set_option(options, key, text);
  }
}

void set_options(lsgd::DetectorOptions& options, const py::dict& values) {
  std::map<std::string, std::string> given;
  set_options(options, values, "", given);
}

lsgd::DetectorOptions make_options(const py::object& options, const py::kwargs& kwargs) {
  lsgd::DetectorOptions o;
  if (!options.is_none()) {
    if (py::isinstance<py::dict>(options)) {
      set_options(o, options.cast<py::dict>());
    } else {
      o = lsgd::io::load_config(path_of(options, "options"));  // a YAML file
    }
  }
  set_options(o, kwargs);
  o.check();
  return o;
}

// Every option as {"search.min_gap": "50", ...}, in the YAML's order, as text
// that reads back equal.
py::dict options_dict(const lsgd::DetectorOptions& o) {
  py::dict out;
  for (const auto& f : lsgd::DetectorOptions::fields()) out[py::str(f.name)] = f.text(o);
  return out;
}

// ---- images: numpy uint8 arrays, H x W (gray), H x W x 3 (BGR), H x W x 4 (BGRA)

// Each row's pixels packed (a dimension of size 1 may have any stride: numpy
// calls such arrays contiguous whatever it holds there).
bool rows_dense(const py::array& a) {
  if (a.ndim() < 2) return false;
  const py::ssize_t channels = a.ndim() == 3 ? a.shape(2) : 1;
  return (a.ndim() == 2 || a.shape(2) == 1 || a.strides(2) == 1) &&
         (a.shape(1) == 1 || a.strides(1) == channels) &&
         (a.shape(0) == 1 || a.strides(0) >= a.shape(1) * channels);
}

// The image's pixels, checked (type, shape, size) before anything is copied;
// an array whose rows are not contiguous is copied into `a` first (the view
// points into `a`, which must outlive it).
lsgd::ImageView image_view(py::array& a) {
  if (a.dtype().kind() != 'u' || a.itemsize() != 1) {
    throw lsgd::InvalidArgument("the image is a numpy array of " + py::str(a.dtype()).cast<std::string>() +
                                ": expected uint8 (convert 16-bit or float images first)");
  }
  const int channels = a.ndim() == 2 ? 1 : a.ndim() == 3 ? static_cast<int>(a.shape(2)) : 0;
  if (channels != 1 && channels != 3 && channels != 4) {
    std::string shape;
    for (py::ssize_t i = 0; i < a.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(a.shape(i));
    throw lsgd::InvalidArgument("the image has shape (" + shape +
                                "): expected (H, W) gray, (H, W, 3) BGR or (H, W, 4) BGRA");
  }
  for (py::ssize_t i = 0; i < 2; ++i) {
    if (a.shape(i) == 0 || a.shape(i) > lsgd::kMaxImageSide) {
      throw lsgd::InvalidArgument("the image is " + std::to_string(a.shape(0)) + " x " +
                                  std::to_string(a.shape(1)) + " pixels: " +
                                  (a.shape(i) == 0 ? std::string("empty")
                                                   : "a side above " + std::to_string(lsgd::kMaxImageSide)));
    }
  }
  if (!rows_dense(a)) a = py::array::ensure(a, py::array::c_style);
  if (!a || !rows_dense(a)) throw lsgd::InvalidArgument("the image's rows are not contiguous");
  lsgd::ImageView v;
  v.data = static_cast<const std::uint8_t*>(a.data());
  v.width = static_cast<int>(a.shape(1));
  v.height = static_cast<int>(a.shape(0));
  v.stride_bytes = a.shape(0) == 1 ? static_cast<std::size_t>(a.shape(1)) * static_cast<std::size_t>(channels)
                                    : static_cast<std::size_t>(a.strides(0));
  v.format = channels == 1 ? lsgd::PixelFormat::kGray8
             : channels == 3 ? lsgd::PixelFormat::kBgr8 : lsgd::PixelFormat::kBgra8;
  return v;
}


py::array mat_to_array(const cv::Mat& m) {
  std::vector<py::ssize_t> shape = {m.rows, m.cols};
  if (m.channels() > 1) shape.push_back(m.channels());
  py::array_t<std::uint8_t> out(shape);
  for (int y = 0; y < m.rows; ++y) {
    std::memcpy(out.mutable_data(y), m.ptr(y), static_cast<std::size_t>(m.cols) * m.channels());
  }
  return out;
}

lsgd::eval::FrameRecord record_of(const lsgd::Result& r) {
  lsgd::eval::FrameRecord rec;
  rec.frame = r.frame;
  rec.reported = r.best;
  rec.loop = r.loop;
  rec.ranking = r.ranking;
  rec.candidates = r.candidates;
  rec.timings = r.timings;
  return rec;
}

}  // namespace

// A Database Python can close before the garbage collector drops it (a
// second writer on the same file in this process is refused while the first
// is open): every call on a closed one is an InvalidArgument naming the file.
struct PyDatabase {
  explicit PyDatabase(lsgd::io::Database d) : db(std::make_unique<lsgd::io::Database>(std::move(d))), path(db->path()) {}
  lsgd::io::Database& get() const {
    if (!db) throw lsgd::InvalidArgument("database " + path + " is closed");
    return *db;
  }
  void close() { db.reset(); }
  std::unique_ptr<lsgd::io::Database> db;
  std::string path;
};

PYBIND11_MODULE(_lsgd, m) {
  m.doc() = "lsgd: training-free visual loop closure detection (LSGDDN-LCD)";
  m.attr("__version__") = lsgd::version();
  m.attr("__commit__") = lsgd::commit();

  // Errors: lsgd.Error and its kinds, each also a standard Python exception.
  static py::exception<lsgd::Error> error(m, "Error", PyExc_RuntimeError);
  static py::handle invalid = PyErr_NewException("lsgd.InvalidArgument",
      py::make_tuple(error, py::handle(PyExc_ValueError)).release().ptr(), nullptr);
  static py::handle io_error = PyErr_NewException("lsgd.IoError",
      py::make_tuple(error, py::handle(PyExc_OSError)).release().ptr(), nullptr);
  static py::handle format_error = PyErr_NewException("lsgd.FormatError",
      py::make_tuple(error, py::handle(PyExc_ValueError)).release().ptr(), nullptr);
  m.attr("InvalidArgument") = invalid;
  m.attr("IoError") = io_error;
  m.attr("FormatError") = format_error;
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const lsgd::InvalidArgument& e) {
      PyErr_SetString(invalid.ptr(), e.what());
    } catch (const lsgd::IoError& e) {
      PyErr_SetString(io_error.ptr(), e.what());
    } catch (const lsgd::FormatError& e) {
      PyErr_SetString(format_error.ptr(), e.what());
    } catch (const lsgd::Error& e) {
      PyErr_SetString(error.ptr(), e.what());
    }
  });

  py::class_<lsgd::Candidate>(m, "Candidate")
      .def_readonly("frame", &lsgd::Candidate::frame)
      .def_readonly("score", &lsgd::Candidate::score)
      .def("__repr__", [](const lsgd::Candidate& c) {
        return "Candidate(frame=" + std::to_string(c.frame) + ", score=" + lsgd::format_real(c.score) + ")";
      });
  py::class_<lsgd::LoopEvidence>(m, "LoopEvidence")
      .def_readonly("appearance", &lsgd::LoopEvidence::appearance)
      .def_readonly("inliers", &lsgd::LoopEvidence::inliers)
      .def_readonly("confirmed", &lsgd::LoopEvidence::confirmed)
      .def_readonly("continues", &lsgd::LoopEvidence::continues);
  py::class_<lsgd::Ranking>(m, "Ranking")
      .def_readonly("best", &lsgd::Ranking::best)
      .def_readonly("confirmed", &lsgd::Ranking::confirmed)
      .def("__repr__", [](const lsgd::Ranking& r) {
        return "Ranking(best=Candidate(frame=" + std::to_string(r.best.frame) + ", score=" +
               lsgd::format_real(r.best.score) + "), confirmed=" + (r.confirmed ? "True" : "False") + ")";
      });
  // Copies into numpy arrays (a LoopGeometry is immutable and shared).
  const auto points = [](const std::vector<float>& v) {
    py::array_t<float> out({static_cast<py::ssize_t>(v.size() / 2), py::ssize_t{2}});
    std::copy(v.begin(), v.end(), out.mutable_data());
    return out;
  };
  py::class_<lsgd::LoopGeometry, std::shared_ptr<lsgd::LoopGeometry>>(m, "LoopGeometry",
      "What the geometric stage fitted between the query and the reported candidate: its "
      "matches and the better model (points in pixels of each original image)")
      .def_readonly("model", &lsgd::LoopGeometry::model, "'fundamental' or 'homography'")
      .def_property_readonly("matrix", [](const lsgd::LoopGeometry& g) {
             py::array_t<double> out({py::ssize_t{3}, py::ssize_t{3}});
             std::copy(g.matrix.begin(), g.matrix.end(), out.mutable_data());
             return out;
           }, "3x3 float64: c^T F q = 0 for a match, or c ~ H q (q query, c candidate)")
      .def_property_readonly("query_points", [points](const lsgd::LoopGeometry& g) {
             return points(g.query_points);
           }, "N x 2 float32, x and y of each match in the query")
      .def_property_readonly("candidate_points", [points](const lsgd::LoopGeometry& g) {
             return points(g.candidate_points);
           }, "N x 2 float32, the same matches in the candidate")
      .def_property_readonly("inliers", [](const lsgd::LoopGeometry& g) {
             py::array_t<bool> out(static_cast<py::ssize_t>(g.inliers.size()));
             for (std::size_t k = 0; k < g.inliers.size(); ++k) out.mutable_data()[k] = g.inliers[k] != 0;
             return out;
           }, "N bool: the matches that are inliers of the model")
      .def("__repr__", [](const lsgd::LoopGeometry& g) {
        std::size_t inliers = 0;
        for (const std::uint8_t v : g.inliers) inliers += v;
        return "LoopGeometry(model='" + g.model + "', matches=" + std::to_string(g.matches()) +
               ", inliers=" + std::to_string(inliers) + ")";
      });
  py::class_<lsgd::StageVerdict>(m, "StageVerdict")
      .def_readonly("candidate", &lsgd::StageVerdict::candidate)
      .def_readonly("stage", &lsgd::StageVerdict::stage)
      .def_readonly("accepted", &lsgd::StageVerdict::accepted)
      .def_readonly("reason", &lsgd::StageVerdict::reason)
      .def_readonly("ms", &lsgd::StageVerdict::ms);
  py::class_<lsgd::Timings>(m, "Timings")
      .def_readonly("convert_ms", &lsgd::Timings::convert_ms)
      .def_readonly("segment_ms", &lsgd::Timings::segment_ms)
      .def_readonly("describe_ms", &lsgd::Timings::describe_ms)
      .def_readonly("search_ms", &lsgd::Timings::search_ms)
      .def_readonly("insert_ms", &lsgd::Timings::insert_ms)
      .def_readonly("evidence_ms", &lsgd::Timings::evidence_ms)
      .def_readonly("verify_ms", &lsgd::Timings::verify_ms)
      .def_readonly("total_ms", &lsgd::Timings::total_ms);
  py::enum_<lsgd::LoopStatus> status(m, "LoopStatus",
                                     "Why a query has a loop or none (Result.status); str() of a "
                                     "value is the CSV's name");
  status.value("LOOP", lsgd::LoopStatus::kLoop)
      .value("TOO_FEW_FRAMES", lsgd::LoopStatus::kTooFewFrames)
      .value("NO_CANDIDATE", lsgd::LoopStatus::kNoCandidate)
      .value("GATED", lsgd::LoopStatus::kGated)
      .value("YOUNG", lsgd::LoopStatus::kYoung)
      .value("NOT_CONFIRMED", lsgd::LoopStatus::kNotConfirmed)
      .value("BELOW_THRESHOLD", lsgd::LoopStatus::kBelowThreshold);
  // Replaces enum_'s own __str__ (a def() would only add an overload after it).
  status.attr("__str__") = py::cpp_function(
      [](lsgd::LoopStatus s) { return std::string(lsgd::to_string(s)); }, py::is_method(status));
  py::class_<lsgd::Descriptor>(m, "Descriptor",
      "A frame's descriptor (Detector.describe): one histogram per cell of its grid. "
      "Descriptor.from_arrays builds one back from numpy arrays.")
      .def_property_readonly("grid", [](const lsgd::Descriptor& d) { return py::make_tuple(d.grid.rows, d.grid.cols); })
      .def_property_readonly("storage", [](const lsgd::Descriptor& d) { return std::string(lsgd::to_string(d.storage)); })
      .def_property_readonly("histograms", [](const lsgd::Descriptor& d) -> py::array {
             const auto cells = static_cast<py::ssize_t>(d.grid.cells());
             if (d.storage == lsgd::HistogramStorage::kCompact) {
               py::array_t<std::uint8_t> out({cells, py::ssize_t{lsgd::kCompactBins}});
               std::copy(d.compact.begin(), d.compact.end(), out.mutable_data());
               return out;
             }
             py::array_t<std::uint16_t> out({cells, py::ssize_t{lsgd::kBins}});
             std::copy(d.hist.begin(), d.hist.end(), out.mutable_data());
             return out;
           }, "cells x 256 uint16 counts (exact), or cells x 128 uint8 (compact), cell-major")
      .def_property_readonly("pixels", [](const lsgd::Descriptor& d) {
             py::array_t<std::uint32_t> out(static_cast<py::ssize_t>(d.pixels.size()));
             std::copy(d.pixels.begin(), d.pixels.end(), out.mutable_data());
             return out;
           }, "pixels per cell (exact; empty when compact)")
      .def_readonly("cell_pixels", &lsgd::Descriptor::cell_pixels, "mean pixels per cell (compact)")
      .def_static("from_arrays", [](py::array histograms, const py::object& pixels, py::tuple grid, double cell_pixels) {
             lsgd::Descriptor d;
             if (grid.size() != 2) throw lsgd::InvalidArgument("grid is (rows, cols)");
             d.grid = {grid[0].cast<int>(), grid[1].cast<int>()};
             if (d.grid.rows <= 0 || d.grid.cols <= 0 || d.grid.cells() > 1 << 20) {
               throw lsgd::InvalidArgument("grid " + std::to_string(d.grid.rows) + " x " +
                                           std::to_string(d.grid.cols) + " is not a descriptor's grid");
             }
             if (py::isinstance<py::array_t<std::uint8_t>>(histograms)) {
               const auto h = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(histograms);
               d.storage = lsgd::HistogramStorage::kCompact;
               d.compact.assign(h.data(), h.data() + h.size());
               d.cell_pixels = cell_pixels;
             } else {
               const auto h = py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast>::ensure(histograms);
               if (!h) throw lsgd::InvalidArgument("histograms is not an array of counts");
               d.hist.assign(h.data(), h.data() + h.size());
               const auto p = py::array_t<std::uint32_t, py::array::c_style | py::array::forcecast>::ensure(pixels);
               if (!p) throw lsgd::InvalidArgument("an exact descriptor needs its pixels per cell");
               d.pixels.assign(p.data(), p.data() + p.size());
             }
             d.check_consistent("Descriptor.from_arrays");
             return d;
           }, py::arg("histograms"), py::arg("pixels") = py::none(), py::arg("grid"), py::arg("cell_pixels") = 0.0,
           "A descriptor from its arrays: uint16 histograms (cells x 256) with uint32 pixels per cell "
           "(exact), or uint8 histograms (cells x 128) with cell_pixels (compact)");
  m.def("similarity", [](const lsgd::Descriptor& a, const lsgd::Descriptor& b, const std::string& metric) {
          if (a.grid != b.grid || a.storage != b.storage) {
            throw lsgd::InvalidArgument("the descriptors differ in grid or storage");
          }
          return lsgd::similarity(a.view(), b.view(), lsgd::parse_similarity_metric(metric.c_str()));
        }, py::arg("a"), py::arg("b"), py::arg("metric") = std::string(lsgd::to_string(lsgd::SimilarityOptions{}.metric)),
        "Similarity of two descriptors (the detector's similarity.metric by default).");
  m.def("match",
        [](const std::vector<lsgd::Descriptor>& reference, const std::vector<lsgd::Descriptor>& query,
           int top_k, const std::string& metric, std::int64_t query_offset, const py::object& output) {
          std::vector<lsgd::DescriptorView> refs, queries;
          for (const lsgd::Descriptor& d : reference) refs.push_back(d.view());
          for (const lsgd::Descriptor& d : query) queries.push_back(d.view());
          std::vector<lsgd::TopMatch> found;
          {
            py::gil_scoped_release release;
            found = lsgd::match_top_k(refs, queries, top_k,
                                      lsgd::parse_similarity_metric(metric.c_str()), query_offset);
          }
          if (!output.is_none()) {  // the CSV lsgd match writes, whole or not at all
            lsgd::io::write_output_file(path_of(output, "output"), lsgd::eval::match_csv(found), "matches CSV");
          }
          const auto n = static_cast<py::ssize_t>(found.size());
          py::array_t<std::int64_t> q(n), j(n), rank(n);
          py::array_t<double> score(n), sim(n);
          for (py::ssize_t i = 0; i < n; ++i) {
            const lsgd::TopMatch& t = found[static_cast<std::size_t>(i)];
            q.mutable_at(i) = t.query;
            j.mutable_at(i) = t.match;
            score.mutable_at(i) = t.score;
            sim.mutable_at(i) = t.similarity;
            rank.mutable_at(i) = t.rank;
          }
          py::dict d;
          d["query"] = q;
          d["match"] = j;
          d["score"] = score;
          d["similarity"] = sim;
          d["rank"] = rank;
          return d;
        },
        py::arg("reference"), py::arg("query"), py::arg("top_k") = 1,
        py::arg("metric") = std::string(lsgd::to_string(lsgd::SimilarityOptions{}.metric)),
        py::arg("query_offset") = 0, py::arg("output") = py::none(),
        "Place recognition between two traverses, as lsgd match: the top_k reference "
        "descriptors of every query descriptor (Detector.describe), as numpy arrays query "
        "(query_offset + index), match (reference index), score (sigma of the query's "
        "similarities to the reference), similarity and rank (1: best); output: also write "
        "lsgd match's CSV there (lsgd.evaluate_detections reads it).");
  py::class_<lsgd::Result>(m, "Result")
      .def_readonly("frame", &lsgd::Result::frame)
      .def_readonly("id", &lsgd::Result::id)
      .def_readonly("stamp", &lsgd::Result::stamp)
      .def_readonly("loop_id", &lsgd::Result::loop_id)
      .def_readonly("loop", &lsgd::Result::loop)
      .def_readonly("best", &lsgd::Result::best)
      .def_readonly("status", &lsgd::Result::status)
      .def_readonly("evidence", &lsgd::Result::evidence)
      .def_property_readonly("geometry", [](const lsgd::Result& r) {
             return std::const_pointer_cast<lsgd::LoopGeometry>(r.geometry);
           }, "LoopGeometry of the reported candidate when the geometric stage fitted one, else None")
      .def_readonly("ranking", &lsgd::Result::ranking)
      .def_readonly("candidates", &lsgd::Result::candidates)
      .def_readonly("verification", &lsgd::Result::verification)
      .def_readonly("node", &lsgd::Result::node)
      .def_readonly("node_created", &lsgd::Result::node_created)
      .def_readonly("timings", &lsgd::Result::timings)
      .def("__repr__", [](const lsgd::Result& r) {
        return "Result(frame=" + std::to_string(r.frame) + ", loop=" + (r.loop ? "True" : "False") +
               ", best=" + std::to_string(r.best.frame) + ", score=" + lsgd::format_real(r.best.score) +
               ", status=" + lsgd::to_string(r.status) + ")";
      });

  m.def("default_options", [] { return options_dict(lsgd::DetectorOptions{}); },
        "Every detector option and its default, as {'search.min_gap': '50', ...}.");
  m.def("options", [](const py::object& options, const py::kwargs& kwargs) {
          return options_dict(make_options(options, kwargs));
        }, py::arg("options") = py::none(),
        "The options a Detector(options, **kwargs) would use, validated.");

  py::class_<lsgd::Detector>(m, "Detector")
      .def(py::init([](const py::object& options, const py::kwargs& kwargs) {
             return std::make_unique<lsgd::Detector>(make_options(options, kwargs));
           }),
           py::arg("options") = py::none(),
           "Detector(options=None, **kwargs): options as a dict with the YAML's names "
           "(nested or dotted), a YAML file name, or keyword arguments per section: "
           "Detector(search={'min_gap': 50, 'mode': 'nodes'}, verification={'stages': 'temporal'}).")
      .def("process",
           [](lsgd::Detector& d, py::array image, std::int64_t id, double stamp) {
             // A strided view (a crop with a step, a transposed array) is copied once.
             const lsgd::ImageView view = image_view(image);  // may copy into `image`
             py::gil_scoped_release release;  // other Python threads run meanwhile
             return d.process(view, id, stamp);
           },
           py::arg("image"), py::arg("id") = -1, py::arg("stamp") = lsgd::kNoStamp,
           "Processes the next frame (uint8 numpy array: (H, W) gray, (H, W, 3) BGR or "
           "(H, W, 4) BGRA) and returns its Result. id: the caller's id of the frame (above the "
           "last; -1: the one after it), stamp: its time stamp (NaN: none); Result.id, .stamp and "
           ".loop_id carry them. Zero-copy when each row's pixels are contiguous; the GIL is "
           "released while it runs.")
      .def("query",
           [](lsgd::Detector& d, py::array image, std::int64_t id, double stamp) {
             const lsgd::ImageView view = image_view(image);  // may copy into `image`
             py::gil_scoped_release release;
             return d.query(view, id, stamp);
           },
           py::arg("image"), py::arg("id") = -1, py::arg("stamp") = lsgd::kNoStamp,
           "The Result process() would give for the frame as the next one, with nothing "
           "stored and nothing changed (relocalisation; a map opened read-only). Result.frame "
           "is the id process() would give it.")
      .def("forget", &lsgd::Detector::forget, py::arg("first_id"), py::arg("last_id"),
           "Forgets the stored frames whose ids lie in [first_id, last_id] and returns how many: "
           "they are never candidates again; the kept frames keep their ids (their frame numbers "
           "close up), and the detector is the one restoring only them would give.")
      .def("cut", &lsgd::Detector::cut,
           "The next frame starts a new sequence (a new session, another place): it "
           "continues no loop declared for the frame before it.")
      .def_property_readonly("size", &lsgd::Detector::size)
      .def("__len__", &lsgd::Detector::size)
      .def_property_readonly("nodes", &lsgd::Detector::nodes)
      .def_property_readonly("options", [](const lsgd::Detector& d) { return options_dict(d.options()); })
      .def("describe",
           [](lsgd::Detector& d, py::array image) {
             const lsgd::ImageView view = image_view(image);  // may copy into `image`
             py::gil_scoped_release release;
             return d.describe(view);
           },
           py::arg("image"), "The image's Descriptor as the detector would store it; nothing stored.")
      .def("id_of", &lsgd::Detector::id_of, py::arg("frame"), "The caller's id of stored frame `frame`.")
      .def("stamp_of", &lsgd::Detector::stamp_of, py::arg("frame"), "Its time stamp (NaN: none).")
      .def("frame_of", &lsgd::Detector::frame_of, py::arg("id"),
           "The stored frame of caller id `id` (-1: none).")
      .def("similarity", &lsgd::Detector::similarity, py::arg("a"), py::arg("b"),
           "Similarity of two stored frames with the configured metric.");

  // ---- the place database
  py::class_<PyDatabase>(m, "Database",
      "The place database. close() (or leaving a `with` block) releases the file; a closed "
      "Database refuses every call.")
      .def_static("create", [](const py::object& path, const py::object& options, const py::kwargs& kwargs) {
             return PyDatabase(lsgd::io::Database::create(path_of(path), make_options(options, kwargs)));
           }, py::arg("path"), py::arg("options") = py::none(),
           "Creates a new, empty database for detectors with these options.")
      .def_static("open", [](const py::object& path, bool writable) {
             return PyDatabase(lsgd::io::Database::open(
                 path_of(path), writable ? lsgd::io::Database::Mode::kReadWrite : lsgd::io::Database::Mode::kReadOnly));
           }, py::arg("path"), py::arg("writable") = true)
      .def("detector", [](const PyDatabase& db, bool rebuild_index) {
             auto d = std::make_unique<lsgd::Detector>(db.get().options());
             db.get().restore(*d, rebuild_index ? lsgd::io::IndexUse::kRebuild : lsgd::io::IndexUse::kSaved);
             return d;
           }, py::arg("rebuild_index") = false,
           "A detector with the stored options and every stored frame restored (and the saved "
           "search index, unless rebuild_index).")
      .def("restore", [](const PyDatabase& db, lsgd::Detector& d, bool rebuild_index) {
             db.get().restore(d, rebuild_index ? lsgd::io::IndexUse::kRebuild : lsgd::io::IndexUse::kSaved);
           }, py::arg("detector"), py::arg("rebuild_index") = false)
      .def("save_index", [](PyDatabase& db, const lsgd::Detector& d) { return db.get().save_index(d); },
           py::arg("detector"),
           "Saves the detector's search index (index mode's graph) so a resume need not rebuild "
           "it; returns the frames it covers.")
      .def("append", [](PyDatabase& db, const lsgd::Detector& d, const lsgd::Result& r, std::int64_t session,
                        const std::string& name, std::int64_t frame) {
             db.get().append(d, r, session, name, frame);
           }, py::arg("detector"), py::arg("result"), py::arg("session"), py::arg("name") = "",
           py::arg("frame") = -1, "Stores the detector's last frame (call right after process()).")
      .def("forget", [](PyDatabase& db, std::int64_t first_id, std::int64_t last_id) {
             return db.get().forget(first_id, last_id);
           }, py::arg("first_id"), py::arg("last_id"),
           "Forgets the frames whose ids lie in [first_id, last_id], in one transaction (as "
           "Detector.forget); returns how many.")
      .def("plan_session", [](const PyDatabase& db, const lsgd::Detector& d, const py::list& images,
                              std::optional<std::int64_t> session) {
             std::vector<std::string> paths;
             for (const py::handle& image : images) paths.push_back(path_of(py::reinterpret_borrow<py::object>(image)));
             return lsgd::io::plan_session(db.get(), d, paths, session);
           }, py::arg("detector"), py::arg("images"), py::arg("session") = py::none(),
           "Where a run of `images` (paths) continues, as `lsgd run --database` decides: the last "
           "session from its next image when the images are that session's, else a new session "
           "(`session`, or the last + 1). `detector` holds the stored frames (Database.detector()). "
           "Image i is frame plan.first_id + i; store it under lsgd.stored_image_name(path).")
      .def("forget_session", [](PyDatabase& db, std::int64_t session) {
             return db.get().forget_session(session);
           }, py::arg("session"), "Forgets every frame of the session; returns how many.")
      .def("close", &PyDatabase::close,
           "Checkpoints and releases the file (a writer's lock included); again: nothing.")
      .def_property_readonly("closed", [](const PyDatabase& db) { return !db.db; })
      .def("__enter__", [](PyDatabase& db) -> PyDatabase& { return db; }, py::return_value_policy::reference)
      .def("__exit__", [](PyDatabase& db, const py::object&, const py::object&, const py::object&) {
             db.close();
             return false;
           })
      .def_property_readonly("path", [](const PyDatabase& db) { return db.path; })
      .def_property_readonly("frames", [](const PyDatabase& db) { return db.get().frames(); })
      .def_property_readonly("last_session", [](const PyDatabase& db) { return db.get().last_session(); })
      .def_property_readonly("options", [](const PyDatabase& db) { return options_dict(db.get().options()); })
      .def("frame_ids", [](const PyDatabase& db) { return db.get().frame_ids(); })
      .def("__repr__", [](const PyDatabase& db) {
        return "Database('" + db.path + "', " +
               (db.db ? std::to_string(db.db->frames()) + " frames)" : std::string("closed)"));
      });

  py::class_<lsgd::io::SessionPlan>(m, "SessionPlan",
      "Database.plan_session's answer: the session, the id of image 0, the first image to "
      "process, whether the session is continued, and its last stored frame's id.")
      .def_readonly("session", &lsgd::io::SessionPlan::session)
      .def_readonly("first_id", &lsgd::io::SessionPlan::first_id)
      .def_readonly("first", &lsgd::io::SessionPlan::first)
      .def_readonly("resume", &lsgd::io::SessionPlan::resume)
      .def_readonly("last_stored", &lsgd::io::SessionPlan::last_stored)
      .def("__repr__", [](const lsgd::io::SessionPlan& p) {
        return "SessionPlan(session=" + std::to_string(p.session) + ", first_id=" + std::to_string(p.first_id) +
               ", first=" + std::to_string(p.first) + ", resume=" + (p.resume ? "True" : "False") + ")";
      });
  m.def("write_csv", [](const std::vector<lsgd::Result>& results, const py::list& images, const py::object& path) {
          if (images.size() != results.size()) {
            throw lsgd::InvalidArgument("write_csv: " + std::to_string(images.size()) + " image names for " +
                                        std::to_string(results.size()) + " results (one per result)");
          }
          const std::string out = path_of(path);
          std::vector<std::string> names;
          for (const py::handle& image : images) {
            names.push_back(path_of(py::reinterpret_borrow<py::object>(image)));
            std::error_code ec;  // an output never overwrites an input
            if (std::filesystem::equivalent(out, names.back(), ec)) {
              throw lsgd::InvalidArgument("write_csv: the output " + out + " is the input image " + names.back());
            }
          }
          lsgd::eval::CsvWriter csv(out);
          for (std::size_t i = 0; i < results.size(); ++i) csv.write(results[i], names[i]);
          return csv.loops();
        }, py::arg("results"), py::arg("images"), py::arg("path"),
        "Writes the results as `lsgd run`'s CSV (the same code, one row per result, `images` its image "
        "column); returns the loops written. Replaces the file.");
  m.def("stored_image_name", [](const py::object& path) { return lsgd::io::stored_image_name(path_of(path)); },
        py::arg("path"), "The name a database keeps for an image (its absolute, normal path), as lsgd run stores it.");

  // ---- images and sequences
  m.def("read_image", [](const py::object& path) { return mat_to_array(lsgd::io::read_image(path_of(path))); },
        py::arg("path"), "Reads an image file as a uint8 array (gray or BGR); lsgd.Error on a bad file.");
  m.def("open_sequence", [](const py::object& path) { return lsgd::io::open_sequence(path_of(path)).images; },
        py::arg("path"), "The image paths of a folder (natural order) or an image list file.");

  // ---- ground truth and the strict metrics
  py::class_<lsgd::eval::GroundTruth>(m, "GroundTruth")
      .def(py::init<std::int64_t>(), py::arg("frames"))
      .def("add", &lsgd::eval::GroundTruth::add)
      .def_property_readonly("frames", &lsgd::eval::GroundTruth::frames)
      .def_property_readonly("pairs", &lsgd::eval::GroundTruth::pairs)
      .def("is_loop", &lsgd::eval::GroundTruth::is_loop)
      .def("matches", &lsgd::eval::GroundTruth::matches)
      .def("queries", &lsgd::eval::GroundTruth::queries)
      .def("has_loop", &lsgd::eval::GroundTruth::has_loop, py::arg("query"), py::arg("min_gap"));
  m.def("load_groundtruth", [](const py::object& path, std::int64_t frames, const std::string& format) {
          lsgd::eval::GtOptions o;
          o.frames = frames;
          o.format = lsgd::eval::parse_gt_format(format);
          return lsgd::eval::load_groundtruth(path_of(path), o);
        }, py::arg("path"), py::arg("frames") = -1, py::arg("format") = "auto",
        "Reads loop ground truth: pairs text, MATLAB .mat, KITTI poses or loopinf.");

  py::class_<lsgd::eval::PrPoint>(m, "PrPoint")
      .def_readonly("threshold", &lsgd::eval::PrPoint::threshold)
      .def_readonly("precision", &lsgd::eval::PrPoint::precision)
      .def_readonly("recall", &lsgd::eval::PrPoint::recall)
      .def_readonly("confirmed", &lsgd::eval::PrPoint::confirmed);
  py::class_<lsgd::eval::Metrics>(m, "Metrics")
      .def_readonly("protocol", &lsgd::eval::Metrics::protocol)
      .def_readonly("frames", &lsgd::eval::Metrics::frames)
      .def_readonly("positives", &lsgd::eval::Metrics::positives)
      .def_readonly("min_gap", &lsgd::eval::Metrics::min_gap)
      .def_readonly("declared_loops", &lsgd::eval::Metrics::declared_loops)
      .def_readonly("declared_true", &lsgd::eval::Metrics::declared_true)
      .def_readonly("declared_false", &lsgd::eval::Metrics::declared_false)
      .def_readonly("precision_at_decision", &lsgd::eval::Metrics::precision_at_decision)
      .def_readonly("recall_at_decision", &lsgd::eval::Metrics::recall_at_decision)
      .def_readonly("recall_at_100_precision", &lsgd::eval::Metrics::recall_at_100_precision)
      .def_readonly("threshold_at_100_precision", &lsgd::eval::Metrics::threshold_at_100_precision)
      .def_readonly("precision_at_100_recall", &lsgd::eval::Metrics::precision_at_100_recall)
      .def_readonly("average_precision", &lsgd::eval::Metrics::average_precision)
      .def_readonly("decision_recall_at_100_precision",
                    &lsgd::eval::Metrics::decision_recall_at_100_precision)
      .def_readonly("decision_threshold_at_100_precision",
                    &lsgd::eval::Metrics::decision_threshold_at_100_precision)
      .def_readonly("decision_average_precision", &lsgd::eval::Metrics::decision_average_precision)
      .def_readonly("recall_at_1", &lsgd::eval::Metrics::recall_at_1)
      .def_readonly("recall_at_5", &lsgd::eval::Metrics::recall_at_5)
      .def_readonly("recall_at_10", &lsgd::eval::Metrics::recall_at_10)
      .def_readonly("ms_per_frame_median", &lsgd::eval::Metrics::ms_per_frame_median)
      .def_readonly("curve", &lsgd::eval::Metrics::curve);
  m.def("evaluate", [](const std::vector<lsgd::Result>& results, const lsgd::eval::GroundTruth& gt,
                       std::int64_t min_gap) {
          // The results of one detector, in order: its frame k has the id
          // results[k].id, which numbers the ground truth's frames.
          std::vector<std::int64_t> ids;
          for (const lsgd::Result& r : results) {
            if (r.frame != static_cast<std::int64_t>(ids.size())) {
              throw lsgd::InvalidArgument(
                  "evaluate: result " + std::to_string(ids.size()) + " is the detector's frame " +
                  std::to_string(r.frame) + ": give every Result of one detector, in the order "
                  "process() returned them (frames the camera dropped get no Result; give the "
                  "others their ids, process(image, id=...))");
            }
            if (r.id < 0 || r.id >= gt.frames()) {
              throw lsgd::InvalidArgument("evaluate: result " + std::to_string(r.frame) + " has id " +
                                          std::to_string(r.id) + ", outside the ground truth's " +
                                          std::to_string(gt.frames()) + " frames");
            }
            ids.push_back(r.id);
          }
          const auto id = [&](std::int64_t frame) {
            return frame >= 0 && frame < static_cast<std::int64_t>(ids.size())
                       ? ids[static_cast<std::size_t>(frame)]
                       : frame;
          };
          // Every frame of the ground truth: one without a Result is missed.
          std::vector<lsgd::eval::FrameRecord> records(static_cast<std::size_t>(gt.frames()));
          for (std::int64_t f = 0; f < gt.frames(); ++f) {
            records[static_cast<std::size_t>(f)].frame = f;
            records[static_cast<std::size_t>(f)].skipped = true;
          }
          for (const lsgd::Result& r : results) {
            lsgd::eval::FrameRecord rec = record_of(r);
            rec.frame = r.id;
            rec.reported.frame = id(rec.reported.frame);
            if (rec.ranking) rec.ranking->best.frame = id(rec.ranking->best.frame);
            for (lsgd::Candidate& c : rec.candidates) c.frame = id(c.frame);
            records[static_cast<std::size_t>(r.id)] = rec;
          }
          return lsgd::eval::evaluate(records, gt, min_gap);
        }, py::arg("results"), py::arg("groundtruth"), py::arg("min_gap"),
        "Scores a detector's results (every Result in order; ids, process(image, id=...), "
        "number the ground truth's frames, and a frame without a Result is missed) under the "
        "strict protocol (docs/evaluation.md): the declared loops (operating point), R@100P, "
        "AP, R@N.");
  m.def("evaluate_detections", [](const py::object& path, const lsgd::eval::GroundTruth& gt,
                                  std::int64_t min_gap) {
          return lsgd::eval::evaluate(lsgd::eval::read_detections(path_of(path), gt.frames()), gt, min_gap);
        }, py::arg("path"), py::arg("groundtruth"), py::arg("min_gap"),
        "Scores a detections CSV (query,match,score[,rank]: lsgd match, lsgd.match, another "
        "system's output) as lsgd eval --detections does.");
}
