// The binders of the Python module lsgd._lsgd, one per area of the library.
// lsgd_module.cc calls them in this order: a binding's signature names the
// Python types registered before it, so the order is part of the API.
#pragma once

// Every binder sees the same type casters (std::vector and std::optional as
// Python lists and None, numpy arrays): one type converts alike everywhere.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

namespace lsgd::python {

void bind_errors(pybind11::module_& m);        // bind_errors.cc: lsgd.Error and its kinds
void bind_result_parts(pybind11::module_& m);  // bind_result.cc: Candidate ... LoopStatus
void bind_descriptor(pybind11::module_& m);    // bind_descriptor.cc: Descriptor, similarity, match
void bind_result(pybind11::module_& m);        // bind_result.cc: Result
void bind_detector(pybind11::module_& m);      // bind_detector.cc: default_options, options, Detector
void bind_io(pybind11::module_& m);            // bind_io.cc: Database ... read_image, open_sequence
void bind_eval(pybind11::module_& m);          // bind_eval.cc: GroundTruth ... evaluate_detections

}  // namespace lsgd::python
