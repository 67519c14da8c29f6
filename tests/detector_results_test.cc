// The online detector (include/lsgd/detector.h) shared by two threads, the
// status of each result, a loop's geometry, the caller's ids and stamps, and
// describe().
#include "lsgd/detector.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "lsgd/error.h"
#include "lsgd/image.h"
#include "detector_test_support.h"
#include "detector_util.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::message_of;
using detector_test_support::kH;
using detector_test_support::kW;
using detector_test_support::random_frame;
using detector_test_support::small_options;

// One Detector shared by two threads (issue 15: SIGSEGV, heap-use-after-free
// under ASan): an overlapping call throws InvalidArgument instead of
// corrupting the detector; every call either completes or is refused, and the
// detector holds exactly the frames that completed. (Run under ASan/UBSan by
// scripts/ci-hardening.sh.)
TEST(Detector, TwoThreadsOnOneDetectorAreRefusedNotCorrupted) {
  DetectorOptions o = small_options(kNodesSearch, 2, 5);
  Detector det(o);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 8; ++i) frames.push_back(random_frame(700 + i, CV_8UC3, 320, 240));
  std::atomic<int> done{0}, refused{0};
  std::atomic<bool> go{false};
  const auto worker = [&](int offset) {
    while (!go) std::this_thread::yield();
    for (int i = 0; i < 40; ++i) {
      try {
        det.process(frames[static_cast<std::size_t>((i + offset) % 8)]);
        ++done;
      } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("one thread at a time"), std::string::npos)
            << e.what();
        ++refused;
      }
    }
  };
  std::thread a(worker, 0), b(worker, 3);
  go = true;
  a.join();
  b.join();
  EXPECT_EQ(done + refused, 80);
  EXPECT_EQ(det.size(), done.load());
  // Still a working detector.
  const Result r = det.process(frames[0]);
  EXPECT_EQ(r.frame, done.load());
}

// Result::status says why there is a loop or none, consistently with the
// rest of the Result, and every status occurs on the street's revisits.
TEST(Detector, StatusSaysWhyThereIsALoopOrNone) {
  std::map<LoopStatus, int> seen;
  for (const int agree : {0, 3}) {
    DetectorOptions o;
    o.search.min_gap = 20;
    o.verification.temporal_options.agree = agree;  // 3: the temporal gate examines
    Detector d(o);
    for (std::int64_t i = 0; i < test::world().frames(); ++i) {
      const Result r = d.process(test::frame(i));
      ++seen[r.status];
      SCOPED_TRACE("frame " + std::to_string(i) + " " + to_string(r.status));
      EXPECT_EQ(r.loop, r.status == LoopStatus::kLoop);
      EXPECT_EQ(i <= o.search.min_gap, r.status == LoopStatus::kTooFewFrames);
      if (r.status == LoopStatus::kNoCandidate) {
        EXPECT_TRUE(r.candidates.empty());
      }
      if (r.status == LoopStatus::kGated) {
        EXPECT_EQ(r.best.frame, -1);
        for (const StageVerdict& v : r.verification) EXPECT_FALSE(v.accepted);
      }
      if (r.status == LoopStatus::kNotConfirmed || r.status == LoopStatus::kBelowThreshold) {
        EXPECT_GE(r.best.frame, 0);
        EXPECT_LT(r.best.score, o.decision.threshold);
      }
      if (r.status == LoopStatus::kNotConfirmed) {
        EXPECT_FALSE(r.evidence.confirmed);
      }
    }
  }
  for (const LoopStatus s : {LoopStatus::kLoop, LoopStatus::kTooFewFrames, LoopStatus::kNoCandidate,
                             LoopStatus::kGated, LoopStatus::kYoung, LoopStatus::kNotConfirmed,
                             LoopStatus::kBelowThreshold}) {
    EXPECT_GT(seen[s], 0) << to_string(s);
    EXPECT_EQ(parse_loop_status(to_string(s)), s);
  }
  EXPECT_NE(test::message_of<InvalidArgument>([] { parse_loop_status("looped"); })
                .find("loop status 'looped' is not one of loop, too_few_frames"),
            std::string::npos);
}

