#include "bench_report.h"

#include <iomanip>
#include <sstream>
#include <utility>

#include "lsgd/io/config.h"

namespace lsgd::cli::bench {
namespace {

constexpr const char* kSource =
    "synthetic street (eval::SyntheticWorld): frame i renders route frame i % 1090";
constexpr const char* kThreads =
    "OpenCV sequential (cv::setNumThreads(0)); the detector runs on the calling thread";
constexpr const char* kSlicTimed =
    "createSuperpixelSLIC + iterate + getLabels: segmentation only, no descriptor";

double median(const std::vector<double>& v) { return spread(v).median; }

// OpenCV / ours, both medians; null when OpenCV's SLIC did not run.
nlohmann::json ratio(const std::vector<double>& opencv, const std::vector<double>& ours) {
  if (opencv.empty() || ours.empty() || median(ours) <= 0) return nullptr;
  return median(opencv) / median(ours);
}

nlohmann::json median_or_null(const std::vector<double>& v) {
  return v.empty() ? nlohmann::json(nullptr) : nlohmann::json(median(v));
}

nlohmann::json p95_or_null(const std::vector<double>& v) {
  return v.empty() ? nlohmann::json(nullptr) : nlohmann::json(spread(v).p95);
}

nlohmann::json growth_json(const Setup& setup, const std::vector<GrowthRow>& growth) {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& g : growth) {
    rows.push_back({{"first_frame", g.first_frame},
                    {"last_frame", g.last_frame},
                    {"stored_frames", g.stored_frames},
                    {"query_ms_median", g.query_ms_median},
                    {"scanned_bytes", g.scanned_bytes},
                    {"gb_per_s", g.gb_per_s}});
  }
  return {{"block_frames", setup.block}, {"rows", rows}};
}

void add_slic_json(const RunData& d, nlohmann::json& j) {
  const Samples& s = d.samples;
  const SlicSamples& c = d.slic;
  j["opencv_slic_ms_median"] = median_or_null(c.ms);
  j["opencv_slic_ms_p95"] = p95_or_null(c.ms);
  j["opencv_slic_cpu_ms_median"] = median_or_null(c.cpu_ms);
  // As specified: OpenCV's median over our detector's median on every measured
  // frame. The detector's segment stage counts the histograms in its last pass
  // (segment_and_describe), so this ratio already includes the descriptor.
  j["speedup_vs_opencv_slic"] = ratio(c.ms, s.segment);
  j["speedup_vs_opencv_slic_incl_describe"] = ratio(c.ms, s.segment_describe);
  // Paired: the same frames, standalone calls, wall clock and CPU time.
  j["speedup_vs_opencv_slic_same_frames"] = ratio(c.ms, c.segment);
  j["speedup_vs_opencv_slic_cpu"] = ratio(c.cpu_ms, c.segment_cpu);
  j["speedup_vs_opencv_slic_cpu_incl_describe"] = ratio(c.cpu_ms, c.segment_describe_cpu);
  nlohmann::json slic = {{"frames", static_cast<std::int64_t>(c.ms.size())}};
  if (c.slic) {
    slic.update({{"algorithm", "SLIC"},
                 {"region_size", c.slic->region_size()},
                 {"superpixels", c.slic->superpixels()},
                 {"target_cells", d.grid.cells()},
                 {"iterations", c.slic->iterations()},
                 {"ruler", c.slic->ruler()},
                 {"every", c.every},
                 {"timed", kSlicTimed},
                 {"ours_same_frames",
                  {{"segment_ms_median", median_or_null(c.segment)},
                   {"segment_describe_ms_median", median_or_null(c.segment_describe)},
                   {"segment_cpu_ms_median", median_or_null(c.segment_cpu)},
                   {"segment_describe_cpu_ms_median", median_or_null(c.segment_describe_cpu)}}}});
  } else {
    slic["reason"] = c.reason;
  }
  j["opencv_slic"] = slic;
}

std::string fixed(double v, int precision) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << v;
  return s.str();
}

std::string megabytes(double bytes) { return fixed(bytes / 1e6, 1) + " MB"; }

std::string loads(const std::vector<double>& load) {
  return load.empty() ? std::string("unknown") : fixed(load[0], 2);
}

