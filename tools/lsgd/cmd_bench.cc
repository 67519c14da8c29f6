// lsgd bench: whole-pipeline timing on a generated sequence of any length and
// size. Frame i shows frame i % 1090 of the synthetic street's route
// (eval/synthetic.h), rendered on the fly and converted to gray with
// cv::cvtColor outside the timed part; Detector::process gets the gray frame,
// so its stages (Result::timings) are what is reported, after the warm-up
// frames. OpenCV runs sequentially (cv::setNumThreads(0)) for the whole bench.
// Every k-th measured frame is also segmented by OpenCV's own SLIC
// (cv::ximgproc, when built with it) and by a standalone lsgd::Segmenter, in
// alternating order, so machine noise hits both alike.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "bench_distractors.h"
#include "bench_report.h"
#include "bench_support.h"
#include "commands.h"
#include "distractor.h"
#include "common.h"
#include "files.h"
#include "lsgd/descriptor.h"
#include "lsgd/error.h"
#include "lsgd/io/layouts.h"
#include "synthetic/synthetic.h"
#include "lsgd/segmentation.h"

namespace lsgd::cli {
namespace {

using bench::Elapsed;
using bench::Stopwatch;

struct BenchArgs {
  bench::Setup setup;
  std::string json;
  DetectorFlags detector;
  std::int64_t distractors = 0;  // > 0: bench::run_distractors
  std::int64_t distractor_run = 1;  // --distractor-run
  std::string sequence;          // --distractors: a real sequence instead of the street
  std::string gt;                // ... and its ground truth
  SequenceFlags layout;
  CLI::App* command = nullptr;
};

void record(const Result& r, double cpu_ms, double render_ms, double cvt_ms, bench::Samples& s) {
  const Timings& t = r.timings;
  s.convert.push_back(t.convert_ms);
  s.segment.push_back(t.segment_ms);
  s.describe.push_back(t.describe_ms);
  s.query.push_back(t.search_ms);
  s.verify.push_back(t.verify_ms);
  s.total.push_back(t.total_ms);
  s.segment_describe.push_back(t.segment_ms + t.describe_ms);
  s.total_cpu.push_back(cpu_ms);
  s.render.push_back(render_ms);
  s.cvtcolor.push_back(cvt_ms);
}

// Our segmentation and descriptor called the way OpenCvSlic calls SLIC: one
// frame at a time, timed with the same clocks. The segmentation alone and the
// segmentation + descriptor (segment_and_describe, as the detector runs them)
// are two calls on the same frame; which one runs first alternates from frame
// to frame, so that neither always finds the caches warm.
class StandaloneLsgd {
 public:
  explicit StandaloneLsgd(const SegmentationOptions& options) : segmenter_(options) {}

  void time(const cv::Mat& gray, bench::SlicSamples& s) {
    to_gray(gray, gray_);
    Elapsed segment, both;
    // The segmentation alone at the size the detector segments (the working
    // size, scaled before the clock as SLIC's frame is); segment_and_describe
    // scales it itself, as the detector does.
    const GrayImage& work = segmenter_.working(gray_);
    const auto time_segment = [&] {
      const Stopwatch watch;
      segmenter_.segment(work, segmentation_);
      segment = watch.elapsed();
    };
    const auto time_both = [&] {
      const Stopwatch watch;
      segment_and_describe(segmenter_, gray_, segmentation_, descriptor_, scratch_);
      both = watch.elapsed();
    };
    if (s.segment.size() / 2 % 2 == 0) {  // SLIC's order flips every frame, this every other
      time_segment();
      time_both();
    } else {
      time_both();
      time_segment();
    }
    s.segment.push_back(segment.wall_ms);
    s.segment_cpu.push_back(segment.cpu_ms);
    s.segment_describe.push_back(both.wall_ms);
    s.segment_describe_cpu.push_back(both.cpu_ms);
  }

