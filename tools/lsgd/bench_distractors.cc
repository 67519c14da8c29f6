// lsgd bench --distractors N.
//
// The map holds N distractor frames before the sequence (distractor.h: how
// each is made from a frame of the sequence; --distractor-run R: runs of R
// consecutive ones are a stretch of one other place). So a distractor looks
// like a place of the same world, never like a copy of a sequence frame. They
// are stored with Detector::restore_frame (no image: they have no ORB
// features, so geometry never confirms one), then the sequence is processed
// frame by frame as a SLAM system would; every frame is a query against N + i
// frames.
//
// Per mode: query ms (the search and its evidence, without index insertion;
// also split into the mode's candidate search and the evidence: statistics,
// sequence scores, realignment), insert ms (adding one frame to the mode's
// index), build seconds (the first query, which indexes the N distractors),
// recall_vs_exhaustive (the share of the queries with a candidate in
// exhaustive search whose reported candidate is exhaustive's; also apart for
// the queries whose exhaustive candidate is a sequence frame and those whose
// is a distractor), loops declared and declared_vs_exhaustive (the share of
// exhaustive search's declared loops this mode declares, to the same frame),
// and memory per frame (resident memory the detector added,
// over its frames; the descriptor alone beside it).
#include "bench_distractors.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "bench_support.h"
#include "distractor.h"
#include "lsgd/error.h"
#include "lsgd/eval/dataset.h"
#include "lsgd/eval/gt_formats.h"
#include "lsgd/eval/runner.h"
#include "lsgd/io/layouts.h"
#include "lsgd/io/sequence.h"
#include "lsgd/search.h"
#include "lsgd/segmentation.h"
#include "lsgd/stage.h"
#include "lsgd/state.h"
#include "synthetic/synthetic.h"

namespace lsgd::cli::bench {
namespace {

// Resident memory now, bytes (/proc/self/statm counts pages).
std::int64_t current_rss_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::int64_t pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * static_cast<std::int64_t>(sysconf(_SC_PAGESIZE));
}

// The process's peak resident memory since reset_peak_rss(), bytes (VmHWM of
// /proc/self/status, which getrusage's peak cannot reset; 0 when unreadable).
std::int64_t peak_rss_since_reset() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::atoll(line.c_str() + 6) * 1024;  // kB
  }
  return 0;
}

// Resets the peak to the current resident memory (Linux 4.0+: "5" to clear_refs).
void reset_peak_rss() { std::ofstream("/proc/self/clear_refs") << "5"; }


struct Frames {
  std::vector<cv::Mat> gray;       // the sequence, 8-bit gray
  std::vector<Descriptor> exact;   // ... and its exact descriptors
  int width = 0, height = 0;
  std::string source;
  std::optional<eval::GroundTruth> gt;  // over the sequence's frames, when known
};