void print_row(std::ostream& out, const std::string& label, const std::vector<double>& wall,
               const std::vector<double>* cpu = nullptr) {
  const Spread sp = spread(wall);
  out << std::left << std::setw(44) << label << std::right << std::setw(9) << fixed(sp.median, 3)
      << std::setw(9) << fixed(sp.p95, 3);
  if (cpu) out << std::setw(11) << fixed(median(*cpu), 3);
  out << "\n";
}

void print_growth(const Setup& setup, bool exhaustive, const std::vector<GrowthRow>& growth,
                  std::ostream& out) {
  out << "\nquery time vs stored frames N (median per block of " << setup.block << " frames"
      << (exhaustive ? "; the query scans N - min_gap frames" : "") << ")\n"
      << "         N  query ms" << (exhaustive ? "   MB scanned    GB/s" : "") << "\n";
  for (const auto& g : growth) {
    out << std::setw(10) << g.stored_frames << std::setw(10) << fixed(g.query_ms_median, 3);
    if (exhaustive) {
      out << std::setw(13) << fixed(g.scanned_bytes / 1e6, 1) << std::setw(8)
          << fixed(g.gb_per_s, 2);
    }
    out << "\n";
  }
}

void print_slic(const RunData& d, std::ostream& out) {
  const SlicSamples& c = d.slic;
  if (!c.slic || c.ms.empty()) {
    out << "OpenCV SLIC: not timed: " << c.reason << "\n";
    return;
  }
  const Samples& s = d.samples;
  out << "OpenCV SLIC: cv::ximgproc::createSuperpixelSLIC(gray, SLIC, region_size "
      << c.slic->region_size() << ", ruler " << c.slic->ruler() << ") + iterate("
      << c.slic->iterations() << ") + getLabels; " << c.slic->superpixels()
      << " superpixels for our " << d.grid.cells() << " cells\n"
      << "on " << c.ms.size() << " frames (one measured frame in " << c.every
      << "), each also segmented by a standalone lsgd::Segmenter, order alternating\n"
      << std::left << std::setw(44) << "ms" << std::right << std::setw(9) << "median"
      << std::setw(9) << "p95" << std::setw(11) << "CPU median"
      << "\n";
  print_row(out, "  OpenCV SLIC (segmentation only)", c.ms, &c.cpu_ms);
  print_row(out, "  lsgd segment", c.segment, &c.segment_cpu);
  print_row(out, "  lsgd segment + describe", c.segment_describe, &c.segment_describe_cpu);
  out << "speedup = OpenCV SLIC median / ours: segment "
      << fixed(median(c.ms) / median(c.segment), 2) << "x (CPU time "
      << fixed(median(c.cpu_ms) / median(c.segment_cpu), 2) << "x), segment + describe "
      << fixed(median(c.ms) / median(c.segment_describe), 2) << "x (CPU time "
      << fixed(median(c.cpu_ms) / median(c.segment_describe_cpu), 2) << "x)\n"
      << "  against the detector's median over all measured frames (segment stage, histograms "
         "included): "
      << fixed(median(c.ms) / median(s.segment_describe), 2) << "x\n";
}

}  // namespace

nlohmann::json to_json(const Setup& setup, const DetectorOptions& o, const RunData& d) {
  const Samples& s = d.samples;
  nlohmann::json j;
  j["frames"] = setup.frames;
  j["warmup_frames"] = setup.warmup;
  j["measured_frames"] = static_cast<std::int64_t>(s.total.size());
  j["width"] = setup.width;
  j["height"] = setup.height;
  j["seed"] = setup.seed;
  j["source"] = kSource;
  j["mode"] = o.search.mode;
  j["verify"] = verification_stages(o.verification);
  j["grid"] = {{"rows", d.grid.rows}, {"cols", d.grid.cols}, {"cells", d.grid.cells()}};
  const std::pair<const char*, const std::vector<double>*> stages[] = {
      {"convert", &s.convert},     {"segment", &s.segment},
      {"describe", &s.describe},   {"query", &s.query},
      {"verify", &s.verify},       {"frame", &s.total},
      {"frame_cpu", &s.total_cpu}, {"segment_describe", &s.segment_describe},
      {"render", &s.render},       {"cvtcolor", &s.cvtcolor}};
  for (const auto& [name, v] : stages) {
    const Spread sp = spread(*v);
    j[std::string(name) + "_ms_median"] = sp.median;
    j[std::string(name) + "_ms_p95"] = sp.p95;
  }
  j["timed_part"] = "Detector::process on the gray frame (render and cvtcolor are outside it)";
  j["segment_includes_histograms"] = true;  // describe_ms: the storage encoding and the place signature
  j["bytes_per_frame"] = d.bytes_per_frame;
  j["store_bytes"] = static_cast<double>(d.stored) * static_cast<double>(d.bytes_per_frame);
  j["peak_rss_bytes"] = peak_rss_bytes();
  j["peak_rss_before_run_bytes"] = d.peak_rss_before_bytes;
  j["nodes"] = d.nodes;
  j["query_growth"] = growth_json(setup, d.growth);
  add_slic_json(d, j);
  j["threads"] = kThreads;
  j["machine"] = to_json(d.machine);
  j["load_average"] = {{"start", d.load_start}, {"end", d.load_end}};
  j["config_yaml"] = io::to_yaml(o);
  return j;
}

