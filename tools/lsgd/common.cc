#include "common.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>

#include <CLI/CLI.hpp>

#include "bench_support.h"
#include "internal/check.h"
#include "internal/clock.h"
#include "lsgd/io/files.h"
#include "lsgd/error.h"
#include "lsgd/io/config.h"
#include "lsgd/version.h"

namespace lsgd::cli {

using internal::now_ns;

void DetectorFlags::add_to(CLI::App& command) {
  command.add_option("--config", config, "YAML detector configuration (unknown keys are errors)")
      ->check(kExistingFile);
  const DetectorOptions defaults;
  command.add_option("--mode", mode,
                     "search mode (default " + defaults.search.mode + "; overrides search.mode)")
      ->check(one_of(search_mode_list()));
  command.add_option("--min-gap", min_gap,
                     "temporal window in frames: only frames j < i - W are candidates (default " +
                         option_text(defaults, "search.min_gap") + "; overrides search.min_gap)");
  command.add_option("--threshold", threshold,
                     "loop decision threshold on the loop score, standard deviations (default 7; "
                     "overrides decision.threshold)");
  command.add_option("--verify", verify,
                     "verification stages: none or a comma-separated list of " +
                         verification_stage_names() + " (default " +
                         verification_stages(defaults.verification) +
                         "; overrides verification.stages)");
  command.add_option("--option", options,
                     "KEY=VALUE: sets any detector option (`lsgd options` lists them), after "
                     "--config; repeatable")
      ->allow_extra_args(false);
}

DetectorOptions DetectorFlags::resolve() const {
  DetectorOptions resolved = config.empty() ? DetectorOptions{} : io::load_config(config);
  apply(resolved);
  return resolved;
}

std::vector<std::pair<std::string, std::string>> DetectorFlags::keys() const {
  std::vector<std::pair<std::string, std::string>> out;
  for (const std::string& setting : options) {
    const std::size_t eq = setting.find('=');
    if (eq == std::string::npos) {
      throw InvalidArgument("--option " + internal::shown_value(setting) +
                            ": expected KEY=VALUE (keys: lsgd options)");
    }
    out.emplace_back(setting.substr(0, eq), "--option " + setting.substr(0, eq));
  }
  if (!mode.empty()) out.emplace_back("search.mode", "--mode");
  if (min_gap) out.emplace_back("search.min_gap", "--min-gap");
  if (threshold) out.emplace_back("decision.threshold", "--threshold");
  if (!verify.empty()) out.emplace_back("verification.stages", "--verify");
  return out;
}

void DetectorFlags::apply(DetectorOptions& o) const {
  const std::vector<std::pair<std::string, std::string>> set = keys();
  for (std::size_t i = 0; i < set.size(); ++i) {
    for (std::size_t k = 0; k < i; ++k) {
      if (set[k].first != set[i].first) continue;
      // Two --option of one key with different values, or a shortcut and an
      // --option of one key: one would be lost without a word (the same
      // value twice loses nothing).
      const bool options_both = i < options.size();  // keys() lists the --option ones first
      if (options_both && options[k] == options[i]) continue;
      // Values, and keys, are shown as every option message shows them: one
      // line, cut after 64 bytes (internal::shown_value).
      const std::string key = internal::shown_value(set[i].first);
      throw InvalidArgument(options_both ? "--option " + internal::shown_value(options[k]) +
                                               " and --option " + internal::shown_value(options[i]) +
                                               " both set " + key + ": give one"
                                         : internal::shown_value(set[k].second) + " and " +
                                               internal::shown_value(set[i].second) + " both set " +
                                               key + ": give one");
    }
  }
  for (const std::string& setting : options) {
    const std::size_t eq = setting.find('=');
    set_option(o, setting.substr(0, eq), setting.substr(eq + 1));
  }
  if (!mode.empty()) set_option(o, "search.mode", mode);
  if (min_gap) o.search.min_gap = *min_gap;
  if (threshold) o.decision.threshold = *threshold;
  if (!verify.empty()) set_option(o, "verification.stages", verify);
  o.check();
}

std::vector<std::string> SequenceFlags::given(const CLI::App& command) {
  std::vector<std::string> out;
  for (const char* flag : {"--layout", "--kitti-sequence", "--camera", "--side", "--first", "--last",
                           "--every", "--strict"}) {
    if (command.get_option_no_throw(flag) != nullptr && command.count(flag) > 0) out.emplace_back(flag);
  }
  return out;
}

void SequenceFlags::add_to(CLI::App& command, bool skips) {
  command
      .add_option("--layout", layout, [] {
        std::string help =
            "how PATH is laid out: auto (the first layout that recognises PATH, else list for a "
            "file or a dataset folder, folder for another folder)";
        for (const io::LayoutType& t : io::layout_types()) {
          help += std::string(", ") + t.name + " (" + t.summary + ")";
        }
        return help;
      }())
      ->check(one_of(io::layout_names()));
  command.add_option("--kitti-sequence", kitti_sequence,
                     "KITTI: PATH is the dataset root and the frames are sequences/NN");
  command.add_option("--camera", camera, "KITTI: image_0 (default, gray left) .. image_3")
      ->check(CLI::Range(0, 3));
  command
      .add_option("--side", side,
                  "FAB-MAP: left (files 1, 3, 5, ...; default), right (2, 4, 6, ...) or "
                  "both (every file)")
      ->check(one_of({"left", "right", "both"}));
  command.add_option("--first", first, "first frame kept (0-based, before --every)");
  command.add_option("--last", last, "last frame that may be kept (0-based, inclusive)");
  command.add_option("--every", every,
                     "keep frames first, first + K, first + 2K, ...; frame ids, --min-gap and "
                     "the CSV count kept frames");
  if (!skips) return;
  command.add_flag("--strict", strict,
                   "stop at the first image that cannot be read or is rejected (corrupt, "
                   "truncated, not an image, other size, 16-bit); default: skip it, report it on "
                   "stderr and count it as a frame without a report");
}

io::SequenceOptions SequenceFlags::resolve() const {
  io::SequenceOptions options;
  options.layout = io::parse_layout(layout);
  options.kitti_sequence = kitti_sequence;
  options.camera = camera;
  if (!side.empty()) {
    if (options.layout != io::kFabmapLayout) {
      throw InvalidArgument("--side " + side +
                            " applies to --layout fabmap only (FAB-MAP "
                            "folders are not detected automatically)");
    }
    options.side = io::parse_side(side);
  }
  const bool kitti_flags = !kitti_sequence.empty() || camera >= 0;
  if (kitti_flags && options.layout != io::kAutoLayout && options.layout != io::kKittiLayout) {
    throw InvalidArgument("--kitti-sequence and --camera apply to --layout kitti (or auto), not " +
                          layout);
  }
  options.selection = io::FrameSelection{first, last, every};
  options.check();
  return options;
}

Progress::Progress(std::int64_t total, std::string label)
    : total_(total), label_(std::move(label)), enabled_(isatty(STDERR_FILENO) == 1),
      start_ns_(now_ns()) {}

std::string format_duration(double seconds) {
  if (!(seconds >= 0) || seconds > 1e7) return "--:--";
  const auto s = static_cast<long long>(seconds + 0.5);
  char text[32];
  if (s >= 3600) {
    std::snprintf(text, sizeof text, "%lld:%02lld:%02lld", s / 3600, s / 60 % 60, s % 60);
  } else {
    std::snprintf(text, sizeof text, "%lld:%02lld", s / 60, s % 60);
  }
  return text;
}

std::string Progress::line(std::int64_t done, double ms_per_frame, double elapsed_s) const {
  constexpr int kWidth = 30;
  const int filled = total_ > 0 ? static_cast<int>(kWidth * std::min(done, total_) / total_) : kWidth;
  const double rate = elapsed_s > 0 ? static_cast<double>(done) / elapsed_s : 0;
  const double eta = rate > 0 ? static_cast<double>(total_ - done) / rate : -1;
  char text[160];
  std::snprintf(text, sizeof text, " %lld/%lld frames, %.1f frames/s, %.2f ms/frame, elapsed %s, ETA %s",
                static_cast<long long>(done), static_cast<long long>(total_), rate, ms_per_frame,
                format_duration(elapsed_s).c_str(), format_duration(eta).c_str());
  return label_ + " [" + std::string(filled, '#') + std::string(kWidth - filled, '.') + "]" + text;
}

Progress::~Progress() {
  if (enabled_ && last_draw_ns_ != 0) std::fputs("\r\033[K", stderr);
}

void Progress::update(std::int64_t done, double ms_per_frame) {
  if (!enabled_) return;
  const std::int64_t now = now_ns();
  if (done < total_ && now - last_draw_ns_ < 100'000'000) return;  // redraw at most 10 Hz
  last_draw_ns_ = now;
  std::fprintf(stderr, "\r%s\033[K", line(done, ms_per_frame, (now - start_ns_) * 1e-9).c_str());
  std::fflush(stderr);
}

const CLI::Validator kNonEmptyPath(
    [](std::string& value) { return value.empty() ? std::string("an empty file name") : ""; },
    "");  // no name in the help: kExistingFile already says FILE where it applies

const CLI::Validator kExistingFile(
    [](std::string& value) {
      if (value.empty()) return std::string("an empty file name");
      // Devices and pipes pass: the reader refuses them itself, naming them.
      struct stat st {};
      if (::stat(value.c_str(), &st) != 0) {
        const int error = errno;
        return internal::concat("file '", value, "' ",
                      error == ENOENT ? std::string("does not exist")
                                      : internal::concat("cannot be accessed: ", std::strerror(error)));
      }
      return S_ISDIR(st.st_mode) ? internal::concat("file '", value, "' is a folder") : std::string();
    },
    "FILE");

const CLI::Validator kFrameCount(
    [](std::string& value) {
      std::int64_t n = 0;
      std::size_t used = 0;
      try {
        n = std::stoll(value, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || used != value.size() || n < 1 || n > kMaxFrames) {
        return "'" + internal::shown_value(value) + "' is not a frame count from 1 to " + std::to_string(kMaxFrames);
      }
      return std::string();
    },
    "");

CLI::Validator one_of(const std::vector<std::string>& names) {
  std::string all;
  for (const std::string& n : names) all += (all.empty() ? "" : ",") + n;
  return CLI::Validator(
      [names, all](std::string& value) {
        if (std::find(names.begin(), names.end(), value) != names.end()) return std::string();
        return internal::shown_value(value) + " not in {" + all + "}";
      },
      "{" + all + "}");
}

std::vector<std::string> search_mode_list() {
  std::vector<std::string> names;
  for (const SearchMode& m : search_modes()) names.emplace_back(m.name);
  return names;
}

FrameRun run_frames(Detector& detector, const eval::FrameSource& source, const std::string& label,
                    const eval::RunOptions& options, const eval::FrameCallback& on_frame,
                    bool progress, bool report_skips) {
  std::optional<Progress> bar;
  if (progress) bar.emplace(source.frames - options.first, label);
  FrameRun run;
  const std::string advice =
      options.skip_bad_frames ? " (--strict stops here instead)" : std::string();
  run.records = eval::run_detector(
      detector, source,
      [&](const Result& r, const eval::FrameTimes& times) {
        if (on_frame) on_frame(r, times);
        ++run.processed;
        run.total_ms += r.timings.total_ms;
        if (bar) bar->update(run.processed + run.skipped, run.mean_ms());
      },
      options,
      [&](std::int64_t frame, const std::string& name, const std::string& error) {
        // The first kListedSkips each get a line; a list of half a million
        // missing files printed 43 MB over 30 s. The summary counts them all.
        if (report_skips && run.skipped < kListedSkips) {
          std::cerr << "lsgd: skipped frame " + std::to_string(frame) + " (" + name + "): " + error + advice + "\n";
        } else if (report_skips && run.skipped == kListedSkips) {
          std::cerr << "lsgd: more frames skipped; only the first " << kListedSkips
                    << " are listed (the count is in the summary)\n";
        }
        if (run.first_error.empty()) run.first_error = error;
        ++run.skipped;
        if (bar) bar->update(run.processed + run.skipped, run.mean_ms());
      });
  if (detector.size() == 0) throw_no_frame(run.skipped, run.first_error);
  return run;
}

void throw_no_frame(std::int64_t images, const std::string& first_error) {
  // The hint fits when the entries were not images at all.
  const bool not_images = first_error.find("not a decodable image") != std::string::npos ||
                          first_error.find("does not exist") != std::string::npos ||
                          first_error.find("not a regular file") != std::string::npos;
  throw Error("no frame was processed: all " + std::to_string(images) +
              " images were skipped (the first: " + first_error + ")" +
              (not_images ? "; is --sequence a folder of images or a list of their paths?" : ""));
}


namespace {

std::string& recorded_command_line() {
  static std::string line;
  return line;
}

std::string shell_quoted(const std::string& arg) {
  const bool plain = !arg.empty() && arg.find_first_not_of(
      "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./=:,+@%") == std::string::npos;
  if (plain) return arg;
  std::string out = "'";
  for (const char c : arg) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

void set_command_line(int argc, char** argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) {
    line += (i ? " " : "") + shell_quoted(i == 0 ? std::string("lsgd") : std::string(argv[i]));
  }
  recorded_command_line() = line;
}

const std::string& command_line() { return recorded_command_line(); }

std::string version_text() {
  return std::string("lsgd ") + lsgd::version() + " (commit " + lsgd::commit() + ")";
}

void stamp(nlohmann::json& j) {
  j["lsgd_version"] = lsgd::version();
  j["lsgd_commit"] = lsgd::commit();
  j["command"] = command_line();
}

nlohmann::json metrics_json(const eval::Metrics& m) {
  nlohmann::json j;
  j["protocol"] = m.protocol;
  if (m.protocol != "strict") {
    j["protocol_note"] = eval::describe_protocol(m);
    j["tolerance"] = m.tolerance;
  }
  j["frames"] = m.frames;
  j["positives"] = m.positives;
  j["min_gap"] = m.min_gap;
  j["declared_loops"] = m.declared_loops;
  j["declared_true"] = m.declared_true;
  j["declared_false"] = m.declared_false;
  j["precision_at_decision"] = m.precision_at_decision;
  j["recall_at_decision"] = m.recall_at_decision;
  j["recall_at_100_precision"] = m.recall_at_100_precision;
  j["threshold_at_100_precision"] = m.threshold_at_100_precision;
  j["precision_at_100_recall"] = m.precision_at_100_recall;
  j["average_precision"] = m.average_precision;
  j["decision_recall_at_100_precision"] = m.decision_recall_at_100_precision;
  j["decision_threshold_at_100_precision"] = m.decision_threshold_at_100_precision;
  j["decision_average_precision"] = m.decision_average_precision;
  j["recall_at_1"] = m.recall_at_1;
  j["recall_at_5"] = m.recall_at_5;
  j["recall_at_10"] = m.recall_at_10;
  j["prt"] = m.prt;
  j["ms_per_frame_median"] = m.ms_per_frame_median;
  j["ms_per_frame_p95"] = m.ms_per_frame_p95;
  j["ms_per_frame_mean"] = m.ms_per_frame_mean;
  j["stage_ms_median"] = {{"load", m.load_ms_median},         {"convert", m.convert_ms_median},
                          {"segment", m.segment_ms_median},   {"describe", m.describe_ms_median},
                          {"search", m.search_ms_median},     {"verify", m.verify_ms_median}};
  j["stage_ms_p95"] = {{"load", m.load_ms_p95},         {"convert", m.convert_ms_p95},
                       {"segment", m.segment_ms_p95},   {"describe", m.describe_ms_p95},
                       {"search", m.search_ms_p95},     {"verify", m.verify_ms_p95}};
  // Peak resident memory of the whole process so far (getrusage), MB.
  j["peak_rss_mb"] = static_cast<double>(bench::peak_rss_bytes()) / (1024.0 * 1024.0);
  nlohmann::json curve = nlohmann::json::array();
  for (const auto& p : m.curve) curve.push_back({p.threshold, p.precision, p.recall, p.confirmed});
  j["pr_curve"] = {{"columns", {"threshold", "precision", "recall", "confirmed"}}, {"points", curve}};
  return j;
}

namespace {

// Whether R@100P is reached among the ranking's confirmed reports.
bool at_100_confirmed(const eval::Metrics& m) {
  for (const eval::PrPoint& p : m.curve) {
    if (p.false_positives > 0) break;
    if (p.recall >= m.recall_at_100_precision) return p.confirmed;
  }
  return true;
}

}  // namespace

void print_metrics(const eval::Metrics& m, std::int64_t nodes, std::ostream& out) {
  if (m.protocol != "strict") {
    out << "protocol: " << eval::describe_protocol(m) << "\n";
  }
  out << std::fixed << std::setprecision(3);
  out << "frames " << m.frames << ", positives " << m.positives << ", min gap " << m.min_gap << " ("
      << m.protocol << " protocol)\n"
      << "  loops declared " << m.declared_loops << ": " << m.declared_true << " true, "
      << m.declared_false << " false (precision " << m.precision_at_decision << ", recall "
      << m.recall_at_decision << ")" << (m.declared_false > 0 ? "  <- FALSE LOOPS" : "") << "\n"
      << "  R@100P " << m.recall_at_100_precision << "  (threshold "
      << m.threshold_at_100_precision << (at_100_confirmed(m) ? "" : " after every confirmed report")
      << ", chosen with the ground truth)\n"
      << "  AP     " << m.average_precision
      << "   (ranking: the best candidate's appearance, geometry-confirmed first; no decision "
         "setting changes them)\n"
      << "  decision's loop score: R@100P " << m.decision_recall_at_100_precision << ", AP "
      << m.decision_average_precision << "\n"
      << "  R@1    " << m.recall_at_1 << "   R@5 " << m.recall_at_5 << "   R@10 " << m.recall_at_10
      << "\n"
      << "  time   " << std::setprecision(2) << m.ms_per_frame_median << " ms/frame median, "
      << m.ms_per_frame_p95 << " p95 (segment " << m.segment_ms_median << ", describe "
      << m.describe_ms_median << ", search " << m.search_ms_median << ", verify "
      << m.verify_ms_median << ")\n"
      << "  nodes  " << nodes << "\n";
  out.unsetf(std::ios::floatfield);
}

void write_json(const nlohmann::json& json, const std::string& path) {
  nlohmann::json out = json;
  if (out.is_object()) stamp(out);  // every JSON result says what made it
  // A path or name that is not UTF-8 is written with U+FFFD in its place, not an exception.
  io::write_output_file(path, out.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n", "JSON file");
}

}  // namespace lsgd::cli