 private:
  Segmenter segmenter_;
  GrayImage gray_;
  Segmentation segmentation_;
  Descriptor descriptor_;
  DescribeScratch scratch_;
};

void plan_slic(const bench::Setup& a, const DetectorOptions& options, bench::RunData& d) {
  bench::SlicSamples& s = d.slic;
  if (a.opencv_frames == 0) {
    s.reason = "--opencv-frames 0";
  } else if (!bench::OpenCvSlic::available()) {
    s.reason = bench::OpenCvSlic::unavailable_reason();
  } else {
    const FrameSize work = working_size(a.width, a.height, options.segmentation);
    s.slic = std::make_unique<bench::OpenCvSlic>(work.width, work.height, d.grid.cells(),
                                                 options.segmentation.iterations);
    s.every = std::max<std::int64_t>(1, (a.frames - a.warmup) / a.opencv_frames);
  }
}

// Frame i is a SLIC frame when it is the m-th measured frame with m % every == 0, m / every < N.
bool slic_frame(const bench::Setup& a, const bench::SlicSamples& s, std::int64_t i) {
  if (!s.slic || i < a.warmup) return false;
  const std::int64_t m = i - a.warmup;
  return m % s.every == 0 && m / s.every < a.opencv_frames;
}

void run(const bench::Setup& a, const DetectorOptions& options, bench::RunData& d) {
  eval::SyntheticOptions world_options;
  world_options.width = a.width;
  world_options.height = a.height;
  world_options.seed = a.seed;
  const eval::SyntheticWorld world(world_options);
  Detector detector(options);
  StandaloneLsgd ours(options.segmentation);
  d.grid = frame_grid(a.width, a.height, options.segmentation);
  plan_slic(a, options, d);
  d.peak_rss_before_bytes = bench::peak_rss_bytes();

  // Frame i: route frame i % 1090 rendered and converted to gray by the
  // source (outside process()), fed through the frame loop of every command.
  struct Loaded {
    cv::Mat gray;
    double render_ms = 0, cvt_ms = 0;
  };
  const auto loaded = std::make_shared<Loaded>();
  eval::FrameSource source;
  source.frames = a.frames;
  source.load = [&world, loaded](std::int64_t i) {
    const Stopwatch render;
    const cv::Mat bgr = world.render(i % world.frames());
    loaded->render_ms = render.elapsed().wall_ms;
    const Stopwatch cvt;
    cv::cvtColor(bgr, loaded->gray, cv::COLOR_BGR2GRAY);
    loaded->cvt_ms = cvt.elapsed().wall_ms;
    return loaded->gray;
  };
  source.name = [](std::int64_t i) { return "synthetic frame " + std::to_string(i); };
  eval::RunOptions run_options;
  run_options.keep_records = false;
  run_frames(detector, source, "bench " + options.search.mode, run_options,
             [&](const Result& r, const eval::FrameTimes& times) {
               const std::int64_t i = r.frame;
               const cv::Mat& gray = loaded->gray;
               bench::SlicSamples& s = d.slic;
               // SLIC segments the frame at the detector's working size too.
               const FrameSize work = working_size(gray.cols, gray.rows, options.segmentation);
               cv::Mat slic_gray = gray;
               if (s.slic && (work.width != gray.cols || work.height != gray.rows) &&
                   (i == 0 || slic_frame(a, s, i))) {
                 cv::resize(gray, slic_gray, cv::Size(work.width, work.height), 0, 0, cv::INTER_AREA);
               }
               if (s.slic && i == 0) s.slic->time(slic_gray);  // untimed warm-up call
               if (slic_frame(a, s, i)) {
                 const bool ours_first = s.ms.size() % 2 == 0;
                 if (ours_first) ours.time(gray, s);
                 const Elapsed e = s.slic->time(slic_gray);
                 s.ms.push_back(e.wall_ms);
                 s.cpu_ms.push_back(e.cpu_ms);
                 if (!ours_first) ours.time(gray, s);
               }
               if (i >= a.warmup) {
                 record(r, times.process_cpu_ms, loaded->render_ms, loaded->cvt_ms, d.samples);
               }
             });
  d.nodes = detector.nodes();
  d.scores_every_frame = detector.search().scores_every_frame();
  d.bytes_per_frame = detector.bytes_per_frame();
  d.stored = detector.size();
}

void distractors_command(const BenchArgs& args) {
  bench::DistractorSetup d;
  d.distractors = args.distractors;
  d.run = args.distractor_run;
  d.sequence = args.sequence;
  d.gt = args.gt;
  if (!d.gt.empty() && d.sequence.empty()) {
    throw InvalidArgument("--gt is the ground truth of --sequence: the synthetic street has its own");
  }
  d.layout = args.layout.resolve();
  d.frames = args.command->count("--frames") > 0 ? args.setup.frames : 1090;
  d.width = args.setup.width;
  d.height = args.setup.height;
  d.seed = args.setup.seed;
  if (!args.detector.mode.empty()) d.modes = {args.detector.mode};
  d.json = args.json;
  const DetectorOptions options = args.detector.resolve();
  CommandFiles files;
  files.input(args.detector.config, "--config");
  files.input(args.sequence, "--sequence");
  files.input(args.gt, "--gt");
  if (!args.sequence.empty()) {  // the JSON may not land on one of the images read
    files.sequence(io::open_sequence(args.sequence, d.layout), "--sequence", "input image");
  }
  files.output(args.json, "--json");
  files.check();
  cv::setNumThreads(0);
  bench::run_distractors(d, options);
}

// Fails before the first frame when the map of --frames frames and the
// bench's per-frame timings (10 samples of 8 bytes, up to twice that while
// their vectors grow) would not fit in the memory this process can take,
// instead of the run being killed hours in (bench::require_memory).
void check_memory(const bench::Setup& a, const DetectorOptions& options) {
  const int cells = frame_grid(a.width, a.height, options.segmentation).cells();
  const std::int64_t samples = 2 * 10 * static_cast<std::int64_t>(sizeof(double));
  const std::int64_t need = bench::map_bytes(options.search.mode, a.frames, cells, options) + a.frames * samples;
  bench::require_memory("--frames " + std::to_string(a.frames), a.frames, cells, options, need,
                        bench::available_memory_bytes(), "fewer frames");
}

// --layout, --first, ... choose the frames of --sequence: without one they
// would change nothing.
void refuse_sequence_flags_without_sequence(const BenchArgs& args) {
  const std::vector<std::string> given = SequenceFlags::given(*args.command);
  if (!args.sequence.empty() || given.empty()) return;
  std::string flags;
  for (const std::string& f : given) flags += (flags.empty() ? "" : ", ") + f;
  throw InvalidArgument(flags + (given.size() > 1 ? " choose" : " chooses") +
                        " the frames of --sequence: give --distractors N --sequence PATH too "
                        "(the synthetic street takes --frames, --width and --height)");
}

void bench_command(const BenchArgs& args) {
  refuse_sequence_flags_without_sequence(args);
  if (args.distractors > 0) return distractors_command(args);
  if (!args.sequence.empty() || !args.gt.empty() || args.command->count("--distractor-run") > 0) {
    throw InvalidArgument(
        "--sequence, --gt and --distractor-run are about --distractors: give --distractors N too");
  }
  const bench::Setup& a = args.setup;
  if (a.warmup >= a.frames) {
    throw InvalidArgument("--warmup " + std::to_string(a.warmup) +
                          " must be smaller than --frames " + std::to_string(a.frames) +
                          " (no frame would be measured)");
  }
  const DetectorOptions options = args.detector.resolve();
  CommandFiles files;
  files.input(args.detector.config, "--config");
  files.output(args.json, "--json");
  files.check();
  check_memory(a, options);
  cv::setNumThreads(0);  // sequential, like the detector
  bench::RunData d;
  d.machine = bench::describe_machine();
  d.load_start = bench::load_average();
  run(a, options, d);
  d.load_end = bench::load_average();
  d.growth = bench::query_growth(d.samples.query, a.warmup, a.block,
                                 d.scores_every_frame,
                                 options.search.min_gap, d.bytes_per_frame);
  bench::print_report(a, options, d, std::cout);
  if (!args.json.empty()) {
    write_json(bench::to_json(a, options, d), args.json);
    std::cout << "wrote " << args.json << "\n";
  }
}

}  // namespace

void register_bench(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  bench::Setup& s = args->setup;
  CLI::App* cmd = app.add_subcommand(
      "bench", "time the whole pipeline per stage on a generated sequence, next to OpenCV's SLIC");
  const auto at_least = [](std::int64_t lo) { return CLI::Range(lo, std::int64_t{1'000'000'000}); };
  cmd->add_option(
         "--frames", s.frames,
         "frames to process; frame i shows route frame i % 1090 (default: KITTI 00's 4541)")
      ->check(at_least(1));
  cmd->add_option("--width", s.width, "frame width, pixels (default 1241, KITTI)")
      ->check(CLI::Range(32, 4096));
  cmd->add_option("--height", s.height, "frame height, pixels (default 376, KITTI)")
      ->check(CLI::Range(32, 4096));
  cmd->add_option("--warmup", s.warmup, "first frames left out of the statistics (default 20)")
      ->check(at_least(0));
  cmd->add_option("--opencv-frames", s.opencv_frames,
                  "frames also segmented by OpenCV's SLIC, spread evenly (default 100; 0: none)")
      ->check(at_least(0));
  cmd->add_option("--block", s.block, "frames per row of the query-time-vs-N table (default 500)")
      ->check(at_least(1));
  cmd->add_option("--seed", s.seed, "seed of the synthetic world (default 1)");
  cmd->add_option("--json", args->json, "also write the results as JSON here")
      ->check(kNonEmptyPath);
  cmd->add_option("--distractors", args->distractors,
                  "hide the sequence among N distractor frames (perturbed descriptors of its own "
                  "frames) and compare the search modes at that map size: query and insert ms, "
                  "recall_vs_exhaustive, bytes per frame (--mode: that mode and exhaustive)")
      ->check(at_least(0));
  cmd->add_option("--distractor-run", args->distractor_run,
                  "with --distractors: distractors per run, consecutive frames of the sequence "
                  "given one layout and one lighting change, as a stretch of another place "
                  "(default 1: every distractor its own)")
      ->check(at_least(1));
  cmd->add_option("--sequence", args->sequence,
                  "with --distractors: a real sequence (folder, list or dataset layout); default: "
                  "the synthetic street (--frames frames, 1090 by default)")
      ->check(kNonEmptyPath);
  cmd->add_option("--gt", args->gt,
                  "with --distractors --sequence: its loop ground truth (as lsgd eval reads it), "
                  "to count the declared loops that are true; the synthetic street has its own")
      ->check(kNonEmptyPath);
  args->layout.add_to(*cmd, /*skips=*/false);  // a benchmark needs every frame
  args->command = cmd;
  args->detector.add_to(*cmd);
  cmd->callback([args] { bench_command(*args); });
}

}  // namespace lsgd::cli