Frames load_frames(const DistractorSetup& a, const DetectorOptions& options) {
  Frames f;
  if (a.sequence.empty()) {
    eval::SyntheticOptions w;
    w.width = a.width;
    w.height = a.height;
    w.seed = a.seed;
    const eval::SyntheticWorld world(w);
    for (std::int64_t i = 0; i < a.frames; ++i) {
      cv::Mat gray;
      cv::cvtColor(world.render(i % world.frames()), gray, cv::COLOR_BGR2GRAY);
      f.gray.push_back(gray);
    }
    f.source = "synthetic street, " + std::to_string(a.frames) + " frames";
    // Its ground truth covers one lap of the route.
    if (a.frames <= world.frames()) f.gt = world.ground_truth();
  } else {
    // As lsgd eval reads a dataset: the ground truth in the dataset's own
    // numbering, moved onto the frames --first/--last/--every keep.
    io::Sequence sequence;
    if (a.gt.empty()) {
      sequence = io::open_sequence(a.sequence, a.layout);
    } else {
      eval::Dataset dataset = eval::open_dataset(a.sequence, a.layout, a.gt);
      sequence = std::move(dataset.frames);
      f.gt = std::move(dataset.gt);
    }
    for (std::size_t k = 0; k < sequence.images.size(); ++k) {
      cv::Mat image;
      try {
        image = io::read_image(sequence.images[k]);
      } catch (const Error& e) {
        // The map and its ground truth are numbered by frame: a benchmark
        // cannot skip one (lsgd run and eval can).
        throw InvalidArgument("--sequence: frame " + std::to_string(k) + ": " + e.what() +
                              " (lsgd bench needs every frame: leave it out of the sequence)");
      }
      if (image.channels() > 1) cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
      f.gray.push_back(image);
    }
    f.source = a.sequence + ", " + std::to_string(f.gray.size()) + " frames";
  }
  f.width = f.gray.front().cols;
  f.height = f.gray.front().rows;
  Segmenter segmenter(options.segmentation);
  Segmentation segmentation;
  DescribeScratch scratch;
  for (const cv::Mat& g : f.gray) {
    if (g.cols != f.width || g.rows != f.height) {
      throw InvalidArgument("--sequence: a frame is " + std::to_string(g.cols) + "x" + std::to_string(g.rows) +
                            ", the first " + std::to_string(f.width) + "x" + std::to_string(f.height));
    }
    const GrayImage image = to_gray(g);
    Descriptor d;
    segment_and_describe(segmenter, image, segmentation, d, scratch, options.descriptor);
    f.exact.push_back(std::move(d));
  }
  return f;
}

struct ModeRun {
  std::string mode;
  Spread query, insert, total;
  Spread candidates, evidence;  // the query's two parts: the mode's candidate search, the evidence
  double build_s = 0;
  double recall_vs_exhaustive = 0;
  std::int64_t compared = 0;  // queries with an exhaustive candidate
  // ... split by where exhaustive search's candidate is: a frame of the
  // sequence, or a distractor (a query that revisits nothing, whose best
  // candidate is the highest of N sequences of noise scores).
  double recall_sequence = 0, recall_distractor = 0;
  std::int64_t compared_sequence = 0, compared_distractor = 0;
  double bytes_per_frame = 0;            // resident memory added / frames
  std::size_t descriptor_bytes = 0;      // descriptor storage per frame
  double rss_mb = 0;
  double peak_rss_mb = 0;               // the process's peak while the mode ran
  std::int64_t index_bytes = 0;         // Detector::save_index() at the end (0: no index)
  double index_save_s = 0;              // ... the time it took
  double index_restore_s = 0;           // ... and restoring it into a new search (checks included)
  std::int64_t frames = 0;
  std::vector<std::int64_t> best;  // reported candidate per query
  std::vector<std::int64_t> loops;  // declared loop per query (-1: none)
  std::int64_t declared = 0;         // loops declared
  std::int64_t declared_false = 0;   // ... to a distractor or, by the ground truth, not a loop (-1: no GT)
  // Of exhaustive search's declared loops, the share this mode declares too,
  // to the same frame (the operating point at this map size).
  double declared_vs_exhaustive = 0;
};

