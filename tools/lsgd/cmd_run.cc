// lsgd run --sequence PATH [--config FILE] [--output FILE] [--database FILE [--session N | --localize]]
//
// Frame ids (README, "Frame ids"): image i of the sequence (after --first,
// --last, --every) is frame first_id + i, whether or not earlier images were
// skipped; first_id is 0 without a database and for a database's first
// session, and one past the last stored frame for a new session. A run
// re-started with the same sequence continues the session it interrupted.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
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
#include "lsgd/io/session.h"
#include "lsgd/limits.h"

namespace lsgd::cli {
namespace {

namespace fs = std::filesystem;

struct RunArgs {
  std::string sequence;
  std::string output;
  DetectorFlags detector;
  SequenceFlags layout;
  std::string database;                 // SQLite file to create or resume; empty: none
  bool rebuild_index = false;           // ignore the database's saved search index
  std::optional<std::int64_t> session;  // session id of this run's frames
  bool localize = false;                // --database read-only: a session localised in memory
};

// The command's files: nothing it writes may be something it reads.
void check_files(const RunArgs& args, const io::Sequence& sequence) {
  CommandFiles files;
  files.input(args.detector.config, "--config");
  files.input(args.sequence, "--sequence");
  files.sequence(sequence, "--sequence", "input image");
  files.database(args.database, "--database", true);
  files.output_or_stdout(args.output, "--output");
  files.check();
}

const char* kNewSessionHint = "; pass --session N with a new N to store them as a new session";

// True when a CSV row's `image` is `expected`, this run's spelling of the
// image (the run writes the sequence's own): the same text or absolute path,
// or the relative path a run from another folder wrote for that file.
bool same_row_image(const std::string& image, const std::string& expected) {
  if (image == expected || io::same_image(image, io::stored_image_name(expected))) return true;
  if (image.empty() || image[0] == '/') return false;
  fs::path tail;  // the relative path without its leading "." and ".." parts
  for (const fs::path& part : fs::path(image).lexically_normal()) {
    if (tail.empty() && (part == "." || part == "..")) continue;
    tail /= part;
  }
  const std::string full = io::stored_image_name(expected), end = "/" + tail.string();
  return !tail.empty() && full.size() > end.size() &&
         full.compare(full.size() - end.size(), end.size(), end) == 0;
}

// The rows of a CSV an interrupted run of the session wrote: rows of frames
// the database does not hold (at most the one being committed when the run
// stopped) are cut, so the file again has one row per stored frame. The rows
// at the cut must name the images this run has at their frames (the ones
// the database stores: plan_session() checked the session's frames against
// the sequence); another run's CSV is refused, untouched.
std::unique_ptr<CsvWriter> continue_csv(const RunArgs& args, const io::Sequence& sequence,
                                        const io::SessionPlan& plan) {
  struct stat st {};
  if (args.output.empty() || ::stat(args.output.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
    return std::make_unique<CsvWriter>(args.output);
  }
  const auto images = static_cast<std::int64_t>(sequence.images.size());
  const auto check = [&](std::int64_t frame, const std::string& image) {
    const std::int64_t index = frame - plan.first_id;
    const bool ours = index >= 0 && index < images;
    if (ours && same_row_image(image, sequence.images[static_cast<std::size_t>(index)])) return;
    throw InvalidArgument(
        args.output + " holds another run's rows: its row of frame " + std::to_string(frame) +
        " names " + image + ", but " +
        (ours ? "this run's frame " + std::to_string(frame) + " is " +
                    sequence.images[static_cast<std::size_t>(index)] +
                    (frame <= plan.last_stored ? " (as " + args.database + " stores it)" : "")
              : "frame " + std::to_string(frame) + " is no image of this run (its frames are " +
                    std::to_string(plan.first_id) + " .. " +
                    std::to_string(plan.first_id + images - 1) + ")") +
        ": give that run's CSV as --output, or another --output (" + args.output +
        " was left as it was)");
  };
  const CsvWriter::Trim trim = CsvWriter::trim(args.output, plan.last_stored, check);
  // One row may be ahead of the database: the frame being committed when the
  // run stopped (its row is written first). More means committed frames were lost.
  if (trim.dropped > 1) {
    std::cerr << "lsgd: warning: " << args.output << " had rows for " << trim.dropped
              << " frames after frame " << plan.last_stored
              << ", the last one " << args.database
              << " holds: frames forgotten (lsgd db forget), or committed frames lost (a damaged or "
                 "deleted write-ahead log); they are processed again\n";
  }
  if (trim.other > 0) {
    std::cerr << "lsgd: note: " << args.output << " had " << trim.other
              << " lines that are no row of lsgd run after its rows; they are cut\n";
  }
  if (trim.last_row != plan.last_stored) {
    std::cerr << "lsgd: note: " << args.output << " ends at frame " << trim.last_row
              << ", but session " << plan.session << " holds frames up to " << plan.last_stored
              << " (their rows went to another output)\n";
  }
  return std::make_unique<CsvWriter>(args.output, CsvWriter::kAppend, trim.version);
}

// Frames of another size than the stored ones are refused up front, once,
// rather than skipped one by one: the first image of the run that can be read
// decides (a map keeps one frame size).
void check_frame_size(const std::string& database, const Detector& detector,
                      const eval::FrameSource& source, std::int64_t first) {
  if (detector.size() == 0) return;
  for (std::int64_t i = first; i < source.frames; ++i) {
    cv::Mat image;
    try {
      image = source.load(i);
    } catch (const Error&) {
      continue;  // the run reports it in its place
    }
    if (image.cols == detector.width() && image.rows == detector.height()) return;
    throw InvalidArgument("database " + database + " holds " + std::to_string(detector.width()) + "x" +
                          std::to_string(detector.height()) + " frames, but " + source.name(i) + " is " +
                          std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                          ": a map keeps one frame size (resize the images, or give another --database)");
  }
}

// Opens --database when it exists (the options: --config's, else the stored
// ones, with the flags applied) or creates it with the options the flags give.
io::Database open_or_create(const RunArgs& args, bool exists, DetectorOptions& options) {
  const DetectorFlags& flags = args.detector;
  if (!exists) {
    options = flags.resolve();
    return io::Database::create(args.database, options);
  }
  io::Database db = io::Database::open(args.database);
  if (!db.note().empty()) std::cerr << "lsgd: note: " << args.database << ": " << db.note() << "\n";
  options = flags.config.empty() ? db.options() : io::load_config(flags.config);
  flags.apply(options);
  return db;
}

// Saves the search index of the stored frames (not when the detector holds a
// frame the database lacks).
void save_index(io::Database& db, const Detector& detector) {
  if (detector.size() != db.frames()) return;
  const auto start = std::chrono::steady_clock::now();
  const std::int64_t covered = db.save_index(detector);
  if (covered > 0) {
    std::cerr << "saved the search index of " << covered << " frames in "
              << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
              << " s\n";
  }
}

void print_session_start(const std::string& database, bool exists, const Detector& detector,
                         const io::SessionPlan& plan, std::int64_t images) {
  std::cerr << (exists ? "resumed " : "created ") << database << ": " << detector.size()
            << " frames stored; "
            << (plan.resume ? "continuing session " : "appending session ") << plan.session
            << (plan.resume ? " at image " + std::to_string(plan.first) : std::string())
            << ", frame ids " << plan.first_id + plan.first << " .. "
            << plan.first_id + images - 1 << "\n";
}

// Processes the session's images, writing each frame's row and storing the
// frame. The search index is saved when the run ends, also when an error ends
// it (what the frames stored so far built is kept).
FrameRun store_frames(const RunArgs& args, const io::Sequence& sequence,
                      const eval::FrameSource& source, const io::SessionPlan& plan,
                      Detector& detector, io::Database& db, CsvWriter& csv) {
  eval::RunOptions run_options;
  run_options.skip_bad_frames = !args.layout.strict;
  run_options.first = plan.first;
  run_options.first_id = plan.first_id;
  run_options.stored_ids = db.frame_ids();
  run_options.keep_records = false;
  // The row is written (and flushed) before the frame is committed: after a
  // crash the CSV holds at most one row the database lacks, which the
  // re-run cuts (continue_csv).
  FrameRun run;
  try {
    run = run_frames(
        detector, source, "run", run_options, [&](const Result& r, const eval::FrameTimes&) {
          const std::string& image = sequence.images[static_cast<std::size_t>(r.frame - plan.first_id)];
          csv.write(r, image);
          db.append(detector, r, plan.session, io::stored_image_name(image), r.frame);
        });
  } catch (const std::exception& error) {
    try {
      save_index(db, detector);
    } catch (const std::exception& e) {
      // (The same error again, a file replaced under the run: said once, by the error.)
      if (std::strcmp(e.what(), error.what()) != 0) {
        std::cerr << "lsgd: note: the search index was not saved (" << e.what() << ")\n";
      }
    }
    throw;
  }
  save_index(db, detector);
  return run;
}

// Runs the sequence as a session of `db` (opened or, when not `exists`,
// created with `options`).
void run_session(const RunArgs& args, const io::Sequence& sequence, bool exists,
                 const DetectorOptions& options, io::Database& db) {
  Detector detector(options);
  // Checks the options against the stored ones; the saved search index
  // (index mode's graph) comes back with the frames.
  db.restore(detector, args.rebuild_index ? io::IndexUse::kRebuild : io::IndexUse::kSaved);
  const eval::FrameSource source = eval::sequence_source(sequence);
  const io::SessionPlan plan = io::plan_session(db, detector, sequence.images, args.session);
  const auto images = static_cast<std::int64_t>(sequence.images.size());
  if (plan.resume && plan.first >= images) {
    std::cerr << args.database << ": session " << plan.session << " already holds every image "
              << "of --sequence (frames " << plan.first_id << " .. " << plan.last_stored
              << "): nothing to do" << kNewSessionHint << "\n";
    return;
  }
  check_frame_size(args.database, detector, source, plan.first);
  print_session_start(args.database, exists, detector, plan, images);
  // A new session is another sequence: nothing continues across it.
  io::begin_session(detector, plan);
  const std::unique_ptr<CsvWriter> csv =
      plan.resume ? continue_csv(args, sequence, plan) : std::make_unique<CsvWriter>(args.output);
  const FrameRun run = store_frames(args, sequence, source, plan, detector, db, *csv);
  // A new session that stored nothing is an error as a new database is
  // (frames of another size than the stored ones, a list of garbage).
  if (run.processed == 0 && !plan.resume) throw_no_frame(run.skipped, run.first_error);
  db.close();  // its last checkpoint, and that the path still names the file written
  std::cerr << "processed " << run.processed << " frames"
            << (run.skipped > 0 ? " (" + std::to_string(run.skipped) + " skipped)"
                                : std::string())
            << ", " << csv->loops() << " loops, " << run.mean_ms() << " ms/frame mean; "
            << args.database << " holds " << db.frames() << " frames"
            << (args.output.empty() ? "" : ", rows in " + args.output) << "\n";
}

void run_database(const RunArgs& args, const io::Sequence& sequence) {
  check_files(args, sequence);
  struct stat st {};
  const bool exists = ::stat(args.database.c_str(), &st) == 0;  // also when unreadable
  std::optional<io::Database> db;
  DetectorOptions options;
  db.emplace(open_or_create(args, exists, options));
  try {
    run_session(args, sequence, exists, options, *db);
  } catch (...) {
    // A database this run created and could not store a frame in is not left behind.
    if (!exists && db && db->frames() == 0) {
      db.reset();
      for (const char* suffix : {"", "-wal", "-shm"}) std::remove((args.database + suffix).c_str());
    }
    throw;
  }
}

// --localize: the map is opened read-only and restored; the sequence is a new
// session processed against it in memory (its frames join the in-memory map
// as they come, so each has the sequence of the session's own frames before
// it), and nothing is written to the file. Frame ids continue the map's.
void run_localize(const RunArgs& args, const io::Sequence& sequence) {
  CommandFiles files;
  files.input(args.detector.config, "--config");
  files.input(args.sequence, "--sequence");
  files.sequence(sequence, "--sequence", "input image");
  files.input(args.database, "--database");
  files.output_or_stdout(args.output, "--output");
  files.check();
  const io::Database db = io::Database::open(args.database, io::Database::Mode::kReadOnly);
  DetectorOptions options = args.detector.config.empty() ? db.options() : io::load_config(args.detector.config);
  args.detector.apply(options);
  Detector detector(options);
  db.restore(detector, args.rebuild_index ? io::IndexUse::kRebuild : io::IndexUse::kSaved);
  if (detector.size() == 0) {
    throw InvalidArgument("--localize: database " + args.database + " holds no frame to localise against");
  }
  const eval::FrameSource source = eval::sequence_source(sequence);
  check_frame_size(args.database, detector, source, 0);
  // A new session: nothing continues across it.
  detector.cut();
  CsvWriter csv(args.output);
  eval::RunOptions run_options;
  run_options.skip_bad_frames = !args.layout.strict;
  run_options.keep_records = false;
  run_options.stored_ids = db.frame_ids();
  run_options.first_id = run_options.stored_ids.back() + 1;
  const auto images = static_cast<std::int64_t>(sequence.images.size());
  std::cerr << "localising against " << args.database << " (read-only, " << detector.size()
            << " frames): frame ids " << run_options.first_id << " .. "
            << run_options.first_id + images - 1 << ", nothing stored\n";
  const FrameRun run = run_frames(detector, source, "run", run_options,
                                  [&](const Result& r, const eval::FrameTimes&) {
                                    csv.write(r, source.name(r.frame - run_options.first_id));
                                  });
  if (run.processed == 0) throw_no_frame(run.skipped, run.first_error);
  std::cerr << "processed " << run.processed << " frames"
            << (run.skipped > 0 ? " (" + std::to_string(run.skipped) + " skipped)" : std::string())
            << ", " << csv.loops() << " loops, " << run.mean_ms() << " ms/frame mean; "
            << args.database << " unchanged" << (args.output.empty() ? "" : ", rows in " + args.output)
            << "\n";
}

void run(const RunArgs& args) {
  if (args.session && args.database.empty()) {
    throw InvalidArgument("--session needs --database");
  }
  if (args.rebuild_index && args.database.empty()) {
    throw InvalidArgument("--rebuild-index needs --database (the map whose saved index to rebuild)");
  }
  if (args.localize && args.database.empty()) {
    throw InvalidArgument("--localize needs --database (the map to localise against)");
  }
  if (args.localize && args.session) {
    throw InvalidArgument("--localize stores nothing, so it takes no --session");
  }
  if (args.localize) {
    run_localize(args, io::open_sequence(args.sequence, args.layout.resolve()));
    return;
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
  eval::RunOptions run_options;
  run_options.skip_bad_frames = !args.layout.strict;
  run_options.keep_records = false;
  const FrameRun run = run_frames(detector, source, "run", run_options,
                                  [&](const Result& r, const eval::FrameTimes&) {
                                    csv.write(r, source.name(r.frame));
                                  });
  std::cerr << "processed " << run.processed << " frames"
            << (run.skipped > 0 ? " (" + std::to_string(run.skipped) + " skipped)" : std::string())
            << ", " << csv.loops() << " loops, " << run.mean_ms() << " ms/frame mean"
            << (args.output.empty() ? "" : ", rows in " + args.output) << "\n";
}

}  // namespace

void register_run(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("run", "detect loops in an image sequence, one CSV row per frame");
  cmd->add_option("--sequence", args->sequence,
                  "folder of images (natural order), list file, or a dataset layout (--layout)")
      ->required()
      ->check(kNonEmptyPath);
  cmd->add_option("--output", args->output, "CSV file to write (default: standard output)")
      ->check(kNonEmptyPath);
  args->detector.add_to(*cmd);
  args->layout.add_to(*cmd);
  cmd->add_option("--database", args->database,
                  "SQLite file keeping the detector's state: created when missing, else resumed "
                  "(its options apply; frames are appended, one transaction each; a re-run "
                  "with the same sequence continues the session it interrupted)")
      ->check(kNonEmptyPath);
  cmd->add_option("--session", args->session,
                  "session id of this run's frames in --database (default: continue the last "
                  "session when --sequence is its sequence, else last session + 1; 0 for a new "
                  "database)")
      ->check(CLI::Range(std::int64_t{0}, kMaxSession));
  cmd->add_flag("--localize", args->localize,
                "with --database: open it read-only and localise --sequence against it, as a "
                "new session kept in memory; nothing is written to the file");
  cmd->add_flag("--rebuild-index", args->rebuild_index,
                "with --database: ignore the search index saved in it (index mode's graph) and "
                "rebuild it from the stored frames");
  cmd->callback([args] { run(*args); });
}

}  // namespace lsgd::cli
