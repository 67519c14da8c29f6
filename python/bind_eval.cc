// The evaluation layer: loop ground truth, the strict metrics
// (docs/evaluation.md) and scoring a detector's Results or a detections CSV.
#include <cstdint>
#include <string>
#include <vector>

#include "bindings.h"
#include "convert.h"
#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "lsgd/eval/detections.h"
#include "lsgd/eval/groundtruth.h"
#include "lsgd/eval/gt_formats.h"
#include "lsgd/eval/metrics.h"
#include "lsgd/eval/runner.h"
#include "lsgd/eval/sweep.h"

namespace lsgd::python {

namespace {

lsgd::eval::Metrics evaluate_results(const std::vector<lsgd::Result>& results, const lsgd::eval::GroundTruth& gt,
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
  // One record per Result; evaluate() counts every other frame of the ground
  // truth as a query that reported nothing (missed when it is a revisit).
  std::vector<lsgd::eval::FrameRecord> records;
  records.reserve(results.size());
  for (const lsgd::Result& r : results) {
    lsgd::eval::FrameRecord rec = lsgd::eval::record_of(r);
    rec.frame = r.id;
    rec.reported.frame = id(rec.reported.frame);
    if (rec.ranking) rec.ranking->best.frame = id(rec.ranking->best.frame);
    for (lsgd::Candidate& c : rec.candidates) c.frame = id(c.frame);
    records.push_back(std::move(rec));
  }
  return lsgd::eval::evaluate(records, gt, min_gap);
}

void bind_groundtruth(py::module_& m) {
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
}

void bind_metrics(py::module_& m) {
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
}

// lsgd sweep's grid from Python: the same library calls (eval/sweep.h), a
// row a cell, in grid order.
py::list run_sweep(const std::vector<std::string>& datasets, const std::vector<std::string>& sets,
                   const py::object& options, int jobs, bool strict) {
  const lsgd::DetectorOptions base = make_options(options, py::kwargs());
  std::vector<lsgd::eval::SweepAxis> axes;
  std::vector<std::string> keys;
  for (const std::string& spec : sets) {
    axes.push_back(lsgd::eval::parse_sweep_axis(spec));
    keys.push_back(axes.back().key);
  }
  const std::vector<lsgd::eval::SweepPoint> points = lsgd::eval::expand_sweep(axes, base);
  std::vector<lsgd::eval::SweepData> data;
  for (const std::string& spec : datasets) {
    data.push_back(lsgd::eval::open_sweep_dataset(lsgd::eval::parse_dataset_spec(spec)));
  }
  const std::vector<lsgd::eval::SweepCell> cells = lsgd::eval::sweep_cells(data, points, keys);
  std::vector<lsgd::eval::SweepRow> rows(cells.size());
  {
    py::gil_scoped_release release;
    lsgd::eval::run_sweep(
        cells, jobs, [&rows](std::size_t i, const lsgd::eval::SweepRow& row) { rows[i] = row; }, {},
        strict);
  }
  py::list out;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    py::dict values;
    for (std::size_t k = 0; k < keys.size(); ++k) values[py::str(keys[k])] = cells[i].point->values[k];
    py::dict row;
    row["dataset"] = cells[i].dataset->spec.name;
    row["values"] = values;
    row["metrics"] = rows[i].metrics;
    row["nodes"] = rows[i].nodes;
    row["bytes_per_frame"] = rows[i].bytes_per_frame;
    row["skipped_frames"] = rows[i].skipped;
    out.append(row);
  }
  return out;
}

}  // namespace

void bind_eval(py::module_& m) {
  bind_groundtruth(m);
  bind_metrics(m);
  m.def("evaluate", &evaluate_results, py::arg("results"), py::arg("groundtruth"), py::arg("min_gap"),
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
  m.def("sweep", &run_sweep, py::arg("datasets"), py::arg("sets") = std::vector<std::string>(),
        py::arg("options") = py::none(), py::arg("jobs") = 1, py::arg("strict") = false,
        "Runs lsgd sweep's grid: every configuration of `sets` (\"KEY=VALUES\", as --set) on "
        "every dataset (\"NAME=SEQUENCE,GT,MIN_GAP\" or \"NAME=DIR,MIN_GAP\", as --dataset), "
        "on top of `options` (a dict or a YAML path), on `jobs` threads; bad frames are skipped "
        "unless strict. A list of rows in grid order: dataset, values, metrics, nodes, "
        "bytes_per_frame, skipped_frames. Everything is checked before the first run.");
}

}  // namespace lsgd::python
