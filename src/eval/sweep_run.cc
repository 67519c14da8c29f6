// Running a sweep (include/lsgd/eval/sweep.h): the datasets opened before
// any run, the grid's cells, one cell through the frame loop of every
// command, and the cells on several threads. `lsgd sweep` adds its progress
// bar, messages and tables around these.
#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>

#include "internal/check.h"
#include "lsgd/error.h"
#include "lsgd/eval/sweep.h"

namespace lsgd::eval {

SweepData open_sweep_dataset(const SweepDataset& spec) {
  Dataset opened = open_dataset(spec.sequence, spec.sequence_options, spec.ground_truth, spec.gt_options);
  SweepData d{spec, sequence_source(opened.frames), std::move(opened.gt), 0,
              std::move(opened.all)};
  for (std::int64_t q = 0; q < d.gt.frames(); ++q) d.positives += d.gt.has_loop(q, spec.min_gap);
  return d;
}

std::vector<SweepCell> sweep_cells(const std::vector<SweepData>& datasets,
                                   const std::vector<SweepPoint>& points,
                                   const std::vector<std::string>& keys) {
  for (std::size_t i = 0; i < datasets.size(); ++i) {
    for (std::size_t k = 0; k < i; ++k) {
      if (datasets[k].spec.name == datasets[i].spec.name) {
        internal::throw_invalid("sweep datasets: the name '", datasets[i].spec.name, "' is used twice");
      }
    }
  }
  std::vector<SweepCell> cells;
  const std::size_t total = datasets.size() * points.size();
  for (const SweepData& d : datasets) {
    for (const SweepPoint& p : points) {
      SweepCell cell{&d, &p, p.options, d.spec.name, &p == &points.front()};
      for (std::size_t k = 0; k < keys.size() && k < p.values.size(); ++k) {
        cell.label += " " + keys[k] + "=" + p.values[k];
      }
      cell.label = internal::concat("[", cells.size() + 1, "/", total, "] ", cell.label);
      cell.options.search.min_gap = d.spec.min_gap;
      try {
        cell.options.check();
      } catch (const InvalidArgument& e) {
        internal::throw_invalid(cell.label, ": ", e.what());
      }
      cells.push_back(std::move(cell));
    }
  }
  return cells;
}

SweepRow run_sweep_cell(const SweepCell& cell, bool strict, const FrameCallback& on_frame,
                        const SkipCallback& on_skip) {
  Detector detector(cell.options);
  RunOptions options;
  options.skip_bad_frames = !strict;
  std::int64_t skipped = 0;
  std::string first_error;
  const std::vector<FrameRecord> records = run_detector(
      detector, cell.dataset->source, on_frame, options,
      [&](std::int64_t frame, const std::string& name, const std::string& error) {
        if (first_error.empty()) first_error = error;
        ++skipped;
        if (on_skip) on_skip(frame, name, error);
      });
  if (detector.size() == 0) {
    throw Error(internal::concat("no frame was processed: all ", skipped,
                                 " images were skipped (the first: ", first_error, ")"));
  }
  return {evaluate(records, cell.dataset->gt, cell.options.search.min_gap), detector.nodes(),
          detector.bytes_per_frame(), skipped, true};
}

void run_sweep(const std::vector<SweepCell>& cells, int jobs,
               const std::function<void(std::size_t, const SweepRow&)>& on_row,
               const SweepCellRunner& run_cell, bool strict) {
  if (jobs < 1) internal::throw_invalid("sweep jobs = ", jobs, " must be at least 1");
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex mutex;  // on_row and error, one at a time
  const auto worker = [&] {
    for (std::size_t i; !failed && (i = next++) < cells.size();) {
      try {
        const SweepRow row = run_cell ? run_cell(cells[i]) : run_sweep_cell(cells[i], strict);
        const std::lock_guard<std::mutex> lock(mutex);
        if (on_row) on_row(i, row);
      } catch (const std::exception& e) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (!failed.exchange(true)) {
          error = std::make_exception_ptr(Error(cells[i].label + ": " + e.what()));
        }
      }
    }
  };
  if (jobs == 1) {
    worker();
  } else {
    std::vector<std::thread> threads;
    const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(jobs), cells.size());
    // A thread that cannot be started (its stack does not fit an address-space
    // limit, too many threads) leaves the cells to those that could: the
    // rows are the same on any number of jobs. None at all: this thread
    // runs them. (Unwinding with joinable threads would end the process.)
    try {
      for (std::size_t t = 0; t < n; ++t) threads.emplace_back(worker);
    } catch (const std::system_error&) {
    }
    if (threads.empty()) worker();
    for (std::thread& t : threads) t.join();
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace lsgd::eval
