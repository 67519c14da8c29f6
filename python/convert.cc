// The conversions the binders share (convert.h).
#include "convert.h"

#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/io/config.h"

namespace lsgd::python {

std::string path_of(const py::handle& value, const char* what) {
  const py::module_ os = py::module_::import("os");
  py::object text;
  try {
    // The file system's bytes (os.fsencode): a name that is not UTF-8 (a
    // bytes path, a str with surrogate escapes) is the file it names, not
    // pybind11's bare "Unable to cast" on its way to a std::string.
    text = os.attr("fsencode")(os.attr("fspath")(value));
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

py::str fs_str(const std::string& path) {
  return py::module_::import("os").attr("fsdecode")(py::bytes(path));
}

py::list fs_strs(const std::vector<std::string>& paths) {
  py::list out;
  for (const std::string& p : paths) out.append(fs_str(p));
  return out;
}

std::vector<std::string> paths_of(const py::handle& values, const char* what) {
  const py::module_ os = py::module_::import("os");
  if (py::isinstance<py::str>(values) || py::isinstance<py::bytes>(values) ||
      py::isinstance(values, os.attr("PathLike"))) {
    throw lsgd::InvalidArgument(std::string(what) + ": one path (" + path_of(values, what) +
                                "), where a list of paths is expected");
  }
  py::iterator it;
  try {
    it = py::iter(values);
  } catch (const py::error_already_set&) {
    throw lsgd::InvalidArgument(std::string(what) + ": " + std::string(py::str(py::type::of(values).attr("__name__"))) +
                                " is not a list of paths");
  }
  std::vector<std::string> out;
  for (; it != py::iterator::sentinel(); ++it) out.push_back(path_of(*it, what));
  return out;
}

namespace {

// Python text as bytes: a str that is not valid UTF-8 (lone surrogates, as
// os.fsdecode makes them) keeps its bytes (surrogateescape), so the library
// refuses it naming the option instead of pybind11's bare "Unable to cast".
std::string text_of(const py::handle& value) {
  if (py::isinstance<py::bytes>(value)) return value.cast<std::string>();
  const py::object encoded = py::str(value).attr("encode")("utf-8", "surrogateescape");
  return encoded.cast<std::string>();
}

bool is_option_key(const std::string& key) {
  for (const auto& f : lsgd::DetectorOptions::fields()) {
    if (f.name == key) return true;
  }
  return false;
}

std::string option_value_text(const std::string& key, const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) {
    throw lsgd::InvalidArgument("option " + key + ": the value is a bool; options take numbers or names");
  }
  if (py::isinstance<py::float_>(value)) {
    return lsgd::format_real(value.cast<double>());
  }
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    if (key != "verification.stages") {  // the one option that is a list of names
      throw lsgd::InvalidArgument("option " + key + ": the value is a list; only verification.stages "
                                  "takes a list (of stage names)");
    }
    std::string text;
    for (const py::handle& item : value) text += (text.empty() ? "" : ",") + text_of(item);
    return text.empty() ? "none" : text;
  }
  return text_of(value);
}

// Option keys are a few names deep ("verification.temporal.place_cut"): a
// dict nested deeper is not options (and one that holds itself would recurse
// until the stack ends).
constexpr int kMaxOptionDepth = 16;

// `given`: the keys set so far from this dict, with their values: a key
// given twice ({"search": {"min_gap": 5}, "search.min_gap": 7}) is refused.
void set_options(lsgd::DetectorOptions& options, const py::dict& values, const std::string& prefix,
                 std::map<std::string, std::string>& given, int depth) {
  for (const auto& [k, v] : values) {
    const std::string key = prefix + text_of(k);
    if (py::isinstance<py::dict>(v) && is_option_key(key)) {  // {} was taken as a section, and ignored
      throw lsgd::InvalidArgument("option " + key + ": the value is a dict; it takes a number or a name");
    }
    if (py::isinstance<py::dict>(v)) {
      if (depth + 1 >= kMaxOptionDepth) {
        throw lsgd::InvalidArgument("options nested more than " + std::to_string(kMaxOptionDepth) +
                                    " dicts deep (at '" + key.substr(0, 200) +
                                    "'): option keys are a few names long");
      }
      set_options(options, v.cast<py::dict>(), key + ".", given, depth + 1);
      continue;
    }
    const std::string text = option_value_text(key, v);
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
  set_options(options, values, "", given, 0);
}

}  // namespace

lsgd::DetectorOptions make_options(const py::object& options, const py::kwargs& kwargs) {
  lsgd::DetectorOptions o;
  if (!options.is_none()) {
    if (py::isinstance<py::dict>(options)) {
      set_options(o, options.cast<py::dict>());
    } else if (py::isinstance<py::str>(options) || py::isinstance<py::bytes>(options) ||
               py::hasattr(options, "__fspath__")) {
      o = lsgd::io::load_config(path_of(options, "options"));  // a YAML file
    } else {
      // Not "is not a path": a dict of options is what most callers give
      // (lsgd.options(detector) was told only of paths).
      throw lsgd::InvalidArgument("options: " + std::string(py::str(py::type::of(options).attr("__name__"))) +
                                  " is neither a dict of options ({'search.mode': 'nodes'}) nor the path of a "
                                  "YAML config (str, bytes or os.PathLike)");
    }
  }
  set_options(o, kwargs);
  o.check();
  return o;
}

py::dict options_dict(const lsgd::DetectorOptions& o) {
  py::dict out;
  for (const auto& f : lsgd::DetectorOptions::fields()) out[py::str(f.name)] = f.text(o);
  return out;
}

namespace {

// Each row's pixels packed (a dimension of size 1 may have any stride: numpy
// calls such arrays contiguous whatever it holds there).
bool rows_dense(const py::array& a) {
  if (a.ndim() < 2) return false;
  const py::ssize_t channels = a.ndim() == 3 ? a.shape(2) : 1;
  return (a.ndim() == 2 || a.shape(2) == 1 || a.strides(2) == 1) &&
         (a.shape(1) == 1 || a.strides(1) == channels) &&
         (a.shape(0) == 1 || a.strides(0) >= a.shape(1) * channels);
}

}  // namespace

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

}  // namespace lsgd::python
