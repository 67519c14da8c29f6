// End-to-end tests of what the lsgd commands may write (tools/lsgd/files.h):
// no output is ever an input or another output (by inode, whatever the
// spelling: other paths, hard links, symbolic links), and an output that
// cannot be written stops the command before any work. Each refusal leaves
// every file as it was.
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli_util.h"

namespace fs = std::filesystem;

namespace {

const fs::path kTmp = fs::path(LSGD_TEST_TMP) / ("files-cli-" + std::to_string(getpid()));

using lsgd::test::CmdResult;
using lsgd::test::slurp;

CmdResult lsgd(const std::string& args) { return lsgd::test::run_command(LSGD_CLI, args, kTmp); }

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// A small sequence: 60 noise images, a list file, a pairs ground truth and a
// config, written once.
class Files : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::remove_all(kTmp);
    dir_ = kTmp / "seq";
    fs::create_directories(dir_ / "images");
    std::ofstream list(dir_ / "sequence.txt");
    cv::Mat m(48, 64, CV_8UC1);
    for (int i = 0; i < 60; ++i) {
      cv::randu(m, 0, 255);
      const std::string name = "images/" + std::to_string(1000 + i) + ".png";
      ASSERT_TRUE(cv::imwrite((dir_ / name).string(), m));
      list << name << "\n";
    }
    list.close();
    std::ofstream(dir_ / "gt.txt") << "50 5\n55 8\n";
    std::ofstream(dir_ / "config.yaml") << "search: {min_gap: 5}\n";
  }
  static void TearDownTestSuite() { fs::remove_all(kTmp); }

  // Runs `args` and expects a refusal naming `part`, with `guarded` unchanged.
  static void expect_refused(const std::string& args, const std::string& part,
                             const std::vector<fs::path>& guarded) {
    std::vector<std::string> before;
    for (const fs::path& p : guarded) before.push_back(slurp(p));
    const CmdResult r = lsgd(args);
    EXPECT_NE(r.code, 0) << args;
    EXPECT_NE(r.err.find(part), std::string::npos) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("nothing was run"), std::string::npos) << r.err;
    for (std::size_t i = 0; i < guarded.size(); ++i) {
      EXPECT_EQ(slurp(guarded[i]), before[i]) << guarded[i] << " changed by " << args;
    }
  }

  static fs::path dir_;
};
fs::path Files::dir_;

TEST_F(Files, AnOutputIsNeverAnInput) {
  const fs::path seq = dir_ / "sequence.txt", gt = dir_ / "gt.txt", config = dir_ / "config.yaml";
  const fs::path image = dir_ / "images" / "1005.png";
  expect_refused("run --sequence " + q(seq) + " --output " + q(image), "it is input image 5",
                 {image});
  expect_refused("run --sequence " + q(dir_ / "images") + " --output " + q(image),
                 "it is input image 5", {image});
  expect_refused("run --sequence " + q(seq) + " --output " + q(seq), "given by --sequence", {seq});
  expect_refused("run --sequence " + q(seq) + " --config " + q(config) + " --output " + q(config),
                 "given by --config", {config});
  const std::string eval = "eval --sequence " + q(seq) + " --gt " + q(gt) + " --min-gap 5";
  expect_refused(eval + " --json " + q(gt), "given by --gt", {gt});
  expect_refused(eval + " --json " + q(kTmp / "j.json") + " --output " + q(gt), "given by --gt",
                 {gt});
  expect_refused(eval + " --json " + q(kTmp / "j.json") + " --report " + q(image), "input image",
                 {image});
  expect_refused("gt convert " + q(gt) + " --output " + q(gt), "given by SOURCE", {gt});
  expect_refused("gt stats " + q(gt) + " --json " + q(gt), "given by SOURCE", {gt});
  expect_refused("bench --frames 30 --warmup 1 --opencv-frames 0 --config " + q(config) +
                     " --json " + q(config),
                 "given by --config", {config});
  expect_refused("sweep --dataset s=" + seq.string() + "," + gt.string() + ",5 --csv " + q(gt),
                 "--dataset s", {gt});
  // Other spellings of the same file: a path through '..', a hard link, a
  // symbolic link.
  expect_refused(eval + " --json " + q(dir_ / "images" / ".." / "gt.txt"), "given by --gt", {gt});
  const fs::path hard = kTmp / "hard.txt", soft = kTmp / "soft.txt";
  fs::remove(hard);
  fs::remove(soft);
  fs::create_hard_link(gt, hard);
  fs::create_symlink(gt, soft);
  expect_refused(eval + " --json " + q(hard), "given by --gt", {gt});
  expect_refused(eval + " --json " + q(soft), "given by --gt", {gt});
}

