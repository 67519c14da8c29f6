// The evaluation layer: loop ground truth, the strict metrics
// (docs/evaluation.md) and scoring a detector's Results or a detections CSV.
#include <cstdint>
#include <memory>
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
#include "lsgd/io/config.h"

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

// Metrics and PrPoint cross processes (lsgd.sweep(client=...)'s rows come
// from a cluster's workers) as their fields: every member, bound or not.
using lsgd::eval::Metrics;
using lsgd::eval::PrPoint;
constexpr std::int64_t Metrics::*kMetricsCounts[] = {
    &Metrics::tolerance, &Metrics::frames, &Metrics::positives, &Metrics::min_gap,
    &Metrics::declared_loops, &Metrics::declared_true, &Metrics::declared_false};
constexpr double Metrics::*kMetricsValues[] = {
    &Metrics::precision_at_decision, &Metrics::recall_at_decision,
    &Metrics::recall_at_100_precision, &Metrics::threshold_at_100_precision,
    &Metrics::precision_at_100_recall, &Metrics::average_precision,
    &Metrics::decision_recall_at_100_precision, &Metrics::decision_threshold_at_100_precision,
    &Metrics::decision_average_precision, &Metrics::recall_at_1, &Metrics::recall_at_5,
    &Metrics::recall_at_10, &Metrics::ms_per_frame_median, &Metrics::ms_per_frame_p95,
    &Metrics::ms_per_frame_mean, &Metrics::load_ms_median, &Metrics::convert_ms_median,
    &Metrics::segment_ms_median, &Metrics::describe_ms_median, &Metrics::search_ms_median,
    &Metrics::verify_ms_median, &Metrics::load_ms_p95, &Metrics::convert_ms_p95,
    &Metrics::segment_ms_p95, &Metrics::describe_ms_p95, &Metrics::search_ms_p95,
    &Metrics::verify_ms_p95, &Metrics::prt};

py::tuple point_state(const PrPoint& p) {
  return py::make_tuple(p.threshold, p.confirmed, p.precision, p.recall, p.true_positives,
                        p.false_positives);
}

PrPoint point_of_state(const py::tuple& t) {
  if (t.size() != 6) throw lsgd::InvalidArgument("PrPoint: a pickled state of 6 fields was expected");
  return {t[0].cast<double>(), t[1].cast<bool>(), t[2].cast<double>(), t[3].cast<double>(),
          t[4].cast<std::int64_t>(), t[5].cast<std::int64_t>()};
}

py::tuple metrics_state(const Metrics& m) {
  py::list counts, values, curve;
  for (const auto member : kMetricsCounts) counts.append(m.*member);
  for (const auto member : kMetricsValues) values.append(m.*member);
  for (const PrPoint& p : m.curve) curve.append(point_state(p));
  return py::make_tuple(m.protocol, counts, values, curve);
}

Metrics metrics_of_state(const py::tuple& t) {
  const auto counts = t.size() == 4 ? t[1].cast<py::list>() : py::list();
  const auto values = t.size() == 4 ? t[2].cast<py::list>() : py::list();
  if (t.size() != 4 || counts.size() != std::size(kMetricsCounts) ||
      values.size() != std::size(kMetricsValues)) {
    throw lsgd::InvalidArgument("Metrics: the pickled state is of another lsgd version's Metrics");
  }
  Metrics m;
  m.protocol = t[0].cast<std::string>();
  for (std::size_t k = 0; k < std::size(kMetricsCounts); ++k) m.*kMetricsCounts[k] = counts[k].cast<std::int64_t>();
  for (std::size_t k = 0; k < std::size(kMetricsValues); ++k) m.*kMetricsValues[k] = values[k].cast<double>();
  for (const py::handle p : t[3].cast<py::list>()) m.curve.push_back(point_of_state(p.cast<py::tuple>()));
  return m;
}

