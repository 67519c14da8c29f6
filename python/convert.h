// Conversions the binders (python/bind_*.cc) share: paths from Python
// objects, detector options from a dict, a YAML file or keywords (and back
// as a dict), images between numpy uint8 arrays and the library's types.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <opencv2/core.hpp>
#include <string>

#include "lsgd/detector.h"
#include "lsgd/eval/metrics.h"
#include "lsgd/options.h"

namespace lsgd::python {

namespace py = pybind11;

// ---- paths: str, bytes or any os.PathLike (pathlib.Path), as os.fspath
// gives them, taken as the file system's bytes (os.fsencode). A NUL
// inside is refused (the C library would read the name up to it).
std::string path_of(const py::handle& value, const char* what = "path");
// The paths of a list, tuple or any other iterable of paths; InvalidArgument
// naming `what` for one path (a str would iterate its characters) or a value
// that is not iterable.
std::vector<std::string> paths_of(const py::handle& values, const char* what);
// A path for Python: str as os.fsdecode gives it (a name that is not UTF-8
// keeps its bytes as surrogate escapes, so it opens the same file).
py::str fs_str(const std::string& path);
py::list fs_strs(const std::vector<std::string>& paths);

// ---- options: a dict with the YAML's names, nested ({"search": {"min_gap":
// 50}}) or dotted ({"search.min_gap": 50}), values as Python numbers or text;
// `options` is None, such a dict or a YAML file's path, `kwargs` set on top.
// Validated (DetectorOptions::check).
lsgd::DetectorOptions make_options(const py::object& options, const py::kwargs& kwargs);

// Every option as {"search.min_gap": "50", ...}, in the YAML's order, as text
// that reads back equal.
py::dict options_dict(const lsgd::DetectorOptions& o);

// ---- images: numpy uint8 arrays, H x W (gray), H x W x 3 (BGR), H x W x 4 (BGRA)

// The image's pixels, checked (type, shape, size) before anything is copied;
// an array whose rows are not contiguous is copied into `a` first (the view
// points into `a`, which must outlive it).
lsgd::ImageView image_view(py::array& a);

// A copy of the image as a uint8 array (H x W, or H x W x channels).
py::array mat_to_array(const cv::Mat& m);

}  // namespace lsgd::python
