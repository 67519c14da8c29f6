// `lsgd run --database`, `lsgd db info` and `lsgd db forget` end to end
// (include/lsgd/io/database.h through tools/lsgd), when the CLI is built.
#include "lsgd/io/database.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "database_test_support.h"
#include "detector_util.h"

namespace lsgd::io {
namespace {

namespace fs = std::filesystem;
using database_test_support::read_bytes;
using database_test_support::temp_path;
using database_test_support::write_bytes;
using test::frame;

#ifdef LSGD_CLI
int run_cli(const std::string& args, const std::string& out = "") {
  const std::string command =
      std::string(LSGD_CLI) + " " + args + (out.empty() ? "" : " > " + out) + " 2>/dev/null";
  return std::system(command.c_str());
}

std::vector<std::string> csv_columns(const std::string& path, std::vector<int> keep) {
  std::vector<std::string> rows;
  for (const std::vector<std::string>& fields : test::csv_rows(path)) {
    std::string row;
    for (const int k : keep) row += (k < static_cast<int>(fields.size()) ? fields[k] : "?") + ",";
    rows.push_back(row);
  }
  return rows;
}

// Frames 0-99 in DIR/a, 100-149 in DIR/b, all of them listed in DIR/all.txt.
std::string write_split_sequence(const std::string& name) {
  const std::string dir = temp_path(name);
  fs::remove_all(dir);
  fs::create_directories(dir + "/a");
  fs::create_directories(dir + "/b");
  std::ofstream all(dir + "/all.txt");
  for (std::int64_t i = 0; i < 150; ++i) {
    char file_name[32];
    std::snprintf(file_name, sizeof(file_name), "/%04d.png", static_cast<int>(i));
    const std::string file = dir + (i < 100 ? "/a" : "/b") + file_name;
    cv::imwrite(file, frame(i));
    all << file << "\n";
  }
  return dir;
}

TEST(DatabaseCli, RunResumesAndDbInfo) {
  const std::string dir = write_split_sequence("cli_frames");
  const std::string db = temp_path("cli.db");
  const std::string flags = " --min-gap 20 --mode nodes";
  ASSERT_EQ(run_cli("run --sequence " + dir + "/all.txt --layout list" + flags + " --output " +
                    dir + "/all.csv"),
            0);
  ASSERT_EQ(run_cli("run --sequence " + dir + "/a --database " + db + flags + " --output " + dir +
                    "/a.csv"),
            0);
  // Resuming takes the stored options; a different min_gap is refused.
  EXPECT_NE(run_cli("run --sequence " + dir + "/b --database " + db + " --min-gap 30"), 0);
  ASSERT_EQ(run_cli("run --sequence " + dir + "/b --database " + db + " --session 7 --output " +
                    dir + "/b.csv"),
            0);
  // frame, loop_frame, candidate_frame, score: equal to the uninterrupted run.
  const auto expected = csv_columns(dir + "/all.csv", {0, 2, 3, 4});
  auto split = csv_columns(dir + "/a.csv", {0, 2, 3, 4});
  const auto tail = csv_columns(dir + "/b.csv", {0, 2, 3, 4});
  split.insert(split.end(), tail.begin() + 1, tail.end());  // skip b.csv's header
  EXPECT_EQ(split, expected);

  ASSERT_EQ(run_cli("db info " + db + " --json", dir + "/info.json"), 0);
  std::ifstream in(dir + "/info.json");
  const nlohmann::json info = nlohmann::json::parse(in);
  EXPECT_EQ(info["frames"], 150);
  EXPECT_EQ(info["format_version"], kDatabaseFormatVersion);
  ASSERT_EQ(info["sessions"].size(), 2u);
  EXPECT_EQ(info["sessions"][0]["session"], 0);
  EXPECT_EQ(info["sessions"][0]["frames"], 100);
  EXPECT_EQ(info["sessions"][1]["session"], 7);
  EXPECT_EQ(info["sessions"][1]["frames"], 50);
  EXPECT_GT(info["nodes"].get<int>(), 0);
  EXPECT_NE(info["options"].get<std::string>().find("mode: nodes"), std::string::npos);
  ASSERT_EQ(run_cli("db info " + db, dir + "/info.txt"), 0);
  const std::string text = read_bytes(dir + "/info.txt");
  EXPECT_NE(text.find("frames: 150"), std::string::npos) << text;
  EXPECT_NE(text.find("session 7: 50 frames"), std::string::npos) << text;

  write_bytes(dir + "/bad.db", "not a database at all, just text that is long enough");
  EXPECT_NE(run_cli("db info " + dir + "/bad.db"), 0);
}

// lsgd db forget: a range of ids in the middle of the last session, then
// the session before it; lsgd run --database resumes the last session at its
// next image, its rows as a detector that forgot the same frames gives them.
TEST(DatabaseCli, ForgetThenResume) {
  const std::string dir = write_split_sequence("cli_forget_frames");
  const std::string db = temp_path("cli_forget.db");
  fs::remove(db);
  const std::string flags = " --min-gap 20 --mode nodes";
  {
    std::ofstream first(dir + "/first.txt");
    std::ifstream all(dir + "/all.txt");
    std::string line;
    for (int i = 0; i < 120 && std::getline(all, line); ++i) first << line << "\n";
  }
  ASSERT_EQ(run_cli("run --sequence " + dir + "/a --database " + db + flags), 0);
  ASSERT_EQ(run_cli("run --sequence " + dir + "/first.txt --layout list --database " + db +
                    " --session 1"),
            0);
  ASSERT_EQ(run_cli("db forget " + db + " --frames 110:114", dir + "/forget.txt"), 0);
  EXPECT_EQ(read_bytes(dir + "/forget.txt"),
            "forgot 5 frames (ids 110 .. 114) of " + db + ": it holds 215 frames in 2 sessions, " +
                std::to_string(fs::file_size(db)) + " bytes\n");
  ASSERT_EQ(run_cli("run --sequence " + dir + "/all.txt --layout list --database " + db +
                    " --output " + dir + "/rest.csv"),
            0);
  // The same frames forgotten by a detector, then the rest processed.
  DetectorOptions o;
  o.search.min_gap = 20;
  o.search.mode = kNodesSearch;
  Detector d(o);
  for (std::int64_t i = 0; i < 100; ++i) d.process(frame(i));
  d.cut();
  for (std::int64_t i = 0; i < 120; ++i) d.process(frame(i));
  EXPECT_EQ(d.forget(110, 114), 5);
  auto rows = csv_columns(dir + "/rest.csv", {0, 2, 3});
  ASSERT_EQ(rows.size(), 31u);  // images 120 .. 149 as ids 220 .. 249
  for (std::int64_t i = 120; i < 150; ++i) {
    const Result r = d.process(frame(i));
    EXPECT_EQ(rows[static_cast<std::size_t>(i - 119)],
              std::to_string(r.id) + "," + std::to_string(r.loop ? d.id_of(r.best.frame) : -1) + "," +
                  std::to_string(r.best.frame >= 0 ? d.id_of(r.best.frame) : -1) + ",")
        << "image " << i;
  }
  ASSERT_EQ(run_cli("db forget " + db + " --session 0", dir + "/forget.txt"), 0);
  ASSERT_EQ(run_cli("db info " + db + " --json", dir + "/info.json"), 0);
  std::ifstream in(dir + "/info.json");
  const nlohmann::json info = nlohmann::json::parse(in);
  EXPECT_EQ(info["frames"], 145);
  EXPECT_EQ(info["rows_verified"], true);
  ASSERT_EQ(info["sessions"].size(), 1u);
  EXPECT_EQ(info["sessions"][0]["first_frame"], 100);
  // Nothing left to do: every image of the session is stored.
  ASSERT_EQ(run_cli("run --sequence " + dir + "/all.txt --layout list --database " + db), 0);
  ASSERT_EQ(run_cli("db info " + db + " --json", dir + "/info.json"), 0);
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(dir + "/info.json"))["frames"], 145);
  // Refused: no selection, both, a backward or malformed range, an unknown session.
  EXPECT_NE(run_cli("db forget " + db), 0);
  EXPECT_NE(run_cli("db forget " + db + " --session 1 --frames 0:5"), 0);
  EXPECT_NE(run_cli("db forget " + db + " --frames 9:3"), 0);
  EXPECT_NE(run_cli("db forget " + db + " --frames 3-9"), 0);
  EXPECT_NE(run_cli("db forget " + db + " --session 0"), 0);
}