void bind_metrics(py::module_& m) {
  py::class_<lsgd::eval::PrPoint>(m, "PrPoint")
      .def_readonly("threshold", &lsgd::eval::PrPoint::threshold)
      .def_readonly("precision", &lsgd::eval::PrPoint::precision)
      .def_readonly("recall", &lsgd::eval::PrPoint::recall)
      .def_readonly("confirmed", &lsgd::eval::PrPoint::confirmed)
      .def("__reduce__", [](const PrPoint& p) {
             return py::make_tuple(py::module_::import("lsgd._restore").attr("pr_point"), py::make_tuple(point_state(p)));
           });
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
      .def_readonly("curve", &lsgd::eval::Metrics::curve)
      .def("__reduce__", [](const Metrics& metrics) {
             return py::make_tuple(py::module_::import("lsgd._restore").attr("metrics"), py::make_tuple(metrics_state(metrics)));
           });
  // pickle rebuilds through lsgd._restore, never through __new__ (lsgd_module.cc).
  m.def("_restore_pr_point", &point_of_state, py::arg("state"));
  m.def("_restore_metrics", &metrics_of_state, py::arg("state"));
}

// lsgd sweep's grid, opened and checked: the datasets read, every point and
// cell validated, before anything runs (cells point into data and points).
struct SweepGrid {
  std::vector<std::string> keys;
  std::vector<std::string> specs;  // each dataset's spec as given, in data's order
  std::vector<lsgd::eval::SweepPoint> points;
  std::vector<lsgd::eval::SweepData> data;
  std::vector<lsgd::eval::SweepCell> cells;
};

std::unique_ptr<SweepGrid> plan_grid(const std::vector<std::string>& datasets,
                                     const std::vector<std::string>& sets, const py::object& options,
                                     int jobs) {
  if (jobs < 1) throw lsgd::InvalidArgument("sweep jobs = " + std::to_string(jobs) + " must be at least 1");
  auto grid = std::make_unique<SweepGrid>();
  const lsgd::DetectorOptions base = make_options(options, py::kwargs());
  std::vector<lsgd::eval::SweepAxis> axes;
  for (const std::string& spec : sets) {
    axes.push_back(lsgd::eval::parse_sweep_axis(spec));
    grid->keys.push_back(axes.back().key);
  }
  grid->points = lsgd::eval::expand_sweep(axes, base);
  for (const std::string& spec : datasets) {
    grid->data.push_back(lsgd::eval::open_sweep_dataset(lsgd::eval::parse_dataset_spec(spec)));
    grid->specs.push_back(spec);
  }
  grid->cells = lsgd::eval::sweep_cells(grid->data, grid->points, grid->keys);
  return grid;
}

// Cell i's dataset and values, the start of its row.
py::dict cell_row(const SweepGrid& grid, std::size_t i) {
  const lsgd::eval::SweepCell& cell = grid.cells[i];
  py::dict values;
  for (std::size_t k = 0; k < grid.keys.size(); ++k) values[py::str(grid.keys[k])] = cell.point->values[k];
  py::dict row;
  row["dataset"] = cell.dataset->spec.name;
  row["values"] = values;
  return row;
}

// The row of cell i: its dataset and values from the grid, the rest measured.
py::dict sweep_row(const SweepGrid& grid, std::size_t i, const lsgd::eval::SweepRow& measured) {
  py::dict row = cell_row(grid, i);
  row["metrics"] = measured.metrics;
  row["nodes"] = measured.nodes;
  row["bytes_per_frame"] = measured.bytes_per_frame;
  row["skipped_frames"] = measured.skipped;
  return row;
}

// lsgd sweep's grid from Python: the same library calls (eval/sweep.h), a
// row a cell, in grid order.
py::list run_sweep(const std::vector<std::string>& datasets, const std::vector<std::string>& sets,
                   const py::object& options, int jobs, bool strict) {
  const std::unique_ptr<SweepGrid> grid = plan_grid(datasets, sets, options, jobs);
  std::vector<lsgd::eval::SweepRow> rows(grid->cells.size());
  {
    py::gil_scoped_release release;
    lsgd::eval::run_sweep(
        grid->cells, jobs, [&rows](std::size_t i, const lsgd::eval::SweepRow& row) { rows[i] = row; }, {},
        strict);
  }
  py::list out;
  for (std::size_t i = 0; i < grid->cells.size(); ++i) out.append(sweep_row(*grid, i, rows[i]));
  return out;
}

