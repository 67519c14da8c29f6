// Tests of the chunked descriptor store (frame_store.h).
#include "lsgd/frame_store.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "lsgd/error.h"
#include "test_util.h"

namespace lsgd {
namespace {

// A descriptor of `cells` cells whose bins encode the frame id.
Descriptor numbered(int rows, int cols, std::int64_t id) {
  Descriptor d;
  d.grid = {rows, cols};
  d.hist.assign(static_cast<std::size_t>(d.grid.cells()) * kBins, 0);
  d.pixels.assign(static_cast<std::size_t>(d.grid.cells()), 0);
  for (int k = 0; k < d.grid.cells(); ++k) {
    d.hist[static_cast<std::size_t>(k) * kBins + static_cast<std::size_t>(id % kBins)] =
        static_cast<Bin>(id / kBins + 1);
    d.hist[static_cast<std::size_t>(k) * kBins + 255] = static_cast<Bin>(k);
    d.pixels[k] = static_cast<Count>(id + k);
  }
  return d;
}

TEST(FrameStore, ManyChunksKeepEveryFrameAndViewsStayValid) {
  FrameStore store;
  const int rows = 5, cols = 16;  // KITTI-size grid: ~100 frames per 4 MiB chunk
  store.add(numbered(rows, cols, 0));
  const std::int64_t per_chunk = store.max_chunk_frames();
  ASSERT_GT(per_chunk, 10);
  ASSERT_LT(per_chunk, 1000);
  const DescriptorView first = store.view(0);
  const std::int64_t frames = 3 * per_chunk + 7;  // crosses chunk boundaries
  for (std::int64_t i = 1; i < frames; ++i) EXPECT_EQ(store.add(numbered(rows, cols, i)), i);
  EXPECT_EQ(store.size(), frames);
  EXPECT_EQ(store.view(0).hist, first.hist);  // no frame moved
  for (std::int64_t i = 0; i < frames; ++i) {
    const Descriptor want = numbered(rows, cols, i);
    const DescriptorView v = store.view(i);
    ASSERT_EQ(v.cells, rows * cols);
    ASSERT_TRUE(std::equal(want.hist.begin(), want.hist.end(), v.hist)) << "frame " << i;
    ASSERT_TRUE(std::equal(want.pixels.begin(), want.pixels.end(), v.pixels)) << "frame " << i;
  }
  EXPECT_EQ(store.bytes_per_frame(), static_cast<std::size_t>(rows * cols) * (kBins * 2 + 4));
}

TEST(FrameStore, CopiesAreDeepAndIndependent) {
  FrameStore a;
  for (std::int64_t i = 0; i < 300; ++i) a.add(numbered(5, 16, i));
  FrameStore b = a;
  b.add(numbered(5, 16, 300));
  EXPECT_EQ(a.size(), 300);
  EXPECT_EQ(b.size(), 301);
  EXPECT_NE(a.view(7).hist, b.view(7).hist);
  EXPECT_TRUE(std::equal(a.view(7).hist, a.view(7).hist + 80 * kBins, b.view(7).hist));
  FrameStore c;
  c = b;
  EXPECT_EQ(c.view(300).pixels[0], 300u);
}

TEST(FrameStore, RejectedFramesLeaveTheStoreUnchanged) {
  FrameStore store;
  store.add(numbered(2, 3, 0));
  EXPECT_THROW(store.add(numbered(3, 2, 1)), InvalidArgument);  // other grid
  Descriptor broken = numbered(2, 3, 1);
  broken.hist.pop_back();
  EXPECT_THROW(store.add(broken), InvalidArgument);
  EXPECT_EQ(store.size(), 1);
  EXPECT_THROW(store.view(1), InvalidArgument);
  EXPECT_THROW(store.view(-1), InvalidArgument);
  EXPECT_EQ(store.add(numbered(2, 3, 1)), 1);
}

TEST(FrameStore, TinyGridsUseLargeChunksAndReserveIsHarmless) {
  FrameStore store;
  store.reserve(100);  // before the first frame: no grid yet, nothing to do
  store.add(numbered(1, 1, 0));
  EXPECT_EQ(store.max_chunk_frames(),
            static_cast<std::int64_t>((std::size_t{4} << 20) / (kBins * 2)));
  store.reserve(20000);
  for (std::int64_t i = 1; i < 9000; ++i) store.add(numbered(1, 1, i));
  EXPECT_EQ(store.view(8999).pixels[0], 8999u);
}

// Compact descriptor of a 2x3 grid whose first bin holds the frame id.
Descriptor compact_numbered(std::int64_t id) {
  Descriptor d;
  d.grid = {2, 3};
  d.storage = HistogramStorage::kCompact;
  d.cell_pixels = 100;
  d.compact.assign(static_cast<std::size_t>(d.grid.cells()) * kCompactBins, 0);
  for (int k = 0; k < d.grid.cells(); ++k) {
    d.compact[static_cast<std::size_t>(k) * kCompactBins] = static_cast<CompactBin>(id % 251);
    d.compact[static_cast<std::size_t>(k) * kCompactBins + 1] = static_cast<CompactBin>(id / 251);
  }
  return d;
}

std::int64_t id_of(const DescriptorView& v) { return v.compact[0] + 251 * v.compact[1]; }

TEST(FrameStore, GroupsKeepTheirFramesTogetherInOrder) {
  FrameStore store;
  const std::size_t stride = 6 * kCompactBins;
  // Frames go round-robin-ish into 4 groups of very different sizes, so that
  // no two consecutive ids share a group for long.
  std::vector<std::vector<std::int64_t>> members(4);
  for (std::int64_t i = 0; i < 5000; ++i) {
    const std::int64_t wanted = i % 7 == 0 ? 1 : i % 13 == 0 ? 2 : i % 2 == 0 ? 0 : 3;
    const std::int64_t group = std::min(wanted, store.groups());  // groups appear in order
    ASSERT_EQ(store.add(compact_numbered(i), group), i);
    members[static_cast<std::size_t>(group)].push_back(i);
  }
  ASSERT_EQ(store.groups(), 4);
  for (std::int64_t f = 0; f < store.size(); ++f) ASSERT_EQ(id_of(store.view(f)), f);
  for (std::size_t g = 0; g < members.size(); ++g) {
    const auto& m = members[g];
    ASSERT_GT(m.size(), 100u);
    // Consecutive members are adjacent in memory except where the group
    // starts a new chunk; chunks grow by half the group each time, so a group
    // of n frames has O(log n) of them.
    int breaks = 0;
    for (std::size_t i = 1; i < m.size(); ++i) {
      if (store.view(m[i]).compact != store.view(m[i - 1]).compact + stride) ++breaks;
    }
    EXPECT_LE(breaks, 20) << "group " << g << " of " << m.size() << " frames";
  }
}

TEST(FrameStore, GroupedFramesKeepTheirContentAndCopiesTheirPlacement) {
  FrameStore store;
  std::vector<std::int64_t> group_of;
  for (std::int64_t i = 0; i < 3000; ++i) {
    const std::int64_t group = std::min<std::int64_t>(store.groups(), (i * 7919) % 5);
    store.add(compact_numbered(i), group);
    group_of.push_back(group);
  }
  for (std::int64_t i = 0; i < store.size(); ++i) ASSERT_EQ(id_of(store.view(i)), i);
  FrameStore copy = store;
  for (std::int64_t i = 0; i < store.size(); ++i) {
    ASSERT_EQ(id_of(copy.view(i)), i);
    ASSERT_NE(copy.view(i).compact, store.view(i).compact);
  }
  // The copy continues each group where the original was: frame 3000 goes to
  // group 4 and lands right after that group's last frame in both.
  std::int64_t last = -1;
  for (std::int64_t i = 0; i < 3000; ++i)
    last = group_of[static_cast<std::size_t>(i)] == 4 ? i : last;
  ASSERT_GE(last, 0);
  store.add(compact_numbered(3000), 4);
  copy.add(compact_numbered(3000), 4);
  const std::ptrdiff_t in_store = store.view(3000).compact - store.view(last).compact;
  const std::ptrdiff_t in_copy = copy.view(3000).compact - copy.view(last).compact;
  EXPECT_EQ(in_store, in_copy);
  EXPECT_EQ(id_of(copy.view(3000)), 3000);
}

TEST(FrameStore, GroupOutOfRangeIsRejectedAndLeavesTheStoreUnchanged) {
  FrameStore store;
  EXPECT_THROW(store.add(compact_numbered(0), 1), InvalidArgument);  // no group 0 yet
  EXPECT_THROW(store.add(compact_numbered(0), -1), InvalidArgument);
  EXPECT_TRUE(store.empty());
  EXPECT_EQ(store.add(compact_numbered(0), 0), 0);
  EXPECT_EQ(store.add(compact_numbered(1), 1), 1);
  try {
    store.add(compact_numbered(2), 3);
    FAIL() << "group 3 skips group 2";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("group 3"), std::string::npos) << e.what();
  }
  EXPECT_EQ(store.size(), 2);
  EXPECT_EQ(store.groups(), 2);
  EXPECT_EQ(store.add(compact_numbered(2), 2), 2);
  EXPECT_EQ(id_of(store.view(2)), 2);
}

TEST(FrameStore, AllocatedBytesStayWithinHalfAgainTheData) {
  for (const int groups : {1, 3, 50}) {
    FrameStore store;
    for (std::int64_t i = 0; i < 4000; ++i) {
      store.add(numbered(5, 16, i), std::min<std::int64_t>(store.groups(), i % groups));
    }
    const double data = static_cast<double>(store.size()) * store.bytes_per_frame();
    const double allocated = static_cast<double>(store.allocated_bytes());
    EXPECT_GE(allocated, data) << groups << " groups";
    // Empty slots are at most half the filled ones per group; an arena
    // (16 MiB) loses at most a full-size chunk (4 MiB) at its end, and the
    // last one is partly unused; the tables are small.
    EXPECT_LE(allocated, 1.5 * data * 4 / 3 + (16 << 20) + 0.01 * data) << groups << " groups";
  }
}

}  // namespace
}  // namespace lsgd