ModeRun run_mode(const std::string& mode, const DistractorSetup& a, const DetectorOptions& base,
                 const Frames& f) {
  DetectorOptions options = base;
  options.search.mode = mode;
  ModeRun r;
  r.mode = mode;
  reset_peak_rss();
  const std::int64_t rss0 = current_rss_bytes();
  {
    Detector detector(options);
    // The state of a frame without an image: geometry, when on, keeps no
    // features for it; every other component starts without a record.
    std::vector<StateRecord> records;
    if (options.verification.has(kGeometricStage)) records.push_back({kGeometricStage, 1, {}});
    const std::vector<std::uint8_t> state = encode_records(records);
    Descriptor exact, stored;
    for (std::int64_t k = 0; k < a.distractors; ++k) {
      make_distractor(f.exact[static_cast<std::size_t>(k % static_cast<std::int64_t>(f.exact.size()))], k,
                      a.run, options.descriptor.storage, exact, stored);
      detector.restore_frame(f.width, f.height, stored, state);
    }
    std::vector<double> query, insert, total, candidates, evidence;
    r.declared_false = f.gt ? 0 : -1;
    for (std::size_t i = 0; i < f.gray.size(); ++i) {
      const Result res = detector.process(f.gray[i]);
      const double q = res.timings.search_ms - res.timings.insert_ms;
      if (i == 0) {
        r.build_s = res.timings.insert_ms * 1e-3;  // the distractors enter the index
      } else {
        query.push_back(q);
        candidates.push_back(q - res.timings.evidence_ms);
        evidence.push_back(res.timings.evidence_ms);
        if (res.timings.insert_ms > 0) insert.push_back(res.timings.insert_ms);
        total.push_back(res.timings.total_ms);
      }
      r.best.push_back(res.best.frame);
      r.loops.push_back(res.loop ? res.best.frame : -1);
      r.declared += res.loop ? 1 : 0;
      if (res.loop) {
        // Sequence frame i is detector frame N + i; a distractor is never the same place.
        const std::int64_t j = res.best.frame - a.distractors;
        if (f.gt && (j < 0 || !f.gt->is_loop(static_cast<std::int64_t>(i), j))) ++r.declared_false;
      }
    }
    r.query = spread(query);
    r.candidates = spread(candidates);
    r.evidence = spread(evidence);
    r.insert = insert.empty() ? Spread{} : spread(insert);
    r.total = spread(total);
    r.frames = detector.size();
    r.descriptor_bytes = detector.bytes_per_frame();
    const std::int64_t rss1 = current_rss_bytes();
    r.peak_rss_mb = static_cast<double>(peak_rss_since_reset()) / (1 << 20);
    {
      const Stopwatch save;
      std::vector<std::uint8_t> graph;
      detector.save_index(graph);
      r.index_save_s = save.elapsed().wall_ms * 1e-3;
      r.index_bytes = static_cast<std::int64_t>(graph.size());
      if (!graph.empty()) {
        // What a resume costs instead of a rebuild (without reading the file).
        const std::unique_ptr<CandidateSearch> fresh = make_search(options.search);
        const Stopwatch restore;
        fresh->restore_index(detector.store(), options.similarity.metric, graph.data(), graph.size());
        r.index_restore_s = restore.elapsed().wall_ms * 1e-3;
      }
    }
    r.rss_mb = static_cast<double>(rss1) / (1 << 20);
    r.bytes_per_frame = static_cast<double>(rss1 - rss0) / static_cast<double>(r.frames);
  }
  return r;
}

nlohmann::json row_json(const ModeRun& r) {
  return {{"mode", r.mode},
          {"frames", r.frames},
          {"query_ms_median", r.query.median},
          {"query_ms_p95", r.query.p95},
          {"candidates_ms_median", r.candidates.median},
          {"evidence_ms_median", r.evidence.median},
          {"insert_ms_median", r.insert.median},
          {"insert_ms_p95", r.insert.p95},
          {"process_ms_median", r.total.median},
          {"build_s", r.build_s},
          {"recall_vs_exhaustive", r.recall_vs_exhaustive},
          {"compared_queries", r.compared},
          {"recall_vs_exhaustive_sequence", r.recall_sequence},
          {"compared_queries_sequence", r.compared_sequence},
          {"recall_vs_exhaustive_distractor", r.recall_distractor},
          {"compared_queries_distractor", r.compared_distractor},
          {"declared", r.declared},
          {"declared_false", r.declared_false},
          {"declared_vs_exhaustive", r.declared_vs_exhaustive},
          {"bytes_per_frame", r.bytes_per_frame},
          {"descriptor_bytes_per_frame", r.descriptor_bytes},
          {"rss_mb", r.rss_mb},
          {"peak_rss_mb", r.peak_rss_mb},
          {"index_bytes_per_frame", static_cast<double>(r.index_bytes) / static_cast<double>(r.frames)},
          {"index_save_s", r.index_save_s},
          {"index_restore_s", r.index_restore_s}};
}

