// lsgd db info FILE [--json]: what a detector database (lsgd run --database) holds.
// lsgd db forget FILE (--session S | --frames FIRST:LAST): removes frames from it.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <iostream>
#include <optional>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.h"
#include "common.h"
#include "internal/check.h"
#include "internal/numbers.h"
#include "lsgd/error.h"
#include "lsgd/io/database.h"
#include "lsgd/limits.h"

namespace lsgd::cli {
namespace {

struct DbInfoArgs {
  std::string path;
  bool json = false;
};

// Prints what the database holds, then checks every row as a resume would;
// a damaged row is an error naming the frame (exit 1) after the summary.
void db_info(const DbInfoArgs& args) {
  const io::Database db = io::Database::open(args.path, io::Database::Mode::kReadOnly);
  const io::DatabaseInfo info = db.info();
  std::string damage;
  try {
    db.verify();
  } catch (const FormatError& e) {
    damage = e.what();
  }
  if (args.json) {
    nlohmann::json sessions = nlohmann::json::array();
    for (const io::SessionInfo& s : info.sessions) {
      sessions.push_back({{"session", s.session},
                          {"frames", s.frames},
                          {"first_frame", s.first_frame},
                          {"last_frame", s.last_frame}});
    }
    nlohmann::json j = {{"path", info.path},
                              {"format_version", info.format_version},
                              {"library_version", info.library_version},
                              {"width", info.width},
                              {"height", info.height},
                              {"grid", {{"rows", info.grid.rows}, {"cols", info.grid.cols}}},
                              {"frames", info.frames},
                              {"sessions", sessions},
                              {"nodes", info.nodes},
                              {"index_frames", info.index_frames},
                              {"index_bytes", info.index_bytes},
                              {"bytes", info.bytes},
                              {"note", info.note},
                              {"rows_verified", damage.empty()},
                              {"damage", damage},
                              {"options", info.options_yaml}};
    stamp(j);
    std::cout << j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
  } else {
    std::cout << "database: " << info.path << "\n"
              << "format version: " << info.format_version << " (written by lsgd "
              << info.library_version << ")\n"
              << "frame size: " << info.width << "x" << info.height << ", grid " << info.grid.rows
              << "x" << info.grid.cols << "\n"
              << "frames: " << info.frames << "\n"
              << "sessions: " << info.sessions.size() << "\n";
    for (const io::SessionInfo& s : info.sessions) {
      std::cout << "  session " << s.session << ": " << s.frames << " frames, ids "
                << s.first_frame << " .. " << s.last_frame << "\n";
    }
    std::cout << "nodes: " << info.nodes << "\n"
              << "saved search index: "
              << (info.index_frames > 0 ? std::to_string(info.index_frames) + " frames, " +
                                              std::to_string(info.index_bytes) + " bytes"
                                        : std::string("none"))
              << "\n"
              << "bytes: " << info.bytes << "\n";
    if (!info.note.empty()) std::cout << "note: " << info.note << "\n";
    std::cout << "rows: " << (damage.empty() ? "all " + std::to_string(info.frames) + " verified (types, sizes, checksums, nodes, ids)" : "DAMAGED") << "\n"
              << "options:\n";
    std::string line;
    std::istringstream yaml(info.options_yaml);
    while (std::getline(yaml, line)) std::cout << "  " << line << "\n";
  }
  if (!damage.empty()) throw FormatError(damage);
}

struct DbForgetArgs {
  std::string path;
  std::optional<std::int64_t> session;
  std::string frames;  // FIRST:LAST, caller ids, either end may be left out
};

// "FIRST:LAST", "FIRST:" or ":LAST" as an inclusive range of frame ids.
std::pair<std::int64_t, std::int64_t> parse_id_range(const std::string& text) {
  const auto colon = text.find(':');
  const auto bad = [&](const std::string& why) {
    return InvalidArgument("--frames '" + internal::shown_value(text) + "': " + why +
                           " (FIRST:LAST, frame ids as lsgd run numbered them; FIRST: or :LAST for "
                           "an open end)");
  };
  if (colon == std::string::npos || text.find(':', colon + 1) != std::string::npos) {
    throw bad("not FIRST:LAST");
  }
  const auto number = [&](const std::string& part, std::int64_t open) {
    if (part.empty()) return open;
    // Decimal as typed: stoll skipped leading spaces and newlines (' 5:'
    // was 5, '5: ' an error).
    std::int64_t v = 0;
    if (!internal::parses_as(part, v) || v < 0 || v > kMaxFrameId) {
      throw bad("'" + internal::shown_value(part) + "' is not a frame id in [0, " +
                std::to_string(kMaxFrameId) + "]");
    }
    return v;
  };
  const std::int64_t first = number(text.substr(0, colon), 0);
  const std::int64_t last = number(text.substr(colon + 1), kMaxFrameId);
  if (first > last) throw bad("the first id is above the last");
  return {first, last};
}

void db_forget(const DbForgetArgs& args) {
  if (args.session.has_value() == !args.frames.empty()) {
    throw InvalidArgument("lsgd db forget: give --session S or --frames FIRST:LAST (one of them)");
  }
  // The range is read before the database is opened for writing.
  const auto [first, last] =
      args.session ? std::pair<std::int64_t, std::int64_t>() : parse_id_range(args.frames);
  io::Database db = io::Database::open(args.path);
  const bool had_index = db.info().index_frames > 0;
  std::int64_t forgotten = 0;
  std::string what;
  if (args.session) {
    forgotten = db.forget_session(*args.session);
    what = "session " + std::to_string(*args.session);
  } else {
    forgotten = db.forget(first, last);
    what = last == kMaxFrameId ? "ids from " + std::to_string(first)
           : first == 0       ? "ids up to " + std::to_string(last)
                              : "ids " + std::to_string(first) + " .. " + std::to_string(last);
  }
  const io::DatabaseInfo info = db.info();
  db.close();  // its last checkpoint, and that the path still names the file changed
  if (forgotten == 0) {
    std::cout << args.path << ": no frame has " << what << ": nothing forgotten\n";
    return;
  }
  std::cout << "forgot " << forgotten << " frames (" << what << ") of " << args.path << ": it holds "
            << info.frames << " frames in " << info.sessions.size() << " sessions, " << info.bytes
            << " bytes"
            << (had_index ? "; its saved search index was dropped (the next lsgd run --database "
                            "builds it again)"
                          : "")
            << "\n";
}

}  // namespace

void register_db(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "db", "inspect a detector database (lsgd run --database), or forget frames of it");
  cmd->require_subcommand(1);
  auto args = std::make_shared<DbInfoArgs>();
  CLI::App* info = cmd->add_subcommand(
      "info",
      "format version, options, frames per session, nodes and size of a database; checks "
      "every row (exit 1 naming the first damaged frame)");
  info->add_option("FILE", args->path, "database written by lsgd run --database")
      ->required()
      ->check(kNonEmptyPath);
  info->add_flag("--json", args->json, "print JSON instead of text");
  info->callback([args] { db_info(*args); });

  auto forget_args = std::make_shared<DbForgetArgs>();
  CLI::App* forget = cmd->add_subcommand(
      "forget",
      "removes a session or a range of frame ids from a database, in place, in one transaction: "
      "the kept frames keep their ids, their nodes and state as if the forgotten frames had never "
      "been part of the map; lsgd run --database resumes it as before");
  forget->add_option("FILE", forget_args->path, "database written by lsgd run --database")
      ->required()
      ->check(kNonEmptyPath);
  forget->add_option("--session", forget_args->session, "forget every frame of this session");
  forget->add_option("--frames", forget_args->frames,
                     "forget the frames whose ids lie in FIRST:LAST (inclusive; FIRST: or :LAST "
                     "for an open end), ids as lsgd run numbered them (the CSV's frame column)");
  forget->callback([forget_args] { db_forget(*forget_args); });
}

}  // namespace lsgd::cli