// A sweep for a cluster (lsgd/_dask.py): the grid checked here, each cell as
// what a worker needs to run it alone: its dataset's spec, its whole options
// as YAML (io::to_yaml, read back equal) and its label; with the row's
// dataset and values.
py::list plan_sweep(const std::vector<std::string>& datasets, const std::vector<std::string>& sets,
                    const py::object& options, int jobs) {
  const std::unique_ptr<SweepGrid> grid = plan_grid(datasets, sets, options, jobs);
  py::list out;
  for (std::size_t i = 0; i < grid->cells.size(); ++i) {
    const lsgd::eval::SweepCell& cell = grid->cells[i];
    py::dict row = cell_row(*grid, i);
    row["dataset_spec"] =
        grid->specs[static_cast<std::size_t>(cell.dataset - grid->data.data())];
    row["options"] = lsgd::io::to_yaml(cell.options);
    row["label"] = cell.label;
    out.append(row);
  }
  return out;
}

// One cell of plan_sweep's, run where this is called (a cluster's worker):
// the dataset opened again from its spec, the options read back from their
// YAML; errors name the cell as run_sweep's do.
py::dict run_planned_cell(const std::string& dataset_spec, const std::string& options_yaml,
                          const std::string& label, bool strict) {
  lsgd::eval::SweepRow row;
  {
    py::gil_scoped_release release;
    try {
      const lsgd::eval::SweepData data =
          lsgd::eval::open_sweep_dataset(lsgd::eval::parse_dataset_spec(dataset_spec));
      lsgd::eval::SweepCell cell{&data, nullptr,
                                 lsgd::io::parse_config(options_yaml, "the options of sweep cell " + label),
                                 label, true};
      row = lsgd::eval::run_sweep_cell(cell, strict);
    } catch (const lsgd::InvalidArgument& e) {
      throw lsgd::InvalidArgument(label + ": " + e.what());
    } catch (const lsgd::IoError& e) {
      throw lsgd::IoError(label + ": " + e.what());
    } catch (const lsgd::FormatError& e) {
      throw lsgd::FormatError(label + ": " + e.what());
    } catch (const std::exception& e) {
      throw lsgd::Error(label + ": " + e.what());
    }
  }
  py::dict out;
  out["metrics"] = row.metrics;
  out["nodes"] = row.nodes;
  out["bytes_per_frame"] = row.bytes_per_frame;
  out["skipped_frames"] = row.skipped;
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
          const std::string file = path_of(path);
          const auto records = lsgd::eval::read_detections(file, gt.frames());
          const py::object warn = py::module_::import("warnings").attr("warn");
          for (const std::string& w : lsgd::eval::detections_warnings(records, gt, min_gap, file)) {
            warn(w, py::module_::import("builtins").attr("UserWarning"), 2);
          }
          return lsgd::eval::evaluate(records, gt, min_gap);
        }, py::arg("path"), py::arg("groundtruth"), py::arg("min_gap"),
        "Scores a detections CSV (query,match,score[,rank]: lsgd match, lsgd.match, another "
        "system's output) as lsgd eval --detections does, with its warnings as Python warnings "
        "(revisits without a row, matches to the query itself or a later frame).");
  m.def("sweep", &run_sweep, py::arg("datasets"), py::arg("sets") = std::vector<std::string>(),
        py::arg("options") = py::none(), py::arg("jobs") = 1, py::arg("strict") = false,
        "Runs lsgd sweep's grid: every configuration of `sets` (\"KEY=VALUES\", as --set) on "
        "every dataset (\"NAME=SEQUENCE,GT,MIN_GAP\" or \"NAME=DIR,MIN_GAP\", as --dataset), "
        "on top of `options` (a dict or a YAML path), on `jobs` threads; bad frames are skipped "
        "unless strict. A list of rows in grid order: dataset, values, metrics, nodes, "
        "bytes_per_frame, skipped_frames. Everything is checked before the first run.");
  m.def("_sweep_plan", &plan_sweep, py::arg("datasets"), py::arg("sets"), py::arg("options"),
        py::arg("jobs"),
        "sweep(client=...)'s grid, checked as sweep() checks it: a dict a cell, in grid order "
        "(dataset, values, dataset_spec, options as YAML, label).");
  m.def("_sweep_cell", &run_planned_cell, py::arg("dataset_spec"), py::arg("options"), py::arg("label"),
        py::arg("strict"),
        "Runs one cell of _sweep_plan() here: a dict of metrics, nodes, bytes_per_frame, "
        "skipped_frames.");
}

}  // namespace lsgd::python
