// lsgd gt convert SOURCE --output FILE [--format F] [--frames N] [--distance D] [--min-gap G]
// lsgd gt stats SOURCE [--format F] [--frames N] [--distance D] [--min-gap W] [--json FILE]
#include <CLI/CLI.hpp>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <memory>
#include <optional>

#include "commands.h"
#include "common.h"
#include "files.h"
#include "lsgd/error.h"
#include "lsgd/eval/gt_formats.h"
#include "lsgd/limits.h"

namespace lsgd::cli {
namespace {

struct GtArgs {
  std::string source;
  std::string format = "auto";
  std::int64_t frames = -1;
  std::optional<double> distance;
  std::optional<std::int64_t> min_gap;
  std::string variable;
  std::string output;  // convert
  std::string json;    // stats
};

void add_source_options(CLI::App& cmd, GtArgs& a) {
  cmd.add_option("SOURCE", a.source,
                 "ground truth: pairs text, MATLAB .mat, KITTI poses or LSGDDN loopinf")
      ->required()
      ->check(kNonEmptyPath);
  cmd.add_option("--format", a.format, [] {
       std::string help = "auto (default: by content)";
       for (const eval::GtFormatType& t : eval::gt_format_types()) help += std::string(" | ") + t.name;
       return help;
     }());
  cmd.add_option(
         "--frames", a.frames,
         "expected frame count; a file that disagrees is an error (default: from the file)")
      ->check(kFrameCount);
  cmd.add_option(
      "--distance", a.distance,
      "kitti-poses: a loop when camera centres are closer than this, metres (default 10)");
  cmd.add_option("--variable", a.variable, "mat: the variable to read (default: see docs)");
}

// Resolves the format (detecting it when auto) and the reader options; flags
// that do not apply to the resolved format are errors rather than ignored.
eval::GtOptions resolve(const GtArgs& a, bool min_gap_is_poses_only) {
  eval::GtOptions o;
  o.format = eval::parse_gt_format(a.format);
  if (o.format == eval::kAutoGtFormat) o.format = eval::detect_gt_format(a.source);
  o.frames = a.frames;
  o.mat_variable = a.variable;
  const bool poses = o.format == eval::kKittiPosesGtFormat;
  if (a.distance && !poses) {
    throw InvalidArgument("--distance applies to kitti-poses only; '" + a.source + "' is " +
                          o.format);
  }
  if (a.min_gap && min_gap_is_poses_only && !poses) {
    throw InvalidArgument("--min-gap applies to kitti-poses only; '" + a.source + "' is " +
                          o.format);
  }
  if (!a.variable.empty() && o.format != eval::kMatGtFormat) {
    throw InvalidArgument("--variable applies to mat only; '" + a.source + "' is " +
                          o.format);
  }
  if (a.distance) o.poses_distance = *a.distance;
  if (a.min_gap) o.poses_min_gap = *a.min_gap;
  o.check();
  return o;
}

void convert(const GtArgs& a) {
  const eval::GtOptions o = resolve(a, true);
  CommandFiles files;
  files.input(a.source, "SOURCE");
  files.output(a.output, "--output");
  files.check();
  const eval::GroundTruth gt = eval::load_groundtruth(a.source, o);
  eval::write_pairs(gt, a.output);
  std::cout << "wrote " << gt.pairs() << " pairs over " << gt.frames() << " frames to " << a.output
            << " (from " << o.format << ")\n";
}

void stats(const GtArgs& a) {
  const eval::GtOptions o = resolve(a, false);
  CommandFiles files;
  files.input(a.source, "SOURCE");
  files.output(a.json, "--json");
  files.check();
  const eval::GroundTruth gt = eval::load_groundtruth(a.source, o);
  const eval::GtStats s = eval::gt_stats(gt, a.min_gap.value_or(0));
  // The median gap is a whole or a half frame count: written whole (the
  // stream's 6 digits printed 9999997 as "1e+07").
  std::ostringstream median;
  median << std::setprecision(17) << s.gap_median;
  std::cout << "ground truth: " << a.source << " (" << o.format << ")\n"
            << "frames: " << s.frames << "\n"
            << "pairs: " << s.pairs << "\n"
            << "positive queries: " << s.positives << "\n"
            << "frames in loops: " << s.frames_in_loops << "\n"
            << "gap (frames): min " << s.gap_min << ", median " << median.str() << ", max "
            << s.gap_max << "\n";
  if (a.min_gap) {
    std::cout << "with min gap " << s.min_gap << ": positive queries " << s.window_positives
              << ", pairs " << s.window_pairs << "\n";
  }
  if (a.json.empty()) return;
  nlohmann::json j;
  j["source"] = a.source;
  j["format"] = o.format;
  j["frames"] = s.frames;
  j["pairs"] = s.pairs;
  j["positives"] = s.positives;
  j["frames_in_loops"] = s.frames_in_loops;
  j["gap_min"] = s.gap_min;
  j["gap_median"] = s.gap_median;
  j["gap_max"] = s.gap_max;
  j["min_gap"] = s.min_gap;
  j["window_positives"] = s.window_positives;
  j["window_pairs"] = s.window_pairs;
  if (o.format == eval::kKittiPosesGtFormat) {
    j["poses_distance"] = o.poses_distance;
    j["poses_min_gap"] = o.poses_min_gap;
  }
  write_json(j, a.json);
}

}  // namespace

void register_gt(CLI::App& app) {
  CLI::App* gt = app.add_subcommand(
      "gt", "ground truth: convert any supported format to pairs text, or summarise it");
  gt->require_subcommand(1);

  auto conv = std::make_shared<GtArgs>();
  CLI::App* c = gt->add_subcommand("convert", "read any ground-truth format, write pairs text");
  add_source_options(*c, *conv);
  c->add_option("--output", conv->output, "pairs text file to write ('q m' per line)")->required()
      ->check(kNonEmptyPath);
  c->add_option("--min-gap", conv->min_gap,
                "kitti-poses: loops are more than this many frames apart (default 100)")
      ->check(CLI::Range(std::int64_t{0}, kMaxWindowFrames));
  c->callback([conv] { convert(*conv); });

  auto st = std::make_shared<GtArgs>();
  CLI::App* s =
      gt->add_subcommand("stats", "frames, pairs, positive queries and gaps of a ground truth");
  add_source_options(*s, *st);
  s->add_option("--min-gap", st->min_gap,
                "temporal window W: also count positives with a match older than W frames "
                "(kitti-poses: also the derivation gap, default 100)")
      ->check(CLI::Range(std::int64_t{0}, kMaxWindowFrames));
  s->add_option("--json", st->json, "also write the statistics here as JSON")
      ->check(kNonEmptyPath);
  s->callback([st] { stats(*st); });
}

}  // namespace lsgd::cli