// The list a sequence was read from is an input whatever names it: a
// dataset folder's sequence.txt (run, eval, match and sweep were given the
// folder, and `--output FOLDER/sequence.txt` replaced the list with the
// CSV), and a KITTI sequence's times.txt (issue 35, seventh pass).
TEST_F(Files, TheListInsideADatasetFolderIsAnInput) {
  const fs::path seq = dir_ / "sequence.txt", gt = dir_ / "gt.txt";
  expect_refused("run --sequence " + q(dir_) + " --output " + q(seq), "a file the sequence of --sequence was read from",
                 {seq});
  expect_refused("eval --sequence " + q(dir_) + " --gt " + q(gt) + " --min-gap 5 --json " + q(seq),
                 "a file the sequence of --sequence was read from", {seq});
  expect_refused("match --reference " + q(dir_) + " --query " + q(dir_ / "images") + " --output " + q(seq),
                 "a file the sequence of --reference was read from", {seq});
  expect_refused("sweep --dataset s=" + dir_.string() + "," + gt.string() + ",5 --csv " + q(seq),
                 "a file the sequence of --dataset s was read from", {seq});
  // KITTI: the frames' times.
  const fs::path kitti = kTmp / "kitti" / "sequences" / "00";
  fs::create_directories(kitti / "image_0");
  std::ofstream times(kitti / "times.txt");
  for (int i = 0; i < 12; ++i) {
    fs::copy_file(dir_ / "images" / (std::to_string(1000 + i) + ".png"),
                  kitti / "image_0" / (std::string(i < 10 ? "00000" : "0000") + std::to_string(i) + ".png"),
                  fs::copy_options::overwrite_existing);
    times << i * 0.1 << "\n";
  }
  times.close();
  expect_refused("run --sequence " + q(kitti) + " --output " + q(kitti / "times.txt"),
                 "a file the sequence of --sequence was read from", {kitti / "times.txt"});
}

// lsgd sweep --json is written whole at the end; it was opened (emptied) as
// the sweep started, so an interrupted sweep left a 0-byte file where the
// previous sweep's JSON was (issue 35, seventh pass).
TEST_F(Files, AnInterruptedSweepLeavesTheJsonItWouldHaveReplaced) {
  const fs::path json = kTmp / "old.json", csv = kTmp / "table.csv";
  std::ofstream(json) << "{\"earlier\": 1}\n";
  fs::remove(csv);
  // The CSV's header is written after every output is opened: the sweep is
  // stopped then, 40 cells before its end.
  const std::string sweep = "'" + std::string(LSGD_CLI) + "' sweep --dataset s=" + (dir_ / "sequence.txt").string() +
                            "," + (dir_ / "gt.txt").string() + ",5 --set decision.threshold=1:40:1 --csv " +
                            q(csv) + " --json " + q(json) + " >/dev/null 2>&1";
  const std::string script = sweep + " & pid=$!; while [ ! -s " + q(csv) +
                             " ] && kill -0 $pid 2>/dev/null; do sleep 0.05; done; kill -TERM $pid; wait $pid";
  EXPECT_NE(std::system(script.c_str()), 0);
  EXPECT_TRUE(fs::exists(csv));
  EXPECT_EQ(slurp(json), "{\"earlier\": 1}\n");
}

