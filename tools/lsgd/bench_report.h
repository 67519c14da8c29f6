// What `lsgd bench` measured, and how it is printed and written as JSON.
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "bench_support.h"
#include "lsgd/detector.h"

namespace lsgd::cli::bench {

// The generated sequence and the statistics windows.
struct Setup {
  std::int64_t frames = 4541;  // KITTI 00
  int width = 1241;            // KITTI
  int height = 376;
  std::int64_t warmup = 20;          // first frames left out of the statistics
  std::int64_t opencv_frames = 100;  // frames also segmented by OpenCV's SLIC
  std::int64_t block = 500;          // frames per row of the query-growth table
  std::uint64_t seed = 1;
};

// Milliseconds of every measured frame (after the warm-up), per stage of
// Result::timings, plus this thread's CPU time over Detector::process and the
// untimed preparation of the frame.
struct Samples {
  std::vector<double> convert, segment, describe, query, verify, total, segment_describe;
  std::vector<double> total_cpu;
  std::vector<double> render, cvtcolor;
};

// On every `every`-th measured frame: OpenCV's SLIC and, for a like-for-like
// pair (same call pattern, same clocks), a standalone lsgd::Segmenter +
// describe with the detector's options, in alternating order.
struct SlicSamples {
  std::unique_ptr<OpenCvSlic> slic;  // null: not timed, `reason` says why
  std::string reason;
  std::int64_t every = 0;
  std::vector<double> ms, cpu_ms;                         // OpenCV SLIC
  std::vector<double> segment, segment_describe;          // ours, wall
  std::vector<double> segment_cpu, segment_describe_cpu;  // ours, CPU
};

struct RunData {
  Samples samples;
  SlicSamples slic;
  std::vector<GrowthRow> growth;
  std::int64_t peak_rss_before_bytes = 0;  // before the first frame
  std::vector<double> load_start, load_end;
  std::int64_t nodes = 0;
  bool scores_every_frame = false;  // the search mode scans every frame (exhaustive)
  std::size_t bytes_per_frame = 0;
  std::int64_t stored = 0;
  GridSize grid;
  Machine machine;
};

nlohmann::json to_json(const Setup& setup, const DetectorOptions& options, const RunData& data);
void print_report(const Setup& setup, const DetectorOptions& options, const RunData& data,
                  std::ostream& out);

}  // namespace lsgd::cli::bench
