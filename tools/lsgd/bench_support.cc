#include "bench_support.h"

#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/core/version.hpp>
#include <sstream>
#include <thread>
#ifdef LSGD_HAVE_XIMGPROC
#include <opencv2/ximgproc/slic.hpp>
#endif

#include "lsgd/error.h"
#include "lsgd/eval/metrics.h"

#ifndef LSGD_BUILD_TYPE
#define LSGD_BUILD_TYPE ""
#endif

namespace lsgd::cli::bench {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  const auto e = s.find_last_not_of(" \t\r\n");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

// Reads the first processor's "model name" and "flags" lines.
void read_cpuinfo(Machine& m) {
  std::ifstream in("/proc/cpuinfo");
  std::string line, flags;
  while (std::getline(in, line) && (m.cpu_model.empty() || flags.empty())) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = trim(line.substr(0, colon));
    if (key == "model name" && m.cpu_model.empty()) m.cpu_model = trim(line.substr(colon + 1));
    if (key == "flags" && flags.empty()) flags = " " + trim(line.substr(colon + 1)) + " ";
  }
  if (m.cpu_model.empty()) m.cpu_model = "unknown";
  for (const char* f : {"sse4_2", "avx", "avx2", "fma", "avx512f", "avx512bw"}) {
    if (flags.find(std::string(" ") + f + " ") != std::string::npos) m.simd_flags.push_back(f);
  }
}

std::string compiler() {
#if defined(__clang__)
  return std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
  return std::string("GCC ") + __VERSION__;
#else
  return "unknown";
#endif
}

}  // namespace

Machine describe_machine() {
  Machine m;
  read_cpuinfo(m);
  m.logical_cores = std::thread::hardware_concurrency();
  m.compiler = compiler();
  m.build_type = *LSGD_BUILD_TYPE ? LSGD_BUILD_TYPE : "(none)";
#ifdef NDEBUG
  m.assertions = false;
#else
  m.assertions = true;
#endif
  m.opencv_version = CV_VERSION;
  return m;
}

nlohmann::json to_json(const Machine& m) {
  return {{"cpu_model", m.cpu_model},          {"logical_cores", m.logical_cores},
          {"simd_flags", m.simd_flags},        {"compiler", m.compiler},
          {"build_type", m.build_type},        {"assertions", m.assertions},
          {"opencv_version", m.opencv_version}};
}

std::string summary(const Machine& m) {
  std::ostringstream s;
  s << m.cpu_model << ", " << m.logical_cores << " logical cores";
  if (!m.simd_flags.empty()) {
    s << " (";
    for (std::size_t i = 0; i < m.simd_flags.size(); ++i) s << (i ? " " : "") << m.simd_flags[i];
    s << ")";
  }
  s << ", " << m.compiler << ", " << m.build_type << (m.assertions ? " with assertions" : "")
    << ", OpenCV " << m.opencv_version;
  return s.str();
}

