// LSGD descriptor, paper Sec. III-C: one 256-bin intensity histogram per
// superpixel-grid cell, stored as one contiguous block of cells * 256 counts.
// Bins are 16-bit: exact for every bin below 65535 pixels (a cell would need
// more than 65535 pixels of one intensity, i.e. cells larger than 256 x 256
// pixels, to saturate); a fuller bin is stored as 65535. Half the memory and
// memory traffic of the 32-bit counts of the reference implementation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "lsgd/image.h"
#include "lsgd/segmentation.h"

namespace lsgd {

constexpr int kBins = 256;    // one bin per 8-bit intensity
using Bin = std::uint16_t;    // one histogram bin (saturating at 65535)
using Count = std::uint32_t;  // pixels in a cell

// How stored histograms are held (option descriptor.storage).
enum class HistogramStorage {
  // The paper's histogram: kBins 16-bit counts per cell plus the cell's pixel
  // count (41,280 bytes per 1241x376 frame at S_p = 40). Exact.
  kExact,
  // Beyond the paper: kCompactBins bins of two intensities each, as 8-bit
  // values normalised to a cell mass of kCompactMass:
  //   q = min(255, round((h[2b] + h[2b + 1]) * kCompactMass / pixels)).
  // A quarter of the bytes (10,240 per 1241x376 frame) and of the memory
  // traffic of a search; scores approximate the exact ones (docs/performance.md
  // has the measured accuracy). A bin saturates when it holds more than a
  // quarter of its cell's pixels.
  kCompact,
};
constexpr int kCompactBins = kBins / 2;
constexpr int kCompactMass = 1024;
using CompactBin = std::uint8_t;

const char* to_string(HistogramStorage storage);
// Parses "exact" or "compact"; throws InvalidArgument otherwise.
HistogramStorage parse_histogram_storage(const char* name);

struct DescriptorOptions {
  HistogramStorage storage = HistogramStorage::kExact;
  void check() const;
  static const OptionTable<DescriptorOptions>& fields();  // lsgd/options.h
};

// Non-owning view of one frame's descriptor (inside a Descriptor or a
// FrameStore), in either storage: exact when `hist` is set, compact when
// `compact` is set.
struct DescriptorView {
  const Bin* hist = nullptr;  // exact: cells * kBins counts, cell-major
  const Count* pixels =
      nullptr;  // exact: cells pixel counts (sum of each cell's histogram before saturation)
  int cells = 0;
  const CompactBin* compact = nullptr;  // compact: cells * kCompactBins, cell-major
  // compact: mean pixels per cell (image pixels / cells), which turns compact
  // L1 distances back into pixel counts.
  double cell_pixels = 0;

  HistogramStorage storage() const {
    return compact != nullptr ? HistogramStorage::kCompact : HistogramStorage::kExact;
  }
};

struct Descriptor {
  GridSize grid;
  HistogramStorage storage = HistogramStorage::kExact;
  std::vector<Bin> hist;            // exact: cells * kBins; empty when compact
  std::vector<Count> pixels;        // exact: cells; empty when compact
  std::vector<CompactBin> compact;  // compact: cells * kCompactBins; empty when exact
  double cell_pixels = 0;           // compact: mean pixels per cell

  DescriptorView view() const;
  // Bytes of histogram data this storage needs for `cells` cells.
  static std::size_t bytes_per_frame(HistogramStorage storage, int cells);
  // Throws InvalidArgument when the vectors' sizes do not match the grid and
  // storage (`what` names the descriptor in the message).
  void check_consistent(const char* what) const;
};

// Builds the descriptor of `image` from its segmentation (same size; throws
// InvalidArgument otherwise). Reuses out's storage.
void describe(const GrayImage& image, const Segmentation& segmentation, Descriptor& out);
Descriptor describe(const GrayImage& image, const Segmentation& segmentation);

// segmenter.segment(image, segmentation) then describe(image, segmentation,
// out), of the image at its working size (Segmenter::working(); the image
// itself unless segmentation.working_side scales it down), with
// bit-identical results, in one pass: the histograms are counted
// row by row during the segmentation's last iteration, while each row is in
// cache, instead of in a second pass over the label image (what the detector
// runs; describe() stays the reference). Throws what segment() throws.
// Reuses the storage of segmentation, out and scratch: with one scratch per
// stream of frames nothing is allocated once warm (the overload without one
// allocates ~45 KB per call at 1241x376).
class DescribeScratch {
 public:
  DescribeScratch();
  ~DescribeScratch();
  DescribeScratch(DescribeScratch&&) noexcept;
  DescribeScratch& operator=(DescribeScratch&&) noexcept;
  struct Buffers;  // descriptor.cc: a second histogram set, one row's label runs
  Buffers& buffers() { return *buffers_; }

 private:
  std::unique_ptr<Buffers> buffers_;
};
void segment_and_describe(Segmenter& segmenter, const GrayImage& image, Segmentation& segmentation,
                          Descriptor& out, DescribeScratch& scratch);
void segment_and_describe(Segmenter& segmenter, const GrayImage& image, Segmentation& segmentation,
                          Descriptor& out);

// Encodes an exact descriptor in compact storage (see HistogramStorage). An
// empty cell encodes as all zeros. Throws InvalidArgument when `exact` is not
// a consistent exact descriptor. Reuses out's storage.
void compact(const Descriptor& exact, Descriptor& out);

}  // namespace lsgd
