// lsgd.Error and its kinds (InvalidArgument, IoError, FormatError), each
// also a standard Python exception, and the translation of the library's
// exceptions into them.
#include <pybind11/pybind11.h>

#include <cstring>
#include <exception>

#include "bindings.h"
#include "lsgd/error.h"

namespace lsgd::python {

namespace py = pybind11;

void bind_errors(py::module_& m) {
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
  // A message is UTF-8 but for the bytes of a file name that is not: those
  // are kept as surrogate escapes (as os.fsdecode gives names), where
  // PyErr_SetString would leave the message empty.
  static const auto set = [](const py::handle& type, const char* what) {
    PyObject* text = PyUnicode_DecodeUTF8(what, static_cast<Py_ssize_t>(std::strlen(what)), "surrogateescape");
    if (text == nullptr) {
      PyErr_Clear();
      PyErr_SetString(type.ptr(), "(a message that could not be decoded)");
      return;
    }
    PyErr_SetObject(type.ptr(), text);
    Py_DECREF(text);
  };
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const lsgd::InvalidArgument& e) {
      set(invalid, e.what());
    } catch (const lsgd::IoError& e) {
      set(io_error, e.what());
    } catch (const lsgd::FormatError& e) {
      set(format_error, e.what());
    } catch (const lsgd::Error& e) {
      set(error, e.what());
    }
  });
}

}  // namespace lsgd::python