std::int64_t peak_rss_bytes() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return static_cast<std::int64_t>(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

std::vector<double> load_average() {
  std::ifstream in("/proc/loadavg");
  std::vector<double> load(3);
  if (!(in >> load[0] >> load[1] >> load[2])) return {};
  return load;
}

namespace {
std::int64_t clock_ns(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}
}  // namespace

Stopwatch::Stopwatch()
    : wall_ns_(clock_ns(CLOCK_MONOTONIC)), cpu_ns_(clock_ns(CLOCK_THREAD_CPUTIME_ID)) {}

Elapsed Stopwatch::elapsed() const {
  return {(clock_ns(CLOCK_MONOTONIC) - wall_ns_) * 1e-6,
          (clock_ns(CLOCK_THREAD_CPUTIME_ID) - cpu_ns_) * 1e-6};
}

Spread spread(const std::vector<double>& samples) {
  return {eval::percentile(samples, 0.5), eval::percentile(samples, 0.95)};
}

std::vector<GrowthRow> query_growth(const std::vector<double>& query_ms, std::int64_t first_frame,
                                    std::int64_t block, bool exhaustive, std::int64_t min_gap,
                                    std::size_t bytes_per_frame) {
  std::vector<GrowthRow> rows;
  const auto n = static_cast<std::int64_t>(query_ms.size());
  const auto scanned = [&](std::int64_t frame) {
    return static_cast<double>(std::max<std::int64_t>(0, frame - min_gap)) *
           static_cast<double>(bytes_per_frame);
  };
  for (std::int64_t begin = 0; begin < n; begin += block) {
    const std::int64_t end = std::min(n, begin + block);
    const std::vector<double> ms(query_ms.begin() + begin, query_ms.begin() + end);
    GrowthRow row;
    row.first_frame = first_frame + begin;
    row.last_frame = first_frame + end - 1;
    row.stored_frames = first_frame + (begin + end - 1) / 2;  // frame i is queried with i stored
    row.query_ms_median = eval::percentile(ms, 0.5);
    if (exhaustive) {
      row.scanned_bytes = scanned(row.stored_frames);
      double bytes = 0, total_ms = 0;
      for (std::int64_t k = begin; k < end; ++k) {
        bytes += scanned(first_frame + k);
        total_ms += query_ms[static_cast<std::size_t>(k)];
      }
      row.gb_per_s = total_ms > 0 ? bytes / (total_ms * 1e-3) * 1e-9 : 0.0;
    }
    rows.push_back(row);
  }
  return rows;
}

int slic_seed_count(int width, int height, int region_size) {
  // The same float arithmetic as OpenCV: int(0.5f + float(W) / float(r)).
  const int xs =
      static_cast<int>(0.5f + static_cast<float>(width) / static_cast<float>(region_size));
  const int ys =
      static_cast<int>(0.5f + static_cast<float>(height) / static_cast<float>(region_size));
  return xs * ys;
}

int slic_region_size(int width, int height, int cells) {
  if (width < 1 || height < 1 || cells < 1) {
    throw InvalidArgument("slic_region_size: width, height and cells must be positive (got " +
                          std::to_string(width) + ", " + std::to_string(height) + ", " +
                          std::to_string(cells) + ")");
  }
  const double ideal = std::sqrt(static_cast<double>(width) * height / cells);
  int best = 1;
  std::int64_t best_error = -1;
  for (int r = 1; r <= std::min(width, height); ++r) {
    const std::int64_t error = std::abs(slic_seed_count(width, height, r) - cells);
    if (best_error < 0 || error < best_error ||
        (error == best_error && std::abs(r - ideal) < std::abs(best - ideal))) {
      best = r;
      best_error = error;
    }
  }
  return best;
}

#ifdef LSGD_HAVE_XIMGPROC
bool OpenCvSlic::available() { return true; }
const char* OpenCvSlic::unavailable_reason() { return ""; }
#else
bool OpenCvSlic::available() { return false; }
const char* OpenCvSlic::unavailable_reason() {
  return "built without opencv_ximgproc (install libopencv-contrib-dev)";
}
#endif

OpenCvSlic::OpenCvSlic(int width, int height, int cells, int iterations)
    : region_size_(slic_region_size(width, height, cells)),
      iterations_(iterations),
      labels_(std::make_unique<cv::Mat>()) {}

OpenCvSlic::~OpenCvSlic() = default;

Elapsed OpenCvSlic::time(const cv::Mat& gray) {
#ifdef LSGD_HAVE_XIMGPROC
  const Stopwatch watch;
  const cv::Ptr<cv::ximgproc::SuperpixelSLIC> slic =
      cv::ximgproc::createSuperpixelSLIC(gray, cv::ximgproc::SLIC, region_size_, ruler());
  slic->iterate(iterations_);
  slic->getLabels(*labels_);
  const Elapsed elapsed = watch.elapsed();
  superpixels_ = slic->getNumberOfSuperpixels();
  return elapsed;
#else
  (void)gray;
  throw Error(std::string("OpenCV SLIC: ") + unavailable_reason());
#endif
}

}  // namespace lsgd::cli::bench