void print_report(const Setup& setup, const DetectorOptions& o, const RunData& d,
                  std::ostream& out) {
  const Samples& s = d.samples;
  const FrameSize work = working_size(setup.width, setup.height, o.segmentation);
  const std::string scaled = work.width != setup.width || work.height != setup.height
                                 ? " (segmented at " + std::to_string(work.width) + "x" +
                                       std::to_string(work.height) + ", segmentation.working_side)"
                                 : std::string();
  out << "lsgd bench: " << setup.frames << " frames " << setup.width << "x" << setup.height
      << " (synthetic street, seed " << setup.seed << "; frame i renders route frame i % 1090)\n"
      << "  detector  " << o.search.mode << " search, verify "
      << verification_stages(o.verification) << ", S_p " << o.segmentation.superpixel_size
      << " -> grid " << d.grid.rows << "x" << d.grid.cols << " = " << d.grid.cells() << " cells" << scaled
      << ", " << o.segmentation.iterations << " iterations\n"
      << "  machine   " << summary(d.machine) << "\n"
      << "  threads   OpenCV sequential (cv::setNumThreads(0)), detector on the calling thread\n"
      << "  load      " << loads(d.load_start) << " at start, " << loads(d.load_end)
      << " at end (1-minute load average)\n";
  const double cores = d.machine.logical_cores;
  for (const auto* load : {&d.load_start, &d.load_end}) {
    if (!load->empty() && cores > 0 && (*load)[0] > cores) {
      out << "  WARNING   load average above " << d.machine.logical_cores
          << " cores: other processes share the CPU, wall-clock times are inflated "
             "(CPU-time columns much less)\n";
      break;
    }
  }
  out << "\nper frame, over the " << s.total.size() << " frames after " << setup.warmup
      << " warm-up frames\n"
      << std::left << std::setw(44) << "ms" << std::right << std::setw(9) << "median"
      << std::setw(9) << "p95"
      << "\n";
  print_row(out, "  convert (lsgd's copy of the gray frame)", s.convert);
  print_row(out, "  segment (histograms counted in its last pass)", s.segment);
  print_row(out, "  describe (storage encoding, place signature)", s.describe);
  print_row(out, "  query (search)", s.query);
  print_row(out, "  verify", s.verify);
  print_row(out, "  total (Detector::process)", s.total);
  print_row(out, "  total, this thread's CPU time", s.total_cpu);
  print_row(out, "  not timed: render", s.render);
  print_row(out, "  not timed: cv::cvtColor BGR->gray", s.cvtcolor);
  print_growth(setup, d.scores_every_frame, d.growth, out);
  out << "\nmemory: " << d.bytes_per_frame << " bytes stored per frame, store "
      << megabytes(static_cast<double>(d.stored) * static_cast<double>(d.bytes_per_frame))
      << " for " << d.stored << " frames; peak RSS "
      << megabytes(static_cast<double>(peak_rss_bytes())) << " ("
      << megabytes(static_cast<double>(d.peak_rss_before_bytes)) << " before the first frame)\n"
      << "nodes: " << d.nodes << "\n\n";
  print_slic(d, out);
}

}  // namespace lsgd::cli::bench
