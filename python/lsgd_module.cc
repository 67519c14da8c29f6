// The Python module lsgd._lsgd (pybind11): the detector, the place
// database, sequences, ground truth and the strict metrics, for
// /usr/bin/python3 with numpy. lsgd/__init__.py re-exports it; README,
// "Python", shows how to use it. Each area's bindings are in its own
// bind_*.cc (bindings.h); the conversions they share in convert.cc.
#include <pybind11/pybind11.h>

#include <stdexcept>
#include <string>

#include "bindings.h"
#include "lsgd/version.h"

namespace py = pybind11;

namespace {

// An instance made by `lsgd.X.__new__(lsgd.X)` (or object.__new__) without
// __init__ has no C++ object: pybind11 allocates one uninitialised the first
// time a method takes it, so a method read garbage or crashed the
// interpreter (Detector.nodes, Database.__repr__, GroundTruth.queries,
// Result.geometry: issue 35). Every class of the module gets its own tp_new
// (the same pybind11 allocation under another address): calling X(...) or a
// Python subclass works as before, while CPython's __new__ wrapper refuses a
// bare __new__ with a TypeError ("... is not safe, use X.__new__()"), since
// the type's tp_new is no longer the base's. pickle therefore cannot rebuild
// through __new__: a class that pickles defines __reduce__ (checked here).
newfunc pybind11_new = nullptr;

PyObject* constructed_new(PyTypeObject* type, PyObject* args, PyObject* kwds) {
  return pybind11_new(type, args, kwds);
}

void refuse_bare_new(py::module_& m) {
  pybind11_new = reinterpret_cast<PyTypeObject*>(py::detail::get_internals().instance_base)->tp_new;
  for (const auto item : m.attr("__dict__").cast<py::dict>()) {
    if (!PyType_Check(item.second.ptr())) continue;
    auto* type = reinterpret_cast<PyTypeObject*>(item.second.ptr());
    if (type->tp_new != pybind11_new) continue;  // exceptions, not a pybind11 class
    const py::dict own = py::reinterpret_borrow<py::dict>(type->tp_dict);
    if (py::hasattr(item.second, "__setstate__") && !own.contains("__reduce__")) {
      throw std::logic_error(std::string("lsgd._lsgd.") + type->tp_name +
                             " pickles through __new__: give it a __reduce__");
    }
    type->tp_new = constructed_new;
    PyType_Modified(type);
  }
}

}  // namespace

// The binders run in this order: a signature names the types registered
// before it, so the order is part of the API.
PYBIND11_MODULE(_lsgd, m) {
  m.doc() = "lsgd: training-free visual loop closure detection (LSGDDN-LCD)";
  m.attr("__version__") = lsgd::version();
  m.attr("__commit__") = lsgd::commit();

  lsgd::python::bind_errors(m);
  lsgd::python::bind_result_parts(m);
  lsgd::python::bind_descriptor(m);
  lsgd::python::bind_result(m);
  lsgd::python::bind_detector(m);
  lsgd::python::bind_io(m);
  lsgd::python::bind_eval(m);
  refuse_bare_new(m);
}
