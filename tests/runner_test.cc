// Tests of the evaluation runner (eval/runner.h): frame ids, skipping bad frames.
#include "lsgd/eval/runner.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/io/files.h"
#include "lsgd/io/sequence.h"
#include "test_util.h"

namespace lsgd::eval {
namespace {

// 50 frames: frames 0..39 show noise patterns 0..39 (enough candidates to
// calibrate the scores, evidence.h), frame 40 + k shows pattern k % 3, so it is
// identical to frame k % 3 and to the frames 3 apart. Frame 2 cannot be read
// and frame 45 has another size.
constexpr std::int64_t kBase = 40;
FrameSource flawed_source() {
  FrameSource source;
  source.frames = kBase + 10;
  source.load = [](std::int64_t i) -> cv::Mat {
    if (i == 2) throw FormatError("image 'f2.png' is truncated");
    if (i == kBase + 5) return cv::Mat(32, 32, CV_8UC1, cv::Scalar(7));
    const std::int64_t pattern = i < kBase ? i : (i - kBase) % 3;
    const GrayImage g = test::random_image(64, 48, static_cast<std::uint64_t>(pattern) + 1);
    return cv::Mat(48, 64, CV_8UC1, const_cast<std::uint8_t*>(g.pixels.data())).clone();
  };
  source.name = [](std::int64_t i) { return "f" + std::to_string(i) + ".png"; };
  return source;
}

DetectorOptions options() {
  DetectorOptions o;
  o.segmentation.superpixel_size = 16;
  o.search.min_gap = 0;
  o.search.top_n = 20;
  o.verification.stages = {};
  return o;
}

TEST(RunDetector, StopsAtTheFirstBadFrameByDefault) {
  Detector detector(options());
  std::vector<std::int64_t> seen;
  const std::string e = test::message_of<FormatError>([&] {
    run_detector(detector, flawed_source(),
                 [&](const Result& r, const FrameTimes&) { seen.push_back(r.frame); });
  });
  EXPECT_NE(e.find("frame 2 (f2.png)"), std::string::npos) << e;
  EXPECT_EQ(seen, (std::vector<std::int64_t>{0, 1}));  // frames before the error were passed on
}

// A resource the system ran out of (file descriptors) is not a bad image:
// the run stops there, naming the frame, even when bad frames are skipped
// (under `ulimit -n 8` every image was skipped, one after the other).
TEST(RunDetector, AResourceErrorStopsTheRunEvenWhenBadFramesAreSkipped) {
  FrameSource source = flawed_source();
  const auto load = source.load;
  source.load = [load](std::int64_t i) -> cv::Mat {
    if (i == 5) throw ResourceError("cannot read image 'f5.png': Too many open files");
    return load(i);
  };
  Detector detector(options());
  RunOptions run;
  run.skip_bad_frames = true;
  std::vector<std::int64_t> skipped, seen;
  const std::string e = test::message_of<ResourceError>([&] {
    run_detector(detector, source, [&](const Result& r, const FrameTimes&) { seen.push_back(r.frame); },
                 run, [&](std::int64_t frame, const std::string&, const std::string&) { skipped.push_back(frame); });
  });
  EXPECT_NE(e.find("frame 5 (f5.png): cannot read image 'f5.png': Too many open files"), std::string::npos) << e;
  EXPECT_NE(e.find("the run stops here, the frames before it are done"), std::string::npos) << e;
  EXPECT_EQ(skipped, (std::vector<std::int64_t>{2}));  // the bad image before it was skipped
  EXPECT_EQ(seen, (std::vector<std::int64_t>{0, 1, 3, 4}));
}

// io::read_file says which: no descriptor left is a ResourceError.
TEST(RunDetector, NoFileDescriptorLeftIsAResourceError) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  // The sanitizers' runtimes open files for their own checks (UBSan's vptr
  // check reads the process's maps): with no descriptor left they report
  // errors of their own. The runner's part is tested above without a limit.
  GTEST_SKIP() << "needs a process without sanitizer runtimes";
#endif
  const std::string path = std::string(LSGD_TEST_TMP) + "/runner-resource.txt";
  std::filesystem::create_directories(LSGD_TEST_TMP);
  std::ofstream(path) << "x";
  rlimit before{};
  ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &before), 0);
  rlimit none = before;
  none.rlim_cur = 0;  // no new descriptor; those open stay valid
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &none), 0);
  std::string message;
  bool resource = false;
  try {
    io::read_file(path, "image", 100);
  } catch (const ResourceError& e) {
    resource = true;
    message = e.what();
  } catch (const Error& e) {
    message = e.what();
  }
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &before), 0);
  EXPECT_TRUE(resource) << message;
  EXPECT_NE(message.find("not the file's fault"), std::string::npos) << message;
  EXPECT_EQ(io::read_file(path, "image", 100).size(), 1u);
}