// Result::geometry: the reported candidate's matches and model whenever the
// geometric stage fitted one, consistent with its inliers; none without it.
TEST(Detector, ALoopCarriesItsGeometry) {
  for (const char* stages : {"temporal,geometric", "temporal"}) {
    DetectorOptions o;
    o.search.min_gap = 20;
    parse_verification_stages(stages, o.verification);
    Detector d(o);
    int loops = 0;
    for (std::int64_t i = 0; i < test::world().frames(); ++i) {
      const Result r = d.process(test::frame(i));
      SCOPED_TRACE(std::string(stages) + ", frame " + std::to_string(i));
      if (std::string(stages) == "temporal") {
        EXPECT_EQ(r.geometry, nullptr);
        continue;
      }
      loops += r.loop ? 1 : 0;
      if (r.loop) {
        ASSERT_NE(r.geometry, nullptr);
      }
      if (r.geometry == nullptr) continue;
      EXPECT_GE(r.best.frame, 0);
      EXPECT_EQ(std::count(r.geometry->inliers.begin(), r.geometry->inliers.end(), 1), r.evidence.inliers);
      EXPECT_EQ(r.geometry->query_points.size(), 2 * r.geometry->matches());
      EXPECT_TRUE(r.geometry->model == "fundamental" || r.geometry->model == "homography");
    }
    if (std::string(stages) != "temporal") {
      EXPECT_GT(loops, 10);
    }
  }
}

// The caller's ids and stamps: carried into the Result, mapped both ways,
// continued when not given, and refused (detector unchanged) when not
// increasing or not finite.
TEST(Detector, CallersIdsAndStamps) {
  DetectorOptions o;
  o.search.min_gap = 20;
  Detector d(o);
  std::int64_t loops = 0;
  for (std::int64_t i = 0; i < test::world().frames(); ++i) {
    const bool given = i < 150;
    const Result r = given ? d.process(test::frame(i), 10 * i + 7, 0.1 * static_cast<double>(i))
                           : d.process(test::frame(i));
    const std::int64_t id = given ? 10 * i + 7 : 10 * 149 + 7 + (i - 149);
    EXPECT_EQ(r.frame, i);
    EXPECT_EQ(r.id, id);
    EXPECT_EQ(d.id_of(i), id);
    EXPECT_EQ(d.frame_of(id), i);
    if (given) {
      EXPECT_EQ(r.stamp, 0.1 * static_cast<double>(i));
    } else {
      EXPECT_TRUE(std::isnan(r.stamp));
    }
    EXPECT_EQ(r.loop_id, r.best.frame >= 0 ? d.id_of(r.best.frame) : -1);
    loops += r.loop ? 1 : 0;
  }
  EXPECT_GT(loops, 0);
  const std::int64_t n = d.size(), last = d.id_of(n - 1);
  for (const auto& [id, stamp] : {std::pair<std::int64_t, double>{last, 0.0}, {last - 5, 0.0}, {-2, 0.0},
                                  {last + 1, std::numeric_limits<double>::infinity()}}) {
    EXPECT_THROW(d.process(test::frame(0), id, stamp), InvalidArgument) << id;
    EXPECT_EQ(d.size(), n);
  }
  EXPECT_NE(test::message_of<InvalidArgument>([&] { d.process(test::frame(0), last); })
                .find("frame id " + std::to_string(last) + " must be above the last frame's id"),
            std::string::npos);
  EXPECT_EQ(d.frame_of(-1), -1);
  EXPECT_THROW(d.id_of(n), InvalidArgument);
  // A query carries the id it was given, and changes nothing.
  const Result q = d.query(test::frame(5), last + 100, 9.5);
  EXPECT_EQ(q.id, last + 100);
  EXPECT_EQ(q.stamp, 9.5);
  EXPECT_EQ(d.process(test::frame(5)).id, last + 1);
}

// describe(): the descriptor process() stores, with nothing stored, in both storages.
TEST(Detector, DescribeGivesTheStoredDescriptorAndStoresNothing) {
  for (const HistogramStorage storage : {HistogramStorage::kExact, HistogramStorage::kCompact}) {
    DetectorOptions o = small_options();
    o.descriptor.storage = storage;
    Detector d(o);
    for (int i = 0; i < 5; ++i) {
      const cv::Mat f = random_frame(900 + i);
      const Descriptor x = d.describe(f);
      EXPECT_EQ(d.size(), i);
      d.process(f);
      const DescriptorView stored = d.store().view(i), own = x.view();
      ASSERT_EQ(own.cells, stored.cells);
      if (storage == HistogramStorage::kCompact) {
        EXPECT_TRUE(std::equal(own.compact, own.compact + own.cells * kCompactBins, stored.compact));
      } else {
        EXPECT_TRUE(std::equal(own.hist, own.hist + own.cells * kBins, stored.hist));
        EXPECT_TRUE(std::equal(own.pixels, own.pixels + own.cells, stored.pixels));
      }
      EXPECT_EQ(similarity(own, stored, o.similarity.metric), similarity(stored, stored, o.similarity.metric));
    }
    EXPECT_THROW(d.describe(random_frame(1, CV_8UC3, kW * 2, kH)), InvalidArgument);
  }
}

}  // namespace
}  // namespace lsgd
