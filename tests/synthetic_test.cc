#include "synthetic/synthetic.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "lsgd/eval/groundtruth.h"

namespace lsgd::eval {
namespace {

constexpr std::int64_t kMinGap = 50;  // the demo's temporal window
// Frames of the default route before F, G and H were appended (A to E).
constexpr std::int64_t kFirstRouteFrames = 854;

// A smaller world for the tests that only need structure, not size.
SyntheticOptions SmallOptions() {
  SyntheticOptions o;
  o.width = 160;
  o.height = 120;
  return o;
}

cv::Mat Gray(const cv::Mat& bgr) {
  cv::Mat gray;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  gray.convertTo(gray, CV_64F);
  return gray;
}

// Gray image scaled to zero mean and unit standard deviation.
cv::Mat Normalised(const cv::Mat& bgr) {
  cv::Mat gray = Gray(bgr);
  cv::Scalar mean, dev;
  cv::meanStdDev(gray, mean, dev);
  return (gray - mean[0]) / std::max(dev[0], 1e-9);
}

double MeanAbsDiff(const cv::Mat& a, const cv::Mat& b) {
  return cv::norm(a, b, cv::NORM_L1) / static_cast<double>(a.total());
}

// FNV-1a over the bytes of an 8-bit image.
std::uint64_t Checksum(const cv::Mat& f) {
  std::uint64_t h = 1469598103934665603ull;
  for (int r = 0; r < f.rows; ++r) {
    const auto* p = f.ptr<std::uint8_t>(r);
    for (int c = 0; c < f.cols * f.channels(); ++c) h = (h ^ p[c]) * 1099511628211ull;
  }
  return h;
}

bool StartsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

// The stretch whose label starts with `prefix` (e.g. "F:"); fails the test if none.
const RouteSegment* Stretch(const SyntheticWorld& w, const char* prefix) {
  for (const RouteSegment& seg : w.route()) {
    if (StartsWith(seg.label, prefix)) return &seg;
  }
  ADD_FAILURE() << "no stretch " << prefix;
  return nullptr;
}

// The GT match of q at least kMinGap frames older, closest in place; -1 if none.
std::int64_t ClosestOldMatch(const SyntheticWorld& w, std::int64_t q) {
  std::int64_t best = -1;
  for (std::int64_t m : w.ground_truth().matches(q)) {
    if (q - m <= kMinGap) continue;
    if (best < 0 || std::fabs(w.place(q) - w.place(m)) < std::fabs(w.place(q) - w.place(best))) {
      best = m;
    }
  }
  return best;
}

TEST(SyntheticOptions, DefaultsAreValid) { EXPECT_NO_THROW(SyntheticOptions{}.check()); }

TEST(SyntheticOptions, EachInvalidFieldThrows) {
  auto expect_invalid = [](auto mutate, const char* field) {
    SyntheticOptions o;
    mutate(o);
    try {
      o.check();
      ADD_FAILURE() << field << " was accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
    EXPECT_THROW(SyntheticWorld{o}, InvalidArgument) << field;
  };
  expect_invalid([](SyntheticOptions& o) { o.width = 31; }, "width");
  expect_invalid([](SyntheticOptions& o) { o.width = 4097; }, "width");
  expect_invalid([](SyntheticOptions& o) { o.height = 0; }, "height");
  expect_invalid([](SyntheticOptions& o) { o.height = 5000; }, "height");
  expect_invalid([](SyntheticOptions& o) { o.route_scale = 0.05; }, "route_scale");
  expect_invalid([](SyntheticOptions& o) { o.route_scale = 11; }, "route_scale");
  expect_invalid([](SyntheticOptions& o) { o.route_scale = std::nan(""); }, "route_scale");
  expect_invalid([](SyntheticOptions& o) { o.loop_radius = 0; }, "loop_radius");
  expect_invalid([](SyntheticOptions& o) { o.loop_radius = 31; }, "loop_radius");
  expect_invalid([](SyntheticOptions& o) { o.sensor_noise = -1; }, "sensor_noise");
  expect_invalid([](SyntheticOptions& o) { o.sensor_noise = 65; }, "sensor_noise");
  expect_invalid([](SyntheticOptions& o) { o.field_of_view = 29; }, "field_of_view");
  expect_invalid([](SyntheticOptions& o) { o.field_of_view = 151; }, "field_of_view");
}

TEST(SyntheticWorld, DefaultRouteHasRevisitsLightingAndObjects) {
  const SyntheticWorld w;
  EXPECT_EQ(w.frames(), 1090);
  std::int64_t next = 0, revisit_frames = 0;
  int revisits = 0;
  bool lighting = false, objects_on_revisit = false;
  for (const RouteSegment& seg : w.route()) {
    EXPECT_EQ(seg.first_frame, next) << seg.label;  // stretches tile the frames
    EXPECT_GT(seg.last_frame, seg.first_frame) << seg.label;
    EXPECT_LT(seg.s_begin, seg.s_end) << seg.label;
    EXPECT_DOUBLE_EQ(w.place(seg.first_frame), seg.s_begin);
    EXPECT_DOUBLE_EQ(w.place(seg.last_frame), seg.s_end);
    const int index = static_cast<int>(&seg - w.route().data());
    EXPECT_EQ(w.segment_of(seg.first_frame), index);
    EXPECT_EQ(w.segment_of(seg.last_frame), index);
    next = seg.last_frame + 1;
    if (!seg.revisit) continue;
    EXPECT_GT(seg.first_frame, 2 * kMinGap) << seg.label;
    ++revisits;
    revisit_frames += seg.last_frame - seg.first_frame + 1;
    lighting |= std::fabs(seg.light_gain - 1) >= 0.2 && seg.light_offset != 0;
    objects_on_revisit |= seg.moving_objects;
  }
  EXPECT_EQ(next, w.frames());
  EXPECT_GE(revisits, 3);
  EXPECT_GE(revisit_frames, 150);
  EXPECT_TRUE(lighting);
  EXPECT_TRUE(objects_on_revisit);
}

TEST(SyntheticWorld, OptionsSwitchLightingAndObjectsOff) {
  SyntheticOptions o;
  o.lighting_change = false;
  o.moving_objects = false;
  const SyntheticWorld w(o);
  for (const RouteSegment& seg : w.route()) {
    EXPECT_EQ(seg.light_gain, 1) << seg.label;
    EXPECT_EQ(seg.light_offset, 0) << seg.label;
    EXPECT_EQ(seg.light_gradient_x, 0) << seg.label;
    EXPECT_EQ(seg.light_gradient_y, 0) << seg.label;
    EXPECT_FALSE(seg.moving_objects) << seg.label;
    EXPECT_FALSE(seg.dense_objects) << seg.label;
  }
}

// Each switch acts alone: the other condition stays on the new stretches.
TEST(SyntheticWorld, SwitchesActOnTheNewStretchesIndependently) {
  SyntheticOptions daylight = SmallOptions(), still = SmallOptions();
  daylight.lighting_change = false;
  still.moving_objects = false;
  const SyntheticWorld no_light(daylight), no_objects(still), both(SmallOptions());
  ASSERT_EQ(no_light.frames(), both.frames());
  ASSERT_EQ(no_objects.frames(), both.frames());
  const RouteSegment *f = Stretch(no_light, "F:"), *g = Stretch(no_light, "G:"),
                     *h = Stretch(no_light, "H:");
  ASSERT_TRUE(f && g && h);
  EXPECT_EQ(f->light_gain, 1);
  EXPECT_EQ(g->light_gain, 1);
  EXPECT_TRUE(g->moving_objects);
  EXPECT_TRUE(h->moving_objects && h->dense_objects);
  EXPECT_EQ(h->label, "H: new street, dense moving objects");
  f = Stretch(no_objects, "F:"), g = Stretch(no_objects, "G:"), h = Stretch(no_objects, "H:");
  ASSERT_TRUE(f && g && h);
  EXPECT_EQ(f->light_gain, 0.75);
  EXPECT_EQ(g->light_gain, 1.1);
  EXPECT_FALSE(g->moving_objects);
  EXPECT_FALSE(h->moving_objects || h->dense_objects);
  EXPECT_EQ(g->label, "G: new street, bright lighting");
  EXPECT_EQ(h->label, "H: new street");
  // The switches change pixels, never the route or the ground truth.
  for (const SyntheticWorld* w : {&no_light, &no_objects}) {
    for (std::size_t i = 0; i < both.route().size(); ++i) {
      EXPECT_EQ(w->route()[i].first_frame, both.route()[i].first_frame);
      EXPECT_EQ(w->route()[i].s_begin, both.route()[i].s_begin);
    }
    EXPECT_EQ(w->ground_truth().pairs(), both.ground_truth().pairs());
  }
}

// F, G and H: new places under the conditions of the revisits, appended after
// E, where any accepted loop is a false positive.
TEST(SyntheticWorld, FinalStretchesAreNewPlacesUnderRevisitConditions) {
  const SyntheticWorld w;
  const RouteSegment *dim = Stretch(w, "A':"), *bright = Stretch(w, "A'':"), *f = Stretch(w, "F:"),
                     *g = Stretch(w, "G:"), *h = Stretch(w, "H:");
  ASSERT_TRUE(dim && bright && f && g && h);
  ASSERT_EQ(w.route().size(), 11u);
  EXPECT_EQ(f, &w.route()[8]);  // the last three stretches, in this order
  EXPECT_EQ(g, &w.route()[9]);
  EXPECT_EQ(h, &w.route()[10]);
  EXPECT_EQ(f->first_frame, kFirstRouteFrames);
  for (const RouteSegment* seg : {f, g, h}) {
    EXPECT_FALSE(seg->revisit) << seg->label;
    const std::int64_t n = seg->last_frame - seg->first_frame + 1;
    EXPECT_GE(n, 60) << seg->label;
    EXPECT_LE(n, 90) << seg->label;
  }
  // F: the lighting of A' (gain 0.75, offset +15, same gradients), no objects.
  EXPECT_EQ(dim->light_gain, 0.75);
  EXPECT_EQ(dim->light_offset, 15);
  EXPECT_EQ(f->light_gain, dim->light_gain);
  EXPECT_EQ(f->light_offset, dim->light_offset);
  EXPECT_EQ(f->light_gradient_x, dim->light_gradient_x);
  EXPECT_EQ(f->light_gradient_y, dim->light_gradient_y);
  EXPECT_FALSE(f->moving_objects);
  EXPECT_EQ(f->label, "F: new street, dim lighting");
  // G: the lighting of A'' and moving objects.
  EXPECT_EQ(g->light_gain, bright->light_gain);
  EXPECT_EQ(g->light_offset, bright->light_offset);
  EXPECT_EQ(g->light_gradient_x, bright->light_gradient_x);
  EXPECT_EQ(g->light_gradient_y, bright->light_gradient_y);
  EXPECT_TRUE(g->moving_objects);
  EXPECT_FALSE(g->dense_objects);
  EXPECT_EQ(g->label, "G: new street, bright lighting, moving objects");
  // H: daylight, the only stretch with dense objects.
  EXPECT_EQ(h->light_gain, 1);
  EXPECT_EQ(h->light_offset, 0);
  EXPECT_EQ(h->light_gradient_x, 0);
  EXPECT_EQ(h->light_gradient_y, 0);
  EXPECT_TRUE(h->moving_objects);
  for (const RouteSegment& seg : w.route()) EXPECT_EQ(seg.dense_objects, &seg == h) << seg.label;
}

// No frame of a new stretch (A to H) has a ground-truth match outside its own
// stretch (only temporal neighbours, which the temporal window removes), and
// each new region lies further along the street than the largest loop radius
// from everything before it; also at other scales and radii.
TEST(SyntheticWorld, NewStretchesHaveNoGroundTruthLoops) {
  for (const double scale : {1.0, 0.5, 2.0}) {
    for (const double radius : {2.5, 30.0}) {
      SyntheticOptions o = SmallOptions();
      o.route_scale = scale;
      o.loop_radius = radius;
      const SyntheticWorld w(o);
      const GroundTruth& gt = w.ground_truth();
      double furthest = -1e9;  // largest place shown before the stretch
      int new_stretches = 0;
      for (const RouteSegment& seg : w.route()) {
        if (!seg.revisit) {
          ++new_stretches;
          EXPECT_GT(seg.s_begin - furthest, 30) << seg.label << " scale " << scale;
          for (std::int64_t q = seg.first_frame; q <= seg.last_frame; ++q) {
            EXPECT_FALSE(gt.has_loop(q, kMinGap)) << seg.label << " frame " << q;
            for (std::int64_t m : gt.matches(q)) {
              ASSERT_GE(m, seg.first_frame) << seg.label << " frame " << q << " matches " << m
                                            << " (scale " << scale << ", radius " << radius << ")";
            }
          }
        }
        furthest = std::max(furthest, seg.s_end);
      }
      EXPECT_EQ(new_stretches, 8);
    }
  }
}

// Appending F, G and H left the first 854 frames, their places and their
// ground truth exactly as before (values pinned from the earlier generator).
TEST(SyntheticWorld, FramesBeforeTheAppendedStretchesAreUnchanged) {
  const SyntheticWorld w;
  const std::int64_t last_frames[] = {179, 299, 432, 527, 618, 698, 793, 853};
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_EQ(w.route()[i].last_frame, last_frames[i]) << w.route()[i].label;
  }
  EXPECT_EQ(w.place(299), 360);
  EXPECT_EQ(w.place(853), 780);
  const struct {
    std::int64_t frame;
    std::uint64_t checksum;
  } pinned[] = {
      {0, 0x09cce6985efdccebull},   {299, 0x862830944c643831ull},  // A, B
      {432, 0x7cb33fd868859875ull}, {500, 0xbebf47a2da90cdb1ull},  // A' (dim), C (objects)
      {600, 0x5026115cc11ae25full}, {750, 0xc72f2d8f7b76d4b4ull},  // B', A'' (bright, objects)
      {853, 0x8d05b97fb67398e3ull},                                // the last frame of E
  };
  for (const auto& p : pinned) {
    const std::uint64_t h = Checksum(w.render(p.frame));
    EXPECT_EQ(h, p.checksum) << "frame " << p.frame << ": checksum 0x" << std::hex << h;
  }
  // The ground truth of frames 0-853: every match list, hashed in order.
  std::uint64_t h = 1469598103934665603ull;
  std::int64_t pairs = 0;
  for (std::int64_t q = 0; q < kFirstRouteFrames; ++q) {
    for (std::int64_t m : w.ground_truth().matches(q)) {
      h = (h ^ static_cast<std::uint64_t>(q * kFirstRouteFrames + m)) * 1099511628211ull;
      ++pairs;
    }
  }
  EXPECT_EQ(pairs, 3561);
  EXPECT_EQ(h, 0x5ba9d623d7c9625eull) << "ground-truth hash 0x" << std::hex << h;
}

TEST(WriteSyntheticDataset, WritesImagesListAndGroundTruth) {
  namespace fs = std::filesystem;
  SyntheticOptions options;
  options.width = 64;
  options.height = 48;
  options.route_scale = 0.1;
  const SyntheticWorld world(options);
  const fs::path dir = fs::path(LSGD_TEST_TMP) / ("synthetic-ds-" + std::to_string(getpid()));
  fs::remove_all(dir);
  write_synthetic_dataset(world, dir.string());
  std::ifstream list(dir / "sequence.txt");
  std::string line;
  std::int64_t n = 0;
  while (std::getline(list, line)) {
    if (n == 3) {
      EXPECT_EQ(line, "images/000003.png");
      const cv::Mat image = cv::imread((dir / line).string(), cv::IMREAD_UNCHANGED);
      ASSERT_FALSE(image.empty());
      EXPECT_EQ(cv::norm(image, world.render(3), cv::NORM_INF), 0.0);  // lossless PNG
    }
    ++n;
  }
  EXPECT_EQ(n, world.frames());
  const GroundTruth gt = read_pairs((dir / "groundtruth.txt").string(), world.frames());
  EXPECT_EQ(gt.pairs(), world.ground_truth().pairs());
  // A folder that cannot be created: IoError naming it.
  std::ofstream(dir / "file") << "x";
  const std::string bad = (dir / "file" / "sub").string();
  try {
    write_synthetic_dataset(world, bad);
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(SyntheticWorld, RouteScaleScalesFrameCount) {
  SyntheticOptions o;
  o.route_scale = 0.5;
  const std::int64_t half = SyntheticWorld(o).frames();
  const std::int64_t full = SyntheticWorld().frames();
  EXPECT_NEAR(static_cast<double>(half), 0.5 * static_cast<double>(full), 0.02 * full);
}

TEST(SyntheticWorld, FramesHaveSizeTypeAndStructure) {
  SyntheticOptions o;
  o.width = 100;
  o.height = 64;
  const SyntheticWorld small(o);
  const cv::Mat f = small.render(0);
  EXPECT_EQ(f.cols, 100);
  EXPECT_EQ(f.rows, 64);
  EXPECT_EQ(f.type(), CV_8UC3);

  const SyntheticWorld w;
  for (std::int64_t i = 0; i < w.frames(); i += 97) {
    const cv::Mat img = w.render(i);
    ASSERT_EQ(img.type(), CV_8UC3);
    ASSERT_EQ(img.cols, 320);
    ASSERT_EQ(img.rows, 240);
    cv::Scalar mean, dev;
    cv::meanStdDev(Gray(img), mean, dev);
    EXPECT_GT(dev[0], 20) << "frame " << i << " is nearly flat";
    EXPECT_GT(mean[0], 40) << "frame " << i;
    EXPECT_LT(mean[0], 215) << "frame " << i;
  }
}

TEST(SyntheticWorld, RenderingIsDeterministicAndSeeded) {
  const SyntheticWorld a(SmallOptions()), b(SmallOptions());
  SyntheticOptions other = SmallOptions();
  other.seed = 2;
  const SyntheticWorld c(other);
  ASSERT_EQ(a.frames(), b.frames());
  for (std::int64_t i : {std::int64_t{0}, std::int64_t{250}, a.frames() - 1}) {
    const cv::Mat fa = a.render(i);
    EXPECT_EQ(cv::norm(fa, b.render(i), cv::NORM_INF), 0) << "frame " << i;
    EXPECT_EQ(cv::norm(fa, a.render(i), cv::NORM_INF), 0) << "frame " << i;
    EXPECT_GT(MeanAbsDiff(fa, c.render(i)), 5) << "frame " << i;
  }
}

TEST(SyntheticWorld, FrameChecksum) {
  // Guards cross-platform determinism of the default world: frame 123 of seed 1
  // must not change unless the generator is deliberately changed.
  const cv::Mat f = SyntheticWorld().render(123);
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a
  for (int r = 0; r < f.rows; ++r) {
    for (int c = 0; c < f.cols * 3; ++c) h = (h ^ f.ptr<std::uint8_t>(r)[c]) * 1099511628211ull;
  }
  EXPECT_EQ(h, 0x14488942d7637af8ull) << "checksum 0x" << std::hex << h;
  // And one frame of each appended stretch: F (dim), G (bright, objects), H (dense objects).
  const SyntheticWorld w;
  const struct {
    std::int64_t frame;
    std::uint64_t checksum;
  } pinned[] = {
      {880, 0x4aea3f516b0fa14aull}, {960, 0x404bb0c0f96aa921ull}, {1050, 0x4cd3ce38d2cda16bull}};
  for (const auto& p : pinned) {
    const std::uint64_t c = Checksum(w.render(p.frame));
    EXPECT_EQ(c, p.checksum) << "frame " << p.frame << ": checksum 0x" << std::hex << c;
  }
}

TEST(SyntheticWorld, RenderAndPlaceRejectFramesOutside) {
  const SyntheticWorld w(SmallOptions());
  EXPECT_THROW(w.render(-1), InvalidArgument);
  EXPECT_THROW(w.render(w.frames()), InvalidArgument);
  EXPECT_THROW(w.place(-1), InvalidArgument);
  EXPECT_THROW(w.place(w.frames()), InvalidArgument);
  EXPECT_NO_THROW(w.render(w.frames() - 1));
}

TEST(SyntheticWorld, GroundTruthMatchesRouteGeometry) {
  const SyntheticWorld w(SmallOptions());
  const GroundTruth& gt = w.ground_truth();
  const double radius = w.options().loop_radius;
  ASSERT_EQ(gt.frames(), w.frames());
  std::int64_t positives = 0;
  for (std::int64_t q = 0; q < w.frames(); ++q) {
    for (std::int64_t m : gt.matches(q)) {
      EXPECT_LE(std::fabs(w.place(q) - w.place(m)), radius) << q << " " << m;
    }
    positives += gt.has_loop(q, kMinGap) ? 1 : 0;
  }
  EXPECT_GE(positives, 150);
  for (const RouteSegment& seg : w.route()) {
    for (std::int64_t q = seg.first_frame; q <= seg.last_frame; ++q) {
      EXPECT_EQ(gt.has_loop(q, kMinGap), seg.revisit) << seg.label << " frame " << q;
    }
  }
  // Exactness: a pair within the radius is in the ground truth.
  const RouteSegment& first = w.route()[0];
  for (std::int64_t q = first.last_frame + 1; q < w.frames(); q += 7) {
    for (std::int64_t m = first.first_frame; m <= first.last_frame; ++m) {
      const bool near = std::fabs(w.place(q) - w.place(m)) <= radius;
      EXPECT_EQ(gt.is_loop(q, m), near) << q << " " << m;
    }
  }
}

TEST(SyntheticWorld, LoopRadiusControlsMatchesPerRevisitFrame) {
  SyntheticOptions o = SmallOptions();
  o.loop_radius = 2.5;
  const SyntheticWorld w(o);
  for (const RouteSegment& seg : w.route()) {
    if (!seg.revisit) continue;
    for (std::int64_t q = seg.first_frame; q <= seg.last_frame; ++q) {
      std::int64_t old = 0;
      for (std::int64_t m : w.ground_truth().matches(q)) old += q - m > kMinGap ? 1 : 0;
      EXPECT_GE(old, 4) << seg.label << " frame " << q;  // about +-2 frames of a traverse
    }
  }
}

// The same place seen on two traverses looks alike; other places do not.
TEST(SyntheticWorld, RevisitsLookLikeTheirMatches) {
  const SyntheticWorld w(SmallOptions());
  std::uint64_t rng = 12345;
  int compared = 0, closer = 0;
  double match_sum = 0, other_sum = 0;
  for (const RouteSegment& seg : w.route()) {
    if (!seg.revisit) continue;
    for (std::int64_t q = seg.first_frame; q <= seg.last_frame; q += 12) {
      const std::int64_t m = ClosestOldMatch(w, q);
      ASSERT_GE(m, 0) << seg.label << " frame " << q;
      std::int64_t far = -1;
      while (far < 0 || std::fabs(w.place(far) - w.place(q)) < 40) {
        rng = rng * 6364136223846793005ull + 1442695040888963407ull;
        far = static_cast<std::int64_t>((rng >> 33) % static_cast<std::uint64_t>(q));
      }
      const cv::Mat nq = Normalised(w.render(q));
      const double d_match = MeanAbsDiff(nq, Normalised(w.render(m)));
      const double d_other = MeanAbsDiff(nq, Normalised(w.render(far)));
      match_sum += d_match;
      other_sum += d_other;
      ++compared;
      closer += d_match < d_other ? 1 : 0;
    }
  }
  ASSERT_GE(compared, 20);
  EXPECT_GE(closer, compared * 9 / 10) << closer << " of " << compared;
  EXPECT_LT(match_sum, 0.7 * other_sum) << match_sum / compared << " vs " << other_sum / compared;
}

TEST(SyntheticWorld, LightingChangeShiftsBrightness) {
  SyntheticOptions lit = SmallOptions(), plain = SmallOptions();
  lit.moving_objects = plain.moving_objects = false;
  plain.lighting_change = false;
  const SyntheticWorld a(lit), b(plain);
  int changed = 0;
  for (const RouteSegment& seg : a.route()) {
    const std::int64_t q = (seg.first_frame + seg.last_frame) / 2;
    const cv::Mat ga = Gray(a.render(q)), gb = Gray(b.render(q));
    if (seg.light_gain == 1 && seg.light_offset == 0) {
      EXPECT_EQ(MeanAbsDiff(ga, gb), 0) << seg.label;  // daylight: the very same frame
      continue;
    }
    ++changed;
    cv::Scalar ma, da, mb, db;
    cv::meanStdDev(ga, ma, da);
    cv::meanStdDev(gb, mb, db);
    EXPECT_NEAR(da[0] / db[0], seg.light_gain, 0.1) << seg.label;
    EXPECT_GT(MeanAbsDiff(ga, gb), 5) << seg.label;
  }
  EXPECT_EQ(changed, 4);  // A', A'', F, G
}

TEST(SyntheticWorld, MovingObjectsOccludePartOfTheView) {
  SyntheticOptions with = SmallOptions(), without = SmallOptions();
  without.moving_objects = false;
  const SyntheticWorld a(with), b(without);
  double dense_cover = 0, most_other_cover = 0;  // mean changed pixels per frame
  for (const RouteSegment& seg : a.route()) {
    int changed_frames = 0, frames = 0;
    double changed_pixels = 0;
    for (std::int64_t q = seg.first_frame; q <= seg.last_frame; q += 5, ++frames) {
      cv::Mat diff;
      cv::absdiff(Gray(a.render(q)), Gray(b.render(q)), diff);
      const int n = cv::countNonZero(diff > 30);
      changed_pixels += n;
      changed_frames += n > 20 ? 1 : 0;
    }
    if (seg.moving_objects) {
      EXPECT_GE(changed_frames, frames / 2) << seg.label;
    } else {
      EXPECT_EQ(changed_frames, 0) << seg.label;
    }
    const double cover = changed_pixels / frames;
    if (seg.dense_objects) {
      dense_cover = cover;
      EXPECT_GE(changed_frames, frames * 9 / 10) << seg.label;
    } else {
      most_other_cover = std::max(most_other_cover, cover);
    }
  }
  // Dense objects (H) hide far more of the view than the objects elsewhere.
  EXPECT_GT(dense_cover, 3 * most_other_cover) << dense_cover << " vs " << most_other_cover;
}

}  // namespace
}  // namespace lsgd::eval