// An image a list names that does not exist yet is no output either, by
// spelling: through a missing folder and '..', or a link to the output to
// be. (A missing image is looked at by its name first: a list of 200,000
// missing images spent 6.5 s resolving each one's spelling.)
TEST_F(Files, AMissingInputIsNeverAnOutputWhateverItsSpelling) {
  const fs::path m = kTmp / "missing";
  fs::create_directories(m);
  fs::copy_file(dir_ / "images" / "1000.png", m / "1000.png", fs::copy_options::overwrite_existing);
  fs::remove(m / "dangling.png");
  fs::create_symlink("res2.csv", m / "dangling.png");
  std::ofstream(m / "list.txt") << "1000.png\ngone/../res.csv\ndangling.png\nnothing.png\n";
  const std::string run = "run --sequence " + q(m / "list.txt") + " --output ";
  expect_refused(run + q(m / "res.csv"), "it is input image 1", {});
  expect_refused(run + q(m / "res2.csv"), "it is input image 2", {});
  EXPECT_FALSE(fs::exists(m / "res.csv") || fs::exists(m / "res2.csv"));
  // Another name is written, the missing images skipped.
  const CmdResult ok = lsgd(run + q(m / "other.csv"));
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_NE(ok.err.find("nothing.png"), std::string::npos) << ok.err;
}

TEST_F(Files, TwoOutputsAreNeverTheSameFile) {
  const std::string eval = "eval --sequence " + q(dir_ / "sequence.txt") + " --gt " +
                           q(dir_ / "gt.txt") + " --min-gap 5";
  const fs::path out = kTmp / "both.json";
  fs::remove(out);
  expect_refused(eval + " --json " + q(out) + " --output " + q(kTmp / "." / "both.json"),
                 "they are the same file", {});
  EXPECT_FALSE(fs::exists(out));  // nothing written, not even the CSV header
  expect_refused(eval + " --json " + q(out) + " --report " + q(out), "they are the same file", {});
  // A link to a file not written yet is that file (one link, then a chain).
  const fs::path link = kTmp / "link.html", chain = kTmp / "chain.csv";
  fs::remove(link);
  fs::remove(chain);
  fs::create_symlink("both.json", link);
  fs::create_symlink(link, chain);
  expect_refused(eval + " --json " + q(out) + " --report " + q(link), "they are the same file", {});
  expect_refused(eval + " --json " + q(out) + " --output " + q(chain), "they are the same file", {});
  EXPECT_FALSE(fs::exists(out));
  // ... and a link into a missing folder is an output in a missing folder.
  const fs::path lost = kTmp / "lost.json";
  fs::remove(lost);
  fs::create_symlink(kTmp / "no-folder" / "x.json", lost);
  expect_refused(eval + " --json " + q(lost),
                 "folder '" + (kTmp / "no-folder").string() + "' does not exist", {});
}

// The database is the run's input and output: no other output may be it or
// one of the SQLite files beside it, which hold committed frames.
TEST_F(Files, TheDatabaseAndItsCompanionsAreNeverOverwritten) {
  const fs::path db = kTmp / "x.db";
  fs::remove(db);
  const std::string run = "run --sequence " + q(dir_ / "sequence.txt") + " --min-gap 5";
  ASSERT_EQ(lsgd(run + " --database " + q(db) + " --output " + q(kTmp / "first.csv")).code, 0);
  const auto size = fs::file_size(db);
  expect_refused(run + " --database " + q(db) + " --output " + q(db), "same file", {db});
  expect_refused(run + " --database " + q(db) + " --output " + q(db.string() + "-wal"),
                 "SQLite wal file", {db});
  // Through a link, SQLite keeps the companions beside the linked file.
  const fs::path link = kTmp / "link.db";
  fs::remove(link);
  fs::create_symlink(db, link);
  expect_refused(run + " --database " + q(link) + " --output " + q(db.string() + "-shm"),
                 "SQLite shm file", {db});
  expect_refused(run + " --database " + q(link) + " --output " + q(db.string() + "-wal"),
                 "SQLite wal file", {db});
  // A database about to be created is an output as well.
  const fs::path fresh = kTmp / "new.db";
  fs::remove(fresh);
  expect_refused(run + " --database " + q(fresh) + " --output " + q(fresh), "same file", {});
  EXPECT_FALSE(fs::exists(fresh));
  EXPECT_EQ(fs::file_size(db), size);
}