// lsgd run --database in index mode saves the graph when it ends and the
// next run resumes from it (or rebuilds it with --rebuild-index): both equal
// to the uninterrupted run.
TEST(DatabaseCli, IndexModeSavesItsGraph) {
  const std::string dir = write_split_sequence("cli_index_frames");
  const std::string flags = " --min-gap 20 --mode index --option search.index.exhaustive_up_to=0";
  ASSERT_EQ(run_cli("run --sequence " + dir + "/all.txt --layout list" + flags + " --output " +
                    dir + "/all.csv"),
            0);
  const auto expected = csv_columns(dir + "/all.csv", {0, 2, 3, 4});
  for (const std::string resume : {"", " --rebuild-index"}) {
    SCOPED_TRACE(resume);
    const std::string db = temp_path("cli_index.db");
    ASSERT_EQ(run_cli("run --sequence " + dir + "/a --database " + db + flags + " --output " + dir +
                      "/a.csv"),
              0);
    ASSERT_EQ(run_cli("db info " + db + " --json", dir + "/info.json"), 0);
    std::ifstream in(dir + "/info.json");
    const nlohmann::json info = nlohmann::json::parse(in);
    EXPECT_EQ(info["index_frames"], 100 - 20 - 1);  // the frames that left the temporal window
    EXPECT_GT(info["index_bytes"].get<int>(), 0);
    ASSERT_EQ(run_cli("run --sequence " + dir + "/b --database " + db + " --session 7 --output " +
                      dir + "/b.csv" + resume),
              0);
    auto split = csv_columns(dir + "/a.csv", {0, 2, 3, 4});
    const auto tail = csv_columns(dir + "/b.csv", {0, 2, 3, 4});
    split.insert(split.end(), tail.begin() + 1, tail.end());
    EXPECT_EQ(split, expected);
    ASSERT_EQ(run_cli("db info " + db, dir + "/info.txt"), 0);
    const std::string text = read_bytes(dir + "/info.txt");
    EXPECT_NE(text.find("saved search index: 129 frames"), std::string::npos) << text;
  }
}
#endif

}  // namespace
}  // namespace lsgd::io
