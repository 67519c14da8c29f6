// A frame's Result and its parts: the candidates and their evidence, the
// geometric stage's model, the verification stages' verdicts, the timings and
// the LoopStatus. Result itself is bound after the Descriptor (lsgd_module.cc).
#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "bindings.h"
#include "lsgd/detector.h"
#include "lsgd/options.h"

namespace lsgd::python {

namespace py = pybind11;

namespace {

void bind_candidate_parts(py::module_& m) {
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
}

void bind_geometry(py::module_& m) {
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
}

void bind_verdicts(py::module_& m) {
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
}

void bind_status(py::module_& m) {
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
  // pickle rebuilds a value by its number, never through __new__ (lsgd_module.cc).
  status.attr("__reduce__") = py::cpp_function(
      [status](lsgd::LoopStatus s) { return py::make_tuple(status, py::make_tuple(static_cast<int>(s))); },
      py::is_method(status));
}

}  // namespace

void bind_result_parts(py::module_& m) {
  bind_candidate_parts(m);
  bind_geometry(m);
  bind_verdicts(m);
  bind_status(m);
}

void bind_result(py::module_& m) {
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
}

}  // namespace lsgd::python