// Fails before any map is built when the largest mode's map would not fit
// in the memory this process can still take (the modes run one after the
// other, each on its own map), so a run too large for the machine is told
// at once instead of being killed at its end.
void check_memory(const DistractorSetup& a, const DetectorOptions& options, const Frames& f,
                  const std::vector<std::string>& modes) {
  const std::int64_t frames = a.distractors + static_cast<std::int64_t>(f.gray.size());
  const int cells = f.exact.front().grid.cells();
  std::int64_t map = 0;
  for (const std::string& m : modes) map = std::max(map, map_bytes(m, frames, cells, options));
  std::int64_t held = 0;  // the sequence's images and exact descriptors, held by the bench
  for (std::size_t i = 0; i < f.gray.size(); ++i) {
    held += static_cast<std::int64_t>(f.gray[i].total() + f.exact[i].hist.size() * sizeof(Bin));
  }
  require_memory("--distractors " + std::to_string(a.distractors), frames, cells, options, map + held,
                 available_memory_bytes(), "fewer distractors");
}

// The modes asked for (all but nodes when none), exhaustive search first: the
// reference the others are compared with.
std::vector<std::string> modes_to_run(const DistractorSetup& a) {
  std::vector<std::string> modes = a.modes;
  if (modes.empty()) {
    for (const SearchMode& m : search_modes()) {
      if (std::string(m.name) != kNodesSearch) modes.emplace_back(m.name);
    }
  }
  for (const std::string& m : modes) {
    if (m == kNodesSearch) {
      throw InvalidArgument("--distractors: search mode nodes cannot take distractors (its nodes "
                            "are built by running Algorithm 1 over every frame, O(N^2) for N "
                            "distractors); use exhaustive or index");
    }
  }
  modes.erase(std::remove(modes.begin(), modes.end(), std::string(kExhaustiveSearch)), modes.end());
  modes.insert(modes.begin(), kExhaustiveSearch);  // the reference, first
  return modes;
}

// Sets each run's agreement with the first (exhaustive search): its best
// candidates, split by where exhaustive search's lies, and its declared loops.
void compare_to_exhaustive(std::vector<ModeRun>& runs, std::int64_t distractors) {
  const std::vector<std::int64_t>& reference = runs.front().best;
  for (ModeRun& r : runs) {
    std::int64_t compared[2] = {}, same[2] = {};  // [0]: into the sequence, [1]: a distractor
    for (std::size_t i = 1; i < reference.size(); ++i) {
      if (reference[i] < 0) continue;
      const int k = reference[i] < distractors ? 1 : 0;
      ++compared[k];
      same[k] += r.best[i] == reference[i] ? 1 : 0;
    }
    const auto share = [](std::int64_t part, std::int64_t whole) {
      return whole > 0 ? static_cast<double>(part) / static_cast<double>(whole) : 0.0;
    };
    r.compared = compared[0] + compared[1];
    r.recall_vs_exhaustive = share(same[0] + same[1], r.compared);
    r.compared_sequence = compared[0];
    r.recall_sequence = share(same[0], compared[0]);
    r.compared_distractor = compared[1];
    r.recall_distractor = share(same[1], compared[1]);
    std::int64_t declared = 0, kept = 0;
    for (std::size_t i = 0; i < reference.size(); ++i) {
      if (runs.front().loops[i] < 0) continue;
      ++declared;
      kept += r.loops[i] == runs.front().loops[i] ? 1 : 0;
    }
    r.declared_vs_exhaustive = declared > 0 ? static_cast<double>(kept) / declared : 1;
  }
}