// Results are never lost at the end of a long run: an output that cannot be
// written stops the command before it starts.
TEST_F(Files, UnwritableOutputsStopTheCommandFirst) {
  const std::string eval = "eval --sequence " + q(dir_ / "sequence.txt") + " --gt " +
                           q(dir_ / "gt.txt") + " --min-gap 5";
  const fs::path missing = kTmp / "no" / "such" / "folder" / "m.json";
  CmdResult r = lsgd(eval + " --json " + q(missing));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("folder '" + (kTmp / "no" / "such" / "folder").string() + "' does not exist"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.out, "");  // no frame was processed, nothing printed
  r = lsgd(eval + " --json " + q(kTmp / "j.json") + " --output " + q(dir_));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("it is a folder"), std::string::npos) << r.err;
  // A stream the user chose is fine.
  r = lsgd(eval + " --json /dev/null");
  EXPECT_EQ(r.code, 0) << r.err;
  // A read-only file or folder is refused by its mode, also for root (whom
  // access() lets write anything): lsgd run as root replaced them.
  const fs::path ro = kTmp / "ro.json";
  std::ofstream(ro) << "{}";
  fs::permissions(ro, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  r = lsgd(eval + " --json " + q(ro));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("read-only"), std::string::npos) << r.err;
  r = lsgd("run --sequence " + q(dir_ / "sequence.txt") + " --output " + q(ro));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("read-only"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(ro), "{}");
  const fs::path locked = kTmp / "locked";
  fs::create_directories(locked);
  fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
  r = lsgd(eval + " --json " + q(locked / "j.json"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("read-only"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(locked / "j.json"));
  fs::permissions(locked, fs::perms::owner_all);
  // A database file without a write bit is not appended to.
  const fs::path db = kTmp / "ro.db";
  r = lsgd("run --sequence " + q(dir_ / "sequence.txt") + " --output /dev/null --database " + q(db));
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string before = slurp(db);
  fs::permissions(db, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  r = lsgd("run --sequence " + q(dir_ / "sequence.txt") + " --output /dev/null --database " + q(db));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("read-only"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(db), before);
  fs::permissions(db, fs::perms::owner_read | fs::perms::owner_write);
}

// A legal name as long as the file system takes (255 bytes) is written:
// its temporary file gets a short name beside it (NAME.tmp-PID did not fit,
// and the results were lost after the run). A name longer than the folder
// takes, or a database whose SQLite companions would not fit, fails first.
TEST_F(Files, NamesAsLongAsTheFileSystemTakesAreWrittenLongerOnesRefusedFirst) {
  const std::string eval = "eval --sequence " + q(dir_ / "sequence.txt") + " --gt " +
                           q(dir_ / "gt.txt") + " --min-gap 5";
  const fs::path folder = kTmp / "long-names";
  fs::create_directories(folder);
  const fs::path longest = folder / (std::string(250, 'a') + ".json");  // 255 bytes
  CmdResult r = lsgd(eval + " --json " + q(longest));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(slurp(longest).find("recall_at_1"), std::string::npos);
  EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator{}), 1);  // no temporary left
  const fs::path too_long = folder / (std::string(256, 'b') + ".json");
  r = lsgd(eval + " --json " + q(too_long));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("its name is 261 bytes, more than the 255 its folder takes"), std::string::npos)
      << r.err;
  EXPECT_EQ(r.out, "");  // nothing was run
  const fs::path db = folder / (std::string(250, 'c') + ".db");
  r = lsgd("run --sequence " + q(dir_ / "sequence.txt") + " --output /dev/null --database " + q(db));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("give a name of at most 247 bytes (nothing was created)"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(db));
  const fs::path fits = folder / (std::string(244, 'd') + ".db");  // 247 bytes
  r = lsgd("run --sequence " + q(dir_ / "sequence.txt") + " --output /dev/null --database " + q(fits));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(fits));
}

