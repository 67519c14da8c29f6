// lsgd.Error and its kinds (InvalidArgument, IoError, FormatError), each
// also a standard Python exception, and the translation of the library's
// exceptions into them.
#include <pybind11/pybind11.h>

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
}

}  // namespace lsgd::python