// The table of the runs on standard output.
void print_runs(const std::vector<ModeRun>& runs) {
  std::cout << std::fixed << std::setprecision(3)
            << "mode        frames   query ms (median, p95)   insert ms (median, p95)   build s   "
               "recall_vs_exhaustive   declared (same as exhaustive)   false   bytes/frame (descriptor)\n";
  for (const ModeRun& r : runs) {
    std::cout << std::left << std::setw(10) << r.mode << std::right << std::setw(9) << r.frames << "   "
              << std::setw(8) << r.query.median << " " << std::setw(8) << r.query.p95 << "          "
              << std::setw(8) << r.insert.median << " " << std::setw(8) << r.insert.p95 << "      "
              << std::setw(8) << std::setprecision(2) << r.build_s << std::setprecision(3) << "   "
              << std::setw(8) << r.recall_vs_exhaustive << " (" << r.compared << " queries)   "
              << std::setw(6) << r.declared << " (" << r.declared_vs_exhaustive << ")   "
              << std::setw(4) << r.declared_false << "   "
              << std::setprecision(0) << r.bytes_per_frame << " (" << r.descriptor_bytes << ")"
              << std::setprecision(3) << "\n";
    std::cout << "          recall where exhaustive search's candidate is in the sequence "
              << r.recall_sequence << " (" << r.compared_sequence << " queries), a distractor "
              << r.recall_distractor << " (" << r.compared_distractor << ")\n";
    std::cout << "          query = candidates " << r.candidates.median << " + evidence " << r.evidence.median
              << " ms (medians); peak memory " << std::setprecision(0) << r.peak_rss_mb << " MB";
    if (r.index_bytes > 0) {
      std::cout << ", saved index " << static_cast<double>(r.index_bytes) / static_cast<double>(r.frames)
                << " bytes/frame, saved in " << std::setprecision(2) << r.index_save_s
                << " s, restored in " << r.index_restore_s << " s";
    }
    std::cout << std::setprecision(3) << "\n";
  }
  std::cout.unsetf(std::ios::floatfield);
}

// The runs as JSON in --json: the top level is the mode asked for (the first
// that is not exhaustive); every mode is under "modes".
void write_runs_json(const DistractorSetup& a, const DetectorOptions& options, const Frames& f,
                     const std::vector<ModeRun>& runs) {
  const ModeRun& main = runs.size() > 1 ? runs[1] : runs[0];
  nlohmann::json j = row_json(main);
  j["distractors"] = a.distractors;
  j["sequence"] = f.source;
  j["width"] = f.width;
  j["height"] = f.height;
  j["storage"] = to_string(options.descriptor.storage);
  j["verification"] = verification_stages(options.verification);
  j["distractor_run"] = a.run;
  j["distractor_recipe"] =
      "descriptor of sequence frame k % M, cells shuffled, each cell's histogram moved by a "
      "random -24..+24 levels (seed k / distractor_run: one layout and lighting per run)";
  j["machine"] = to_json(describe_machine());
  nlohmann::json rows = nlohmann::json::array();
  for (const ModeRun& r : runs) rows.push_back(row_json(r));
  j["modes"] = rows;
  write_json(j, a.json);
  std::cout << "wrote " << a.json << "\n";
}

}  // namespace

void run_distractors(const DistractorSetup& a, const DetectorOptions& options) {
  const std::vector<std::string> modes = modes_to_run(a);
  const Frames f = load_frames(a, options);
  check_memory(a, options, f, modes);
  std::cout << "bench --distractors " << a.distractors << ": " << f.source << " (" << f.width << "x"
            << f.height << "), " << to_string(options.descriptor.storage) << " storage, verification "
            << verification_stages(options.verification) << "\n";
  std::vector<ModeRun> runs;
  for (const std::string& m : modes) {
    std::cout << "  " << m << " ..." << std::flush;
    runs.push_back(run_mode(m, a, options, f));
    std::cout << " done\n";
  }
  compare_to_exhaustive(runs, a.distractors);
  print_runs(runs);
  if (!a.json.empty()) write_runs_json(a, options, f, runs);
}

}  // namespace lsgd::cli::bench
