// Tests of the chunked descriptor store (frame_store.h).
#include "lsgd/frame_store.h"

#include <algorithm>
#include <vector>

#include <gtest/gtest.h>

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
  const std::int64_t per_chunk = store.chunk_frames();
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
  EXPECT_EQ(store.chunk_frames(), static_cast<std::int64_t>((std::size_t{4} << 20) / (kBins * 2)));
  store.reserve(20000);
  for (std::int64_t i = 1; i < 9000; ++i) store.add(numbered(1, 1, i));
  EXPECT_EQ(store.view(8999).pixels[0], 8999u);
}

}  // namespace
}  // namespace lsgd