TEST(RunDetector, SkipsBadFramesAndKeepsSourceIndices) {
  Detector detector(options());
  std::vector<std::int64_t> skipped;
  std::vector<std::string> errors;
  RunOptions run;
  run.skip_bad_frames = true;
  const auto records =
      run_detector(detector, flawed_source(), {}, run,
                   [&](std::int64_t frame, const std::string& name, const std::string& error) {
                     skipped.push_back(frame);
                     errors.push_back(name + ": " + error);
                   });
  EXPECT_EQ(skipped, (std::vector<std::int64_t>{2, kBase + 5}));
  EXPECT_NE(errors[0].find("f2.png: image 'f2.png' is truncated"), std::string::npos);
  EXPECT_NE(errors[1].find("f45.png"), std::string::npos);
  EXPECT_NE(errors[1].find("size"), std::string::npos) << errors[1];
  EXPECT_EQ(detector.size(), kBase + 8);  // the skipped frames never reached the detector
  ASSERT_EQ(records.size(), static_cast<std::size_t>(kBase + 10));
  for (std::int64_t i = 0; i < kBase + 10; ++i) {
    EXPECT_EQ(records[i].frame, i);
    EXPECT_EQ(records[i].skipped, i == 2 || i == kBase + 5);
  }
  EXPECT_EQ(records[2].reported.frame, -1);
  // The identical candidates of a frame score highest, equally.
  const auto identical = [&](std::int64_t frame) {
    std::set<std::int64_t> out;
    const auto& c = records[static_cast<std::size_t>(frame)].candidates;
    for (const Candidate& x : c) {
      if (x.score == c.front().score) out.insert(x.frame);
    }
    return out;
  };
  // Frame 47 shows pattern 1, as frames 1, 41 and 44 do: its identical
  // candidates are named by source index (41, 44), not by detector id (40, 43).
  EXPECT_EQ(identical(kBase + 7), (std::set<std::int64_t>{1, kBase + 1, kBase + 4}));
  EXPECT_EQ(records[kBase + 7].reported.frame, 1);  // ties go to the older frame
  // Frame 49, pattern 0: frames 0, 40, 43 and 46 (detector ids 0, 39, 42, 44).
  EXPECT_EQ(identical(kBase + 9), (std::set<std::int64_t>{0, kBase, kBase + 3, kBase + 6}));
}

// Out of memory (a memory limit, a frame too large for the machine): the run
// stops at the frame, naming it, instead of ending in std::bad_alloc or
// OpenCV's bare "Failed to allocate"; an image that cannot be decoded for
// want of memory is a skip naming the file. Run in a child process under
// RLIMIT_AS (not under the sanitizers, which reserve terabytes of address
// space).
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
// The child's exit code: 0 when `f` throws an Error whose message holds `expected`.
int in_limited_child(const std::function<void()>& f, const std::string& expected) {
  const pid_t pid = fork();
  if (pid == 0) {
    cv::setNumThreads(0);
    long pages = 0;
    std::FILE* statm = std::fopen("/proc/self/statm", "r");
    if (statm == nullptr || std::fscanf(statm, "%ld", &pages) != 1) _exit(3);
    std::fclose(statm);
    const rlim_t limit = static_cast<rlim_t>(pages) * static_cast<rlim_t>(sysconf(_SC_PAGESIZE)) + (120u << 20);
    const rlimit r{limit, limit};
    if (setrlimit(RLIMIT_AS, &r) != 0) _exit(3);
    try {
      f();
    } catch (const Error& e) {
      _exit(std::string(e.what()).find(expected) != std::string::npos ? 0 : 1);
    } catch (...) {
      _exit(4);
    }
    _exit(2);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 100 + WTERMSIG(status);
}

TEST(Runner, OutOfMemoryNamesTheFrameOrTheImage) {
  // An 8192 x 6144 frame (the most pixels lsgd reads): 50 MB to hold, far
  // more to segment and describe at its own size (working_side 0) than
  // 120 MB above what the process uses.
  FrameSource source;
  source.frames = 1;
  source.load = [](std::int64_t) { return cv::Mat(6144, 8192, CV_8UC1, cv::Scalar(9)); };
  source.name = [](std::int64_t i) { return "frame-" + std::to_string(i) + ".png"; };
  EXPECT_EQ(in_limited_child(
                [&] {
                  DetectorOptions own;
                  own.segmentation.working_side = 0;
                  Detector detector(own);
                  RunOptions options;
                  options.skip_bad_frames = true;
                  run_detector(detector, source, nullptr, options);
                },
                "frame 0 (frame-0.png): out of memory while processing it"),
            0);
  // Decoding: a 146 KB PNG of 8192 x 6144 BGR pixels (150 MB decoded).
  const std::string png = std::string(LSGD_TEST_TMP) + "/runner_big_" + std::to_string(getpid()) + ".png";
  ASSERT_TRUE(cv::imwrite(png, cv::Mat(6144, 8192, CV_8UC3, cv::Scalar(1, 2, 3))));
  EXPECT_EQ(in_limited_child([&] { io::read_image(png); },
                             "out of memory while decoding image '" + png + "' (8192 x 6144 pixels declared)"),
            0);
  std::remove(png.c_str());
}
#endif

}  // namespace
}  // namespace lsgd::eval
