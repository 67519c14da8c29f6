// Storage of every stored frame's descriptor in fixed-stride slots, in chunks
// of about 4 MiB of consecutive frames: memory grows linearly with the number
// of frames and never needs a copy of what is stored (peak memory = the store
// plus at most one chunk), views stay valid while frames are added, and a scan
// over frames walks memory in order. Frame ids are dense: 0, 1, 2, ...
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
  FrameStore(const FrameStore& other);  // deep copy
  FrameStore& operator=(const FrameStore& other);
  FrameStore(FrameStore&&) noexcept = default;
  FrameStore& operator=(FrameStore&&) noexcept = default;

  // The grid, the storage (exact or compact) and, for compact storage, the
  // cell size are fixed by the first frame added; later frames must match
  // (throws InvalidArgument otherwise, leaving the store unchanged). Strong
  // guarantee: if allocation fails the store is unchanged too.
  std::int64_t add(const Descriptor& descriptor);

  std::int64_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const GridSize& grid() const { return grid_; }
  HistogramStorage storage() const { return storage_; }
  DescriptorView view(std::int64_t frame) const;

  // Bytes of descriptor data held per frame.
  std::size_t bytes_per_frame() const;
  void reserve(std::int64_t frames);
  // Frames per chunk (0 before the first frame).
  std::int64_t chunk_frames() const { return chunk_frames_; }

 private:
  static constexpr std::size_t kChunkBytes = std::size_t{4} << 20;

  // Chunks are allocated aligned to 2 MiB and, on Linux, marked for
  // transparent huge pages: a search reads stored frames in scattered 10-40
  // KB slots, and with 4 KiB pages most of them cost TLB misses.
  struct FreeChunk {
    void operator()(void* p) const;
  };
  template <typename T>
  using Chunk = std::unique_ptr<T[], FreeChunk>;
  template <typename T>
  static Chunk<T> allocate_chunk(std::size_t elements);
  template <typename T>
  static void copy_chunks(const std::vector<Chunk<T>>& from, std::size_t elements,
                          std::vector<Chunk<T>>& to);
  template <typename T>
  void add_slot(const std::vector<T>& data, std::vector<Chunk<T>>& chunks,
                const std::vector<Count>& pixels);

  GridSize grid_;
  HistogramStorage storage_ = HistogramStorage::kExact;
  double cell_pixels_ = 0;  // compact storage: mean pixels per cell
  std::int64_t size_ = 0;
  std::int64_t chunk_frames_ = 0;
  // Exact storage: chunk_frames_ * cells * kBins bins per chunk, and cells
  // pixel counts per frame.
  std::vector<Chunk<Bin>> chunks_;
  std::vector<Count> pixels_;
  // Compact storage: chunk_frames_ * cells * kCompactBins bins per chunk.
  std::vector<Chunk<CompactBin>> compact_chunks_;
};

}  // namespace lsgd
