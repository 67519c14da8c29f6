// Storage of every stored frame's descriptor in fixed-stride slots, in chunks
// of at most about 4 MiB: memory grows linearly with the number of frames and
// never needs a copy of what is stored, views stay valid while frames are
// added, and a scan over frames walks memory in order. Frame ids are dense:
// 0, 1, 2, ...
//
// Frames are placed by group: the frames of one group sit together in
// memory, in the order they were added, and never share a chunk with another
// group. The detector uses the frame's dynamic node as its group, so that
// scoring a node's members (Algorithm 1) reads one run of memory instead of
// the node's frames scattered among all the others; with one group (the
// default, exhaustive search) frames sit in id order. A group is only a
// placement: it never changes what view() returns.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "lsgd/descriptor.h"

namespace lsgd {

class FrameStore {
 public:
  FrameStore() = default;
  FrameStore(const FrameStore& other);  // deep copy, same placement
  FrameStore& operator=(const FrameStore& other);
  FrameStore(FrameStore&&) noexcept = default;
  FrameStore& operator=(FrameStore&&) noexcept = default;

  // Stores the frame in `group` and returns its id. The grid, the storage
  // (exact or compact) and, for compact storage, the cell size are fixed by
  // the first frame added; later frames must match. `group` must be an
  // existing group or the next new one: 0 <= group <= groups(). Throws
  // InvalidArgument otherwise, leaving the store unchanged. Strong guarantee:
  // if allocation fails the store is unchanged too.
  std::int64_t add(const Descriptor& descriptor, std::int64_t group = 0);

  std::int64_t size() const { return static_cast<std::int64_t>(slots_.size()); }
  bool empty() const { return slots_.empty(); }
  const GridSize& grid() const { return grid_; }
  HistogramStorage storage() const { return storage_; }
  DescriptorView view(std::int64_t frame) const;
  // Number of groups: one more than the highest group used, 0 when empty.
  std::int64_t groups() const { return static_cast<std::int64_t>(groups_.size()); }

  // Bytes of descriptor data held per frame.
  std::size_t bytes_per_frame() const;
  // Bytes allocated for descriptors (the arenas below), pixel counts and the
  // tables: at least size() * bytes_per_frame(). A group's next chunk holds
  // half as many frames as the group already has (1 at first, at most
  // max_chunk_frames()), so each group has at most half as many empty slots as
  // filled ones; chunks are cut from 16 MiB arenas, whose last few MiB stay
  // unused when the next chunk does not fit. Memory is only committed as
  // slots are written: unused arena pages cost address space, not RAM.
  std::size_t allocated_bytes() const;
  // Room for `frames` frames in the frame table (the chunks grow by group).
  void reserve(std::int64_t frames);
  // Frames in a full-size chunk (0 before the first frame).
  std::int64_t max_chunk_frames() const { return max_chunk_frames_; }

 private:
  // Throws unless `descriptor` may join the stored frames in `group` (add()).
  void check_joins(const Descriptor& descriptor, std::int64_t group) const;

  static constexpr std::size_t kChunkBytes = std::size_t{4} << 20;
  static constexpr std::size_t kArenaBytes = std::size_t{16} << 20;

  // Arenas are allocated aligned to 2 MiB and, on Linux, marked for
  // transparent huge pages: a search reads stored frames in 10-40 KB slots,
  // and with 4 KiB pages most of them cost TLB misses. Chunks are cut from
  // them in order and never freed on their own, so a group's small first
  // chunks sit on huge pages too, next to each other.
  struct FreeArena {
    void operator()(std::byte* p) const;
  };
  struct Arena {
    std::unique_ptr<std::byte[], FreeArena> data;
    std::size_t size = 0;  // bytes
    std::size_t used = 0;  // bytes handed out to chunks
  };
  static Arena allocate_arena(std::size_t bytes);
  struct Chunk {
    std::byte* data = nullptr;  // inside arenas_[arena] at `offset`
    std::uint32_t arena = 0;
    std::size_t offset = 0;
  };
  // Where a frame's histograms live: slot `slot` of chunk `chunk`.
  struct Slot {
    std::uint32_t chunk = 0;
    std::uint32_t slot = 0;
  };
  // A group fills its last chunk before it gets a new one.
  struct Group {
    std::int64_t frames = 0;
    std::uint32_t chunk = 0;  // its last chunk
    std::int64_t used = 0;    // slots of that chunk already filled
    std::int64_t capacity = 0;
  };

  std::size_t frame_bytes() const;  // histogram bytes per slot

  GridSize grid_;
  HistogramStorage storage_ = HistogramStorage::kExact;
  double cell_pixels_ = 0;  // compact storage: mean pixels per cell
  std::int64_t max_chunk_frames_ = 0;
  // Exact storage: cells * kBins 16-bit bins per slot; compact storage:
  // cells * kCompactBins 8-bit bins.
  std::vector<Arena> arenas_;
  std::vector<Chunk> chunks_;
  std::vector<Slot> slots_;    // by frame id
  std::vector<Group> groups_;  // by group id
  std::vector<Count> pixels_;  // exact storage: cells pixel counts per frame, by frame id
};

}  // namespace lsgd