// A result that cannot be written whole is an error (exit 1 naming the file),
// never a success; a device given as an output is written, never replaced.
TEST_F(Files, AFullDiskFailsTheCommandAndDevicesStayDevices) {
  const std::string eval = "eval --sequence " + q(dir_ / "sequence.txt") + " --gt " +
                           q(dir_ / "gt.txt") + " --min-gap 5 --verify none";
  const std::string gt = q(dir_ / "gt.txt");
  if (fs::exists("/dev/full")) {
    for (const std::string& args :
         {"gt convert " + gt + " --output /dev/full", "gt stats " + gt + " --json /dev/full",
          eval + " --json /dev/full", eval + " --json /dev/null --report /dev/full",
          eval + " --json /dev/null --output /dev/full",
          "sweep --dataset 's=" + (dir_ / "sequence.txt").string() + "," +
              (dir_ / "gt.txt").string() + ",5' --verify none --markdown /dev/full"}) {
      const CmdResult r = lsgd(args);
      EXPECT_EQ(r.code, 1) << args;
      EXPECT_NE(r.err.find("/dev/full"), std::string::npos) << args << "\n" << r.err;
    }
  }
  const CmdResult r = lsgd(eval + " --json /dev/null --report /dev/null");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(lsgd("gt convert " + gt + " --output /dev/null").code, 0);
  struct stat st {};
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode)) << "/dev/null was replaced";
  EXPECT_FALSE(fs::exists("/dev/null.tmp"));
}

// A command killed while it writes an output (here by the file size limit,
// SIGXFSZ; SIGINT, SIGTERM and SIGHUP alike) leaves no temporary file; one
// started with standard error closed does not write its diagnostics into
// the first file it opens.
// Under a file size limit (ulimit -f) a write that passes it is an error
// naming the file, as a full disk's (lsgd was killed by SIGXFSZ, no word
// said); with no file descriptor left for a new database, nothing is left
// behind to pin the run's options for the next one.
TEST_F(Files, ASizeLimitOrNoDescriptorLeftIsAnErrorAndLeavesNoDatabase) {
  const auto limited = [](const std::string& limit, const std::string& args) {
    return lsgd::test::run_command("/bin/sh", "-c \"ulimit " + limit + "; exec '" + std::string(LSGD_CLI) + "' " +
                                                  args + "\"",
                                   kTmp);
  };
  const fs::path csv = kTmp / "limited.csv", json = kTmp / "limited.json";
  CmdResult r = limited("-f 1", "run --sequence " + q(dir_ / "sequence.txt") + " --output " + q(csv));
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("to '" + csv.string() + "' (File too large)"), std::string::npos) << r.err;
  r = limited("-f 1", "eval --sequence " + q(dir_ / "sequence.txt") + " --gt " + q(dir_ / "gt.txt") +
                          " --min-gap 5 --json " + q(json));
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find(json.string()), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(json));
  for (const auto& entry : fs::directory_iterator(kTmp)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
  }
  const fs::path db = kTmp / "no-descriptors.db";
  r = limited("-n 5", "run --sequence " + q(dir_ / "sequence.txt") + " --output /dev/null --database " + q(db));
  EXPECT_NE(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(db)) << r.err;
  r = lsgd("run --sequence " + q(dir_ / "sequence.txt") + " --output /dev/null --database " + q(db) +
           " --option segmentation.superpixel_size=30");
  EXPECT_EQ(r.code, 0) << r.err;  // a new database, not a resume of the failed one's options
}

