// The Python module lsgd._lsgd (pybind11): the detector, the place
// database, sequences, ground truth and the strict metrics, for
// /usr/bin/python3 with numpy. lsgd/__init__.py re-exports it; README,
// "Python", shows how to use it. Each area's bindings are in its own
// bind_*.cc (bindings.h); the conversions they share in convert.cc.
#include <pybind11/pybind11.h>

#include "bindings.h"
#include "lsgd/version.h"

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
}
