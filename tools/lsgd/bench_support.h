// Pieces of `lsgd bench` that do not run the detector: the machine
// description, peak memory, per-stage statistics, the query-growth table and
// the timer of OpenCV's own SLIC (cv::ximgproc) used as the reference.
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cv {
class Mat;
}

namespace lsgd::cli::bench {

// Where the numbers were measured.
struct Machine {
  std::string cpu_model;                // /proc/cpuinfo "model name"; "unknown" when absent
  unsigned logical_cores = 0;           // std::thread::hardware_concurrency()
  std::vector<std::string> simd_flags;  // of sse4_2 avx avx2 fma avx512f avx512bw: those present
  std::string compiler;                 // e.g. "GCC 12.2.0"
  std::string build_type;               // CMake build type of this binary, e.g. "Release"
  bool assertions = false;              // built without NDEBUG
  std::string opencv_version;           // CV_VERSION
};
Machine describe_machine();
nlohmann::json to_json(const Machine& machine);
// One line: "CPU, N logical cores (avx2 ...), GCC x, Release, OpenCV 4.6.0".
std::string summary(const Machine& machine);

// Peak resident set size of this process so far, bytes (getrusage ru_maxrss).
std::int64_t peak_rss_bytes();

// 1, 5 and 15 minute load averages (/proc/loadavg); empty when unreadable.
// Above the number of cores, other processes share ours and wall-clock times
// grow; this thread's CPU time (Stopwatch::Elapsed::cpu_ms) much less so.
std::vector<double> load_average();

// Wall-clock and this thread's CPU time since construction.
struct Elapsed {
  double wall_ms = 0;
  double cpu_ms = 0;  // CLOCK_THREAD_CPUTIME_ID
};
class Stopwatch {
 public:
  Stopwatch();
  Elapsed elapsed() const;

 private:
  std::int64_t wall_ns_;
  std::int64_t cpu_ns_;
};

// Median and 95th percentile (nearest rank, as eval::percentile) of samples.
struct Spread {
  double median = 0;
  double p95 = 0;
};
Spread spread(const std::vector<double>& samples);

// Query time against the number of stored frames: the measured frames cut into
// consecutive blocks. In exhaustive mode the query of frame i scans the frames
// j < i - min_gap, max(0, i - min_gap) * bytes_per_frame bytes.
struct GrowthRow {
  std::int64_t first_frame = 0;  // frame ids of the block, inclusive
  std::int64_t last_frame = 0;
  std::int64_t stored_frames = 0;  // N: frames stored when the block's middle frame was queried
  double query_ms_median = 0;
  double scanned_bytes = 0;  // exhaustive: bytes scanned by the middle frame's query; else 0
  double gb_per_s = 0;       // exhaustive: bytes scanned in the block / its query time; else 0
};
// query_ms[k] is the query time of frame first_frame + k.
std::vector<GrowthRow> query_growth(const std::vector<double>& query_ms, std::int64_t first_frame,
                                    std::int64_t block, bool exhaustive, std::int64_t min_gap,
                                    std::size_t bytes_per_frame);

// OpenCV's SLIC seeds a round(W / r) x round(H / r) grid for region size r
// (ximgproc slic.cpp, GetChSeedsS). These pick r so that grid holds as close
// as possible to `cells` superpixels: the r in [1, min(W, H)] nearest to
// sqrt(W * H / cells) among those whose count is closest to `cells`.
int slic_seed_count(int width, int height, int region_size);
int slic_region_size(int width, int height, int cells);

// Times cv::ximgproc::createSuperpixelSLIC(gray, SLIC, region_size, ruler)
// + iterate(iterations) + getLabels: segmentation only, no descriptor.
class OpenCvSlic {
 public:
  // False when lsgd was built without opencv_ximgproc; reason() says why.
  static bool available();
  static const char* unavailable_reason();

  OpenCvSlic(int width, int height, int cells, int iterations);
  ~OpenCvSlic();
  // Segments the 8-bit gray frame and returns the time it took.
  Elapsed time(const cv::Mat& gray);
  int region_size() const { return region_size_; }
  int iterations() const { return iterations_; }
  float ruler() const { return 10.0f; }             // OpenCV's default compactness
  int superpixels() const { return superpixels_; }  // as OpenCV reported it on the last frame

 private:
  int region_size_;
  int iterations_;
  int superpixels_ = 0;
  std::unique_ptr<cv::Mat> labels_;
};

}  // namespace lsgd::cli::bench