// lsgd sweep --jobs 16 where only a few threads' stacks fit the address
// space (100-300 MB stacks under ulimit -v): the cells run on the threads
// that could start, or a cell runs out of memory and says so; it never ends
// in std::terminate (the threads already started were destroyed joinable).
// Not under the sanitizers, whose shadow memory needs more address space.
TEST_F(Files, ASweepWhoseThreadsCannotAllStartDoesNotAbort) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "an address-space limit leaves the sanitizers no room";
#endif
  const fs::path csv = kTmp / "threads.csv";
  for (const char* limit : {"-v 1000000 -s 200000", "-v 1500000 -s 300000"}) {
    const CmdResult r = lsgd::test::run_command(
        "/bin/sh",
        "-c \"ulimit " + std::string(limit) + "; exec '" + std::string(LSGD_CLI) + "' sweep --dataset s=" +
            (dir_ / "sequence.txt").string() + "," + (dir_ / "gt.txt").string() +
            ",5 --set decision.threshold=1:16:1 --jobs 16 --verify none --csv " + q(csv) + "\"",
        kTmp);
    EXPECT_TRUE(r.code == 0 || (r.code == 1 && r.err.find("out of memory") != std::string::npos))
        << limit << ": exit " << r.code << ": " << r.err;
    EXPECT_EQ(r.err.find("terminate"), std::string::npos) << r.err;
  }
}

// Standard output is an output too: appended to an input (`>> list.txt`)
// it is refused before anything runs; closed, a command whose results go
// there is refused; a write that fails (a full disk) is an error, exit 1.
TEST_F(Files, StandardOutputIsCheckedLikeEveryOutput) {
  const auto shell = [](const std::string& args, const std::string& redirect) {
    return lsgd::test::run_command(
        "/bin/sh", "-c \"exec '" + std::string(LSGD_CLI) + "' " + args + " " + redirect + "\"", kTmp);
  };
  const fs::path list = dir_ / "sequence.txt", gt = dir_ / "gt.txt";
  const std::string list_before = slurp(list), gt_before = slurp(gt);
  CmdResult r = shell("run --sequence " + q(list) + " --verify none", ">> " + q(list));
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("refusing to write standard output: it is the file given by --sequence"),
            std::string::npos) << r.err;
  r = shell("gt stats " + q(gt), ">> " + q(gt));
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("refusing to write standard output: it is the file given by SOURCE"), std::string::npos)
      << r.err;
  EXPECT_EQ(slurp(list), list_before);
  EXPECT_EQ(slurp(gt), gt_before);

  r = shell("run --sequence " + q(list) + " --verify none", ">&-");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("is closed: give --output FILE (nothing was run)"), std::string::npos) << r.err;
  for (const std::string& args : {std::string("options --yaml"), "gt stats " + q(gt)}) {
    r = shell(args, "> /dev/full");
    EXPECT_EQ(r.code, 1) << args;
    EXPECT_NE(r.err.find("cannot write standard output: No space left on device"), std::string::npos) << r.err;
    r = shell(args, ">&-");
    EXPECT_EQ(r.code, 1) << args;
    EXPECT_NE(r.err.find("cannot write standard output: Bad file descriptor (it is closed)"), std::string::npos)
        << r.err;
  }
  r = shell("options --yaml", "> " + q(kTmp / "options.yaml"));
  EXPECT_EQ(r.code, 0) << r.err;
}

