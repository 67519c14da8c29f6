// lsgd db info FILE [--json]: what a detector database (lsgd run --database) holds.
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.h"
#include "common.h"
#include "lsgd/error.h"
#include "lsgd/io/database.h"

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
    std::cout << j.dump(2) << "\n";
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

}  // namespace

void register_db(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("db", "inspect a detector database (lsgd run --database)");
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
}

}  // namespace lsgd::cli
