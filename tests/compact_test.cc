// Tests of compact histogram storage (descriptor.storage = compact,
// include/lsgd/descriptor.h): the encoding by hand, its similarity against the
// exact one, the store, and the detector end to end on the synthetic street.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "lsgd/descriptor.h"
#include "lsgd/detector.h"
#include "lsgd/error.h"
#include "synthetic/synthetic.h"
#include "lsgd/frame_store.h"
#include "lsgd/similarity.h"
#include "test_util.h"

namespace lsgd {
namespace {

using test::message_of;

const SimilarityMetric kMetrics[] = {SimilarityMetric::kReference, SimilarityMetric::kL1,
                                     SimilarityMetric::kNormalizedL1};

// Exact descriptor of one row of cells, each given as (bin, count) pairs.
constexpr auto make = test::make_descriptor;

Descriptor compacted(const Descriptor& exact) {
  Descriptor out;
  compact(exact, out);
  return out;
}

// Exact descriptors of synthetic-street frames 0, step, 2 step, ...
std::vector<Descriptor> street(int frames, int step) {
  eval::SyntheticOptions o;
  o.width = 160;
  o.height = 120;
  const eval::SyntheticWorld world(o);
  SegmentationOptions so;
  so.superpixel_size = 16;
  Segmenter segmenter(so);
  std::vector<Descriptor> out;
  for (int i = 0; i < frames; ++i) {
    cv::Mat gray;
    cv::cvtColor(world.render(static_cast<std::int64_t>(i) * step), gray, cv::COLOR_BGR2GRAY);
    GrayImage image;
    to_gray(gray, image);
    out.push_back(describe(image, segmenter.segment(image)));
  }
  return out;
}

TEST(HistogramStorageNames, RoundTripAndRejectUnknown) {
  for (auto s : {HistogramStorage::kExact, HistogramStorage::kCompact}) {
    EXPECT_EQ(parse_histogram_storage(to_string(s)), s);
  }
  const std::string m = message_of<InvalidArgument>([] { parse_histogram_storage("u8"); });
  EXPECT_NE(m.find("'u8'"), std::string::npos) << m;
  EXPECT_NE(m.find("exact or compact"), std::string::npos) << m;
  DescriptorOptions o;
  EXPECT_EQ(o.storage, HistogramStorage::kExact);  // the paper's histogram by default
  EXPECT_NO_THROW(o.check());
  o.storage = static_cast<HistogramStorage>(7);
  EXPECT_THROW(o.check(), InvalidArgument);
}

TEST(CompactDescriptor, EncodesByHand) {
  // Cell 0: 2048 pixels, so one pixel is half a unit of the 1024 mass.
  // Cell 1: empty. Cell 2: 1024 pixels, one bin holding them all.
  const Descriptor exact =
      make({{{0, 100}, {1, 28}, {2, 1}, {4, 1}, {5, 1}, {6, 3}, {200, 1914}}, {}, {{255, 1024}}});
  const Descriptor c = compacted(exact);
  EXPECT_EQ(c.storage, HistogramStorage::kCompact);
  EXPECT_EQ(c.grid, exact.grid);
  EXPECT_TRUE(c.hist.empty());
  EXPECT_TRUE(c.pixels.empty());
  ASSERT_EQ(c.compact.size(), 3u * kCompactBins);
  EXPECT_DOUBLE_EQ(c.cell_pixels, (2048.0 + 0 + 1024) / 3);
  const CompactBin* q = c.compact.data();
  EXPECT_EQ(q[0], 64);     // bins 0+1: 128 pixels * 1024 / 2048
  EXPECT_EQ(q[1], 1);      // bin 2: 0.5 rounds up
  EXPECT_EQ(q[2], 1);      // bins 4+5: 2 pixels -> 1
  EXPECT_EQ(q[3], 2);      // bin 6: 3 pixels -> 1.5 -> 2
  EXPECT_EQ(q[100], 255);  // bin 200: 1914 pixels -> 957, saturated
  for (int b = 4; b < kCompactBins; ++b) {
    if (b != 100) {
      EXPECT_EQ(q[b], 0) << "bin " << b;
    }
  }
  for (int b = 0; b < kCompactBins; ++b) EXPECT_EQ(q[kCompactBins + b], 0);  // the empty cell
  EXPECT_EQ(q[2 * kCompactBins + 127], 255);  // 1024 of 1024 pixels, saturated
  EXPECT_EQ(Descriptor::bytes_per_frame(HistogramStorage::kCompact, 80), 10240u);
  EXPECT_EQ(Descriptor::bytes_per_frame(HistogramStorage::kExact, 80), 41280u);
}

TEST(CompactDescriptor, RejectsCompactOrInconsistentInput) {
  const Descriptor exact = make({{{3, 10}}, {{4, 10}}});
  Descriptor c = compacted(exact);
  Descriptor out;
  EXPECT_NE(message_of<InvalidArgument>([&] { compact(c, out); }).find("already compact"),
            std::string::npos);
  Descriptor broken = exact;
  broken.pixels.pop_back();
  EXPECT_THROW(compact(broken, out), InvalidArgument);
  c.compact.pop_back();
  const std::string m = message_of<InvalidArgument>([&] { c.check_consistent("here"); });
  EXPECT_NE(m.find("here"), std::string::npos) << m;
  EXPECT_NE(m.find("255 compact bins"), std::string::npos) << m;
}

TEST(CompactSimilarity, IdenticalIsOneAndMixedStorageThrows) {
  const std::vector<Descriptor> frames = street(2, 30);
  const Descriptor a = compacted(frames[0]);
  for (const SimilarityMetric m : kMetrics) {
    EXPECT_EQ(similarity(a.view(), a.view(), m), 1.0) << to_string(m);
  }
  const std::string m = message_of<InvalidArgument>(
      [&] { similarity(a.view(), frames[1].view(), SimilarityMetric::kReference); });
  EXPECT_NE(m.find("compact"), std::string::npos) << m;
  EXPECT_NE(m.find("exact"), std::string::npos) << m;
}

TEST(CompactSimilarity, HandComputed) {
  // Two cells of 1024 pixels: the compact values are the pair counts.
  const Descriptor a = compacted(make({{{0, 1000}, {10, 24}}, {{50, 1024}}}));
  const Descriptor b = compacted(make({{{0, 900}, {12, 124}}, {{51, 1024}}}));
  // Cell 0: bins 0 (255 vs 255, both saturated), 5 (24 vs 0), 6 (0 vs 124): SAD 148.
  // Cell 1: pair 25 holds bins 50 and 51: SAD 0.
  const double ref = 1.0 / (1.0 + (std::sqrt(148.0) / 256 + 0.0) / 2);
  EXPECT_NEAR(similarity(a.view(), b.view(), SimilarityMetric::kReference), ref, 1e-12);
  const double l1 = 1.0 - 148.0 / (2.0 * 1024 * 2);
  EXPECT_NEAR(similarity(a.view(), b.view(), SimilarityMetric::kL1), l1, 1e-12);
  EXPECT_NEAR(similarity(a.view(), b.view(), SimilarityMetric::kNormalizedL1), l1, 1e-12);
}

TEST(CompactSimilarity, CloseToExactOnRealFrames) {
  // Frames 0..19 of the street, every 15th frame: the compact scores must stay
  // close to the exact ones and rank each frame's best match the same way in
  // most cases (the measured effect on whole datasets is in docs/performance.md).
  const std::vector<Descriptor> exact = street(20, 15);
  std::vector<Descriptor> c;
  for (const Descriptor& d : exact) c.push_back(compacted(d));
  for (const SimilarityMetric m : kMetrics) {
    double worst = 0;
    int same_best = 0;
    for (std::size_t i = 0; i < exact.size(); ++i) {
      std::size_t best_e = 0, best_c = 0;
      double score_e = -1, score_c = -1;
      for (std::size_t j = 0; j < exact.size(); ++j) {
        if (j == i) continue;
        const double e = similarity(exact[i].view(), exact[j].view(), m);
        const double q = similarity(c[i].view(), c[j].view(), m);
        worst = std::max(worst, std::fabs(e - q));
        if (e > score_e) score_e = e, best_e = j;
        if (q > score_c) score_c = q, best_c = j;
      }
      same_best += best_e == best_c ? 1 : 0;
    }
    // The reference metric (the default) works on pixel counts and is hurt
    // least; the mass-normalised metrics see every saturated bin's lost mass.
    const bool reference = m == SimilarityMetric::kReference;
    EXPECT_LT(worst, reference ? 0.01 : 0.06) << to_string(m);
    EXPECT_GE(same_best, reference ? 17 : 15) << to_string(m);
    std::printf("%s: largest score difference %.4f, same best match for %d of 20 frames\n",
                to_string(m), worst, same_best);
  }
}

TEST(CompactFrameStore, StoresTheBytesAndRejectsMixing) {
  const std::vector<Descriptor> exact = street(3, 40);
  FrameStore store;
  const Descriptor c0 = compacted(exact[0]);
  store.add(c0);
  store.add(compacted(exact[1]));
  EXPECT_EQ(store.storage(), HistogramStorage::kCompact);
  EXPECT_EQ(store.bytes_per_frame(), static_cast<std::size_t>(c0.grid.cells()) * kCompactBins);
  const DescriptorView v = store.view(0);
  EXPECT_EQ(v.storage(), HistogramStorage::kCompact);
  EXPECT_EQ(v.hist, nullptr);
  EXPECT_EQ(v.cell_pixels, c0.cell_pixels);
  EXPECT_TRUE(std::equal(c0.compact.begin(), c0.compact.end(), v.compact));

  // An exact frame, or one of another image size, cannot join: store unchanged.
  const std::string m = message_of<InvalidArgument>([&] { store.add(exact[2]); });
  EXPECT_NE(m.find("exact descriptor cannot join a store of compact"), std::string::npos) << m;
  Descriptor other = compacted(exact[2]);
  other.cell_pixels += 1;
  EXPECT_THROW(store.add(other), InvalidArgument);
  EXPECT_EQ(store.size(), 2);

  // Many chunks, and a deep copy.
  for (int i = 0; i < 3000; ++i) store.add(compacted(exact[i % 3]));
  const FrameStore copy = store;
  EXPECT_TRUE(std::equal(c0.compact.begin(), c0.compact.end(), copy.view(2999).compact));
  EXPECT_NE(copy.view(2999).compact, store.view(2999).compact);
}

TEST(CompactDetector, TenKilobytesPerKittiFrameAndResultsCloseToExact) {
  DetectorOptions ko;
  ko.segmentation.superpixel_size = 40;
  ko.descriptor.storage = HistogramStorage::kCompact;
  ko.segmentation.working_side = 0;  // the paper's size
  Detector kitti(ko);
  kitti.process(cv::Mat(376, 1241, CV_8UC1, cv::Scalar(90)));
  EXPECT_EQ(kitti.bytes_per_frame(), 10240u);  // 80 cells x 128 bytes
  ko.segmentation.working_side = 240;  // the default: segmented at 792 x 240
  Detector scaled(ko);
  scaled.process(cv::Mat(376, 1241, CV_8UC1, cv::Scalar(90)));
  EXPECT_EQ(scaled.bytes_per_frame(), 5120u);  // 4 x 10 cells x 128 bytes

  // The street's first revisit (frames ~300 on): both storages find loops
  // there, mostly to the same frames.
  eval::SyntheticOptions wo;
  wo.width = 160;
  wo.height = 120;
  const eval::SyntheticWorld world(wo);
  DetectorOptions o;
  o.segmentation.superpixel_size = 16;
  o.search.min_gap = 20;
  Detector exact(o);
  o.descriptor.storage = HistogramStorage::kCompact;
  Detector small(o);
  int compared = 0, same = 0;
  for (std::int64_t i = 0; i < 420; i += 2) {
    const cv::Mat frame = world.render(i);
    const Result e = exact.process(frame);
    const Result c = small.process(frame);
    ASSERT_EQ(e.frame, c.frame);
    if (e.best.frame < 0) continue;
    ++compared;
    same += std::abs(e.best.frame - c.best.frame) <= 1 ? 1 : 0;
  }
  EXPECT_GE(compared, 150);
  EXPECT_GE(same, compared * 9 / 10) << same << " of " << compared;
  EXPECT_EQ(small.store().storage(), HistogramStorage::kCompact);
  const auto cells = static_cast<std::size_t>(small.store().grid().cells());
  EXPECT_EQ(small.bytes_per_frame(), cells * kCompactBins);
  EXPECT_EQ(exact.bytes_per_frame(), cells * (kBins * 2 + 4));
}

// A frame's state blob with the given records (state.h).
std::vector<std::uint8_t> records(std::vector<StateRecord> r) { return encode_records(r); }

std::vector<std::uint8_t> node_state(std::int64_t node) {
  StateWriter w;
  w.put_i64(node);
  return records({{kNodesSearch, 1, w.bytes()}});
}

TEST(CompactDetector, RestoreFramePlacesFramesByNode) {
  DetectorOptions o;
  o.segmentation.superpixel_size = 16;
  o.descriptor.storage = HistogramStorage::kCompact;
  o.verification.stages = {};
  const std::vector<Descriptor> exact = street(1, 1);
  const Descriptor c = compacted(exact[0]);
  {
    Detector d(o);  // exhaustive: no groups, no search state
    const std::string m = message_of<InvalidArgument>([&] { d.restore_frame(160, 120, c, node_state(1)); });
    EXPECT_NE(m.find("frame 0 has state of 'nodes', which these options do not have (search mode "
                     "exhaustive, verification stages none)"),
              std::string::npos)
        << m;
    EXPECT_EQ(d.size(), 0);
  }
  o.search.mode = kNodesSearch;
  Detector d(o);
  for (const std::int64_t bad : {-1, 1}) {
    const std::string m = message_of<InvalidArgument>([&] { d.restore_frame(160, 120, c, node_state(bad)); });
    EXPECT_NE(m.find("frame 0's nodes state: node " + std::to_string(bad) +
                     " does not exist yet (0 nodes before this frame)"),
              std::string::npos)
        << m;
  }
  // A nodes detector needs each frame's node.
  const std::string m = message_of<InvalidArgument>([&] { d.restore_frame(160, 120, c, records({})); });
  EXPECT_NE(m.find("frame 0's nodes state: there is no record"), std::string::npos) << m;
  EXPECT_EQ(d.size(), 0);
  EXPECT_EQ(d.nodes(), 0);
  // A group's chunks hold 1, 1, 1, 1, 2, 3, ... frames (half what it has), so
  // node 0's fifth and sixth frames (ids 5 and 7) share a chunk, side by side.
  for (const std::int64_t node : {0, 0, 0, 0, 1, 0, 2, 0, 1}) {
    d.restore_frame(160, 120, c, node_state(node));
  }
  EXPECT_EQ(d.store().groups(), 3);
  EXPECT_EQ(d.nodes(), 3);
  EXPECT_EQ(d.search().members(1), (std::vector<std::int64_t>{4, 8}));
  const std::size_t stride = static_cast<std::size_t>(c.grid.cells()) * kCompactBins;
  EXPECT_EQ(d.store().view(7).compact, d.store().view(5).compact + stride);
  EXPECT_THROW(d.restore_frame(160, 120, c, node_state(4)), InvalidArgument);
  EXPECT_EQ(d.size(), 9);
  for (std::int64_t f = 0; f < 9; ++f) {
    // Saved as restored: the node, then the decision (no loop, no ranking
    // track: version 2 writes both), then the frame's id (its number: none
    // was given) and no time stamp.
    StateWriter w;
    w.put_i64(d.search().group_of(f));
    StateWriter loop;
    loop.put_i64(-1);
    loop.put_f64(0);
    loop.put_i64(-1);
    loop.put_f64(0);
    StateWriter tag;
    tag.put_i64(f);
    tag.put_f64(kNoStamp);
    EXPECT_EQ(d.frame_state(f), records({{kNodesSearch, 1, w.bytes()}, {"decision", 2, loop.bytes()},
                                         {"frame", 1, tag.bytes()}}));
  }
  EXPECT_THROW(d.frame_state(9), InvalidArgument);
  EXPECT_THROW(d.search().members(3), InvalidArgument);
}

// A damaged or foreign state blob is refused, detector unchanged: cut,
// trailing bytes, a repeated record, a newer version, a record too short.
TEST(CompactDetector, RestoreFrameRefusesDamagedState) {
  DetectorOptions o;
  o.segmentation.superpixel_size = 16;
  o.descriptor.storage = HistogramStorage::kCompact;
  o.search.mode = kNodesSearch;
  o.verification.stages = {kTemporalStage};
  const Descriptor c = compacted(street(1, 1)[0]);
  Detector d(o);
  const std::vector<std::uint8_t> good = node_state(0);
  const auto refused = [&](const std::vector<std::uint8_t>& state) {
    return message_of<InvalidArgument>([&] { d.restore_frame(160, 120, c, state); });
  };
  std::vector<std::uint8_t> cut(good.begin(), good.end() - 1);
  EXPECT_NE(refused(cut).find("is cut in a record"), std::string::npos) << refused(cut);
  std::vector<std::uint8_t> longer = good;
  longer.push_back(0);
  EXPECT_NE(refused(longer).find("1 bytes after its 1 records"), std::string::npos);
  StateWriter w;
  w.put_i64(0);
  EXPECT_NE(refused(records({{kNodesSearch, 1, w.bytes()}, {kNodesSearch, 1, w.bytes()}}))
                .find("two records of 'nodes'"),
            std::string::npos);
  EXPECT_NE(refused(records({{kNodesSearch, 2, w.bytes()}}))
                .find("version 2 of nodes's state is not one this lsgd reads (1 to 1)"),
            std::string::npos);
  EXPECT_NE(refused(records({{kNodesSearch, 1, {1, 2, 3}}})).find("too few for its content"),
            std::string::npos);
  StateWriter place;
  place.put_i64(0);  // not an earlier frame
  EXPECT_NE(refused(records({{kNodesSearch, 1, w.bytes()}, {kTemporalStage, 1, place.bytes()}}))
                .find("place 0 is not an earlier frame or -1"),
            std::string::npos);
  EXPECT_EQ(d.size(), 0);
  EXPECT_EQ(d.nodes(), 0);
  d.restore_frame(160, 120, c, good);  // the temporal place may be absent (older databases)
  EXPECT_EQ(d.size(), 1);
}

TEST(CompactDetector, RestoreFrameChecksStorageAndSize) {
  DetectorOptions o;
  o.segmentation.superpixel_size = 16;
  o.descriptor.storage = HistogramStorage::kCompact;
  Detector d(o);
  // The default stages: the geometric stage needs the frame's features (none here).
  const std::vector<std::uint8_t> state = records({{kGeometricStage, 1, {}}});
  const std::vector<Descriptor> exact = street(1, 1);
  const std::string m = message_of<InvalidArgument>([&] { d.restore_frame(160, 120, exact[0], state); });
  EXPECT_NE(m.find("descriptor.storage is compact"), std::string::npos) << m;
  Descriptor c = compacted(exact[0]);
  c.cell_pixels *= 2;
  EXPECT_NE(
      message_of<InvalidArgument>([&] { d.restore_frame(160, 120, c, state); }).find("pixels per cell"),
      std::string::npos);
  EXPECT_NE(message_of<InvalidArgument>([&] { d.restore_frame(160, 120, compacted(exact[0]), records({})); })
                .find("frame 0's geometric state: there is no record of its features"),
            std::string::npos);
  EXPECT_EQ(d.size(), 0);
  EXPECT_NO_THROW(d.restore_frame(160, 120, compacted(exact[0]), state));
  EXPECT_EQ(d.size(), 1);
}

}  // namespace
}  // namespace lsgd