TEST_F(Files, AKilledWriteLeavesNoTemporaryAndAClosedStderrStaysClosed) {
  const fs::path out = kTmp / "killed";
  fs::create_directories(out);
  const std::string eval = "'" + std::string(LSGD_CLI) + "' eval --sequence " + q(dir_ / "sequence.txt") +
                           " --gt " + q(dir_ / "gt.txt") + " --min-gap 5 --verify none --json " +
                           q(out / "m.json");
  const int status = std::system(("sh -c \"ulimit -f 1 && exec " + eval + "\" >/dev/null 2>&1").c_str());
  EXPECT_FALSE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "the 512-byte limit was not reached";
  for (const auto& entry : fs::directory_iterator(out)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
  }
  EXPECT_FALSE(fs::exists(out / "m.json"));

  const fs::path bad = kTmp / "bad-seq";
  fs::create_directories(bad);
  for (int i = 0; i < 4; ++i) fs::copy_file(dir_ / "images" / (std::to_string(1000 + i) + ".png"), bad / (std::to_string(i) + ".png"));
  std::ofstream(bad / "2.png") << "not an image";
  const std::string run = "'" + std::string(LSGD_CLI) + "' run --sequence " + q(bad) + " --output " + q(out / "c.csv");
  ASSERT_EQ(std::system(("sh -c \"exec " + run + " 2>&-\" >/dev/null").c_str()), 0);
  const std::string csv = slurp(out / "c.csv");
  EXPECT_EQ(csv.find("skipped"), std::string::npos) << csv;
  EXPECT_EQ(csv.rfind("frame,image,", 0), 0u) << csv;

  // A working folder deleted under the command: its relative output's error says so.
  const fs::path gone = kTmp / "gone";
  const std::string in_gone = "mkdir -p " + q(gone) + " && cd " + q(gone) + " && rmdir " + q(gone) +
                              " && exec '" + std::string(LSGD_CLI) + "' run --sequence " + q(bad) +
                              " --output rel.csv 2>" + q(out / "gone.err");
  EXPECT_NE(std::system(("sh -c \"" + in_gone + "\" >/dev/null").c_str()), 0);
  EXPECT_NE(slurp(out / "gone.err").find("cannot write output file 'rel.csv': No such file or directory; the "
                                          "working folder no longer exists"),
            std::string::npos) << slurp(out / "gone.err");
}

// lsgd demo --output DIR writes frames and files there: a folder it did not
// write (here a dataset with the same file names) is refused.
TEST_F(Files, DemoNeverWritesIntoAForeignFolder) {
  const fs::path foreign = kTmp / "foreign";
  fs::create_directories(foreign / "images");
  std::ofstream(foreign / "sequence.txt") << "images/a.png\n";
  expect_refused("demo --mode exhaustive --output " + q(foreign), "has no metrics.json",
                 {foreign / "sequence.txt"});
  std::ofstream(foreign / "notes.txt") << "mine\n";
  expect_refused("demo --mode exhaustive --output " + q(foreign), "it holds 'notes.txt'",
                 {foreign / "notes.txt"});
}

// A folder spelt through one that does not exist yet (`new/..`) is the
// folder it lands in once that is created: lsgd demo wrote its files into a
// foreign folder, replacing its sequence.txt. A dangling link said "cannot
// create 'link/images': File exists" after printing the route.
TEST_F(Files, DemoOutputSpeltThroughANewFolderIsTheFolderItLandsIn) {
  const fs::path foreign = kTmp / "foreign-up";
  fs::create_directories(foreign);
  std::ofstream(foreign / "sequence.txt") << "images/a.png\n";
  std::ofstream(foreign / "notes.txt") << "mine\n";
  expect_refused("demo --mode exhaustive --output " + q(foreign / "new" / ".."), "it holds '",
                 {foreign / "sequence.txt", foreign / "notes.txt"});
  EXPECT_FALSE(fs::exists(foreign / "images"));
  fs::create_symlink(kTmp / "nowhere" / "x", kTmp / "dangling");
  expect_refused("demo --mode exhaustive --output " + q(kTmp / "dangling"),
                 "is a symbolic link to '" + (kTmp / "nowhere" / "x").string() + "', which does not exist", {});
}

// A folder an earlier demo wrote is its own, whatever mode wrote it (index
// mode's results-index.csv was missing from the demo's list of its files).
TEST_F(Files, DemoWritesAgainIntoTheFolderAnEarlierDemoWrote) {
  const fs::path dir = kTmp / "demo-again";
  for (int k = 0; k < 2; ++k) {
    const CmdResult r = lsgd("demo --mode index --verify none --output " + q(dir));
    EXPECT_EQ(r.code, 0) << "#" << k << ": " << r.err;
  }
  EXPECT_TRUE(fs::exists(dir / "results-index.csv"));
}

}  // namespace
