// lsgd run --sequence PATH [--config FILE] [--output FILE] [--database FILE [--session N]]
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>

#include "commands.h"
#include "common.h"
#include "files.h"
#include "lsgd/error.h"
#include "lsgd/eval/runner.h"
#include "lsgd/io/config.h"
#include "lsgd/io/database.h"
#include "lsgd/io/layouts.h"

namespace lsgd::cli {
namespace {

struct RunArgs {
  std::string sequence;
  std::string output;
  DetectorFlags detector;
  SequenceFlags layout;
  std::string database;                 // SQLite file to create or resume; empty: none
  std::optional<std::int64_t> session;  // session id of this run's frames
};

// --database: creates FILE or resumes the detector it holds, appends every
// frame (one transaction each). Resuming takes the stored options; flags and
// --config must agree with them except --threshold. Frame ids (CSV column
// frame) continue after the stored frames.
// The command's files: nothing it writes may be something it reads.
void check_files(const RunArgs& args, const io::Sequence& sequence) {
  CommandFiles files;
  files.input(args.detector.config, "--config");
  files.input(args.sequence, "--sequence");
  files.inputs(sequence.images, "--sequence", "input image");
  files.database(args.database, "--database", true);
  files.output(args.output, "--output");
  files.check();
}

void run_database(const RunArgs& args, const io::Sequence& sequence) {
  check_files(args, sequence);
  const DetectorFlags& flags = args.detector;
  const bool exists = std::ifstream(args.database).good();
  std::optional<io::Database> db;
  DetectorOptions options;
  if (exists) {
    db.emplace(io::Database::open(args.database));
    options = flags.config.empty() ? db->options() : io::load_config(flags.config);
    if (!flags.mode.empty()) options.search.mode = parse_search_mode(flags.mode.c_str());
    if (flags.min_gap) options.search.min_gap = *flags.min_gap;
    if (flags.threshold) options.decision.threshold = *flags.threshold;
    if (!flags.verify.empty()) parse_verification_stages(flags.verify, options.verification);
    options.check();
  } else {
    options = flags.resolve();
    db.emplace(io::Database::create(args.database, options));
  }
  Detector detector(options);
  db->restore(detector);  // checks the options against the stored ones
  const std::int64_t session = args.session ? *args.session : db->last_session() + 1;
  std::cerr << (exists ? "resumed " : "created ") << args.database << ": " << detector.size()
            << " frames stored, appending session " << session << "\n";
  const eval::FrameSource source = eval::sequence_source(sequence);
  CsvWriter csv(args.output);
  Progress progress(source.frames, "run");
  double total_ms = 0;
  std::int64_t processed = 0;
  std::string first_skip;
  for (std::int64_t i = 0; i < source.frames; ++i) {
    Result result;
    try {
      result = detector.process(source.load(i));
    } catch (const Error& e) {
      const std::string where = "frame " + std::to_string(i) + " (" + source.name(i) + "): ";
      if (args.layout.strict) throw Error(where + e.what());
      std::cerr << "lsgd: skipped " << where << e.what() << " (--strict stops here instead)\n";
      if (first_skip.empty()) first_skip = e.what();
      continue;  // nothing stored: the database only ever holds processed frames
    }
    ++processed;
    db->append(detector, result, session, source.name(i));
    csv.write(result, source.name(i));
    total_ms += result.timings.total_ms;
    progress.update(i + 1, total_ms / static_cast<double>(processed));
  }
  if (processed == 0) {
    // A database this run created and left empty is not left behind.
    if (!exists && db->frames() == 0) {
      db.reset();
      for (const char* suffix : {"", "-wal", "-shm"}) std::remove((args.database + suffix).c_str());
    }
    throw_no_frame(source.frames, first_skip);
  }
  const std::int64_t skipped = source.frames - processed;
  std::cerr << "processed " << processed << " frames"
            << (skipped > 0 ? " (" + std::to_string(skipped) + " skipped)" : std::string()) << ", "
            << csv.loops() << " loops, " << total_ms / static_cast<double>(processed)
            << " ms/frame mean; " << args.database << " holds " << db->frames() << " frames"
            << (args.output.empty() ? "" : ", rows in " + args.output) << "\n";
}

void run(const RunArgs& args) {
  if (args.session && args.database.empty()) {
    throw InvalidArgument("--session needs --database");
  }
  if (args.session && *args.session < 0) {
    throw InvalidArgument("--session " + std::to_string(*args.session) + " must be >= 0");
  }
  if (!args.database.empty()) {
    run_database(args, io::open_sequence(args.sequence, args.layout.resolve()));
    return;
  }
  const DetectorOptions options = args.detector.resolve();
  const io::Sequence sequence = io::open_sequence(args.sequence, args.layout.resolve());
  check_files(args, sequence);
  const eval::FrameSource source = eval::sequence_source(sequence);
  CsvWriter csv(args.output);
  Detector detector(options);
  const auto records = run_with_progress(detector, source, "run", &csv, !args.layout.strict);
  double total_ms = 0;
  for (const auto& r : records) total_ms += r.timings.total_ms;
  const std::int64_t skipped = skipped_frames(records);
  const auto processed = static_cast<std::int64_t>(records.size()) - skipped;
  std::cerr << "processed " << processed << " frames"
            << (skipped > 0 ? " (" + std::to_string(skipped) + " skipped)" : std::string()) << ", "
            << csv.loops() << " loops, "
            << total_ms / static_cast<double>(std::max<std::int64_t>(processed, 1))
            << " ms/frame mean"
            << (args.output.empty() ? "" : ", rows in " + args.output) << "\n";
}

}  // namespace

void register_run(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("run", "detect loops in an image sequence, one CSV row per frame");
  cmd->add_option("--sequence", args->sequence,
                  "folder of images (natural order), list file, or a dataset layout (--layout)")
      ->required();
  cmd->add_option("--output", args->output, "CSV file to write (default: standard output)");
  args->detector.add_to(*cmd);
  args->layout.add_to(*cmd);
  cmd->add_option("--database", args->database,
                  "SQLite file keeping the detector's state: created when missing, else resumed "
                  "(its options apply; frames are appended, one transaction each)");
  cmd->add_option("--session", args->session,
                  "session id of this run's frames in --database (default: last session + 1, "
                  "0 for a new database)");
  cmd->callback([args] { run(*args); });
}

}  // namespace lsgd::cli
