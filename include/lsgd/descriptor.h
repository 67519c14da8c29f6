// LSGD descriptor, paper Sec. III-C: one 256-bin intensity histogram per
// superpixel-grid cell, stored as one contiguous block of cells * 256 counts.
// What a cell's histogram counts is the registered descriptor's
// (DescriptorType below: "intensity", the paper's, by default); the storage,
// its codecs (exact, compact), the similarity and persistence are shared by
// every one of them.
// Bins are 16-bit: exact for every bin below 65535 pixels (a cell would need
// more than 65535 pixels of one intensity, i.e. cells larger than 256 x 256
// pixels, to saturate); a fuller bin is stored as 65535. Half the memory and
// memory traffic of the 32-bit counts of the reference implementation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lsgd/image.h"
#include "lsgd/options.h"
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

// The built-in descriptors (DescriptorOptions::type).
inline constexpr const char* kIntensityDescriptor = "intensity";  // the paper's
inline constexpr const char* kGradientDescriptor = "gradient";    // lsgd/descriptors/gradient.h

struct DescriptorOptions {
  // A registered descriptor (descriptor_types()): what each cell's 256 bins
  // count. "intensity": the paper's gray levels; "gradient": gradient
  // orientations (lighting change).
  std::string type = kIntensityDescriptor;
  HistogramStorage storage = HistogramStorage::kExact;
  // The options registered descriptors declare (DescriptorType::options),
  // keys "<type>.<name>" (descriptor.<type>.<name> in DetectorOptions), as
  // SearchOptions::own: read with own_integer("name") and the like.
  OwnOptionValues own;
  std::int64_t own_integer(const std::string& name) const;
  double own_real(const std::string& name) const;
  std::string own_choice(const std::string& name) const;
  void check() const;
  // Built again after register_descriptor_type() (a new descriptor's options).
  static const OptionTable<DescriptorOptions>& fields();  // lsgd/options.h
};

// A registered descriptor: what each pixel is counted as in its cell's
// histogram. Everything else (the grid, the 256 bins of a cell, storage and
// its codecs, the similarity, databases, described frames) is the same for
// every descriptor, and a map is made of one: descriptor.type is stored with
// the map's options, so a database or a described frame of another
// descriptor is refused by name. docs/design.md, "Add a descriptor".
struct DescriptorType {
  const char* name;
  const char* summary;  // one line, for help texts
  // Writes `codes` (resized to work's size): for each pixel of `work` (the
  // frame, gray, at its working size: Segmenter::working()) the bin, 0-255,
  // it is counted in. Reads its own options from `options`.
  void (*make)(const GrayImage& work, const DescriptorOptions& options, GrayImage& codes);
  // Its own options (lsgd/options.h): descriptor.<name>.<option>, with this
  // descriptor only.
  std::vector<OwnOption> options = {};
};

// Every registered descriptor, in registration order: the built-in ones first.
std::vector<DescriptorType> descriptor_types();
// Registers another descriptor, usable by name in DescriptorOptions::type
// from then on; call it before the detectors that use it are made.
// InvalidArgument for a missing name, summary or make function, a name
// already registered, or an own option that is not complete (as
// register_search_mode(); a descriptor with options may not be named as a
// descriptor option: "storage"). Thread-safe.
void register_descriptor_type(const DescriptorType& type);
// "intensity, gradient": the names, for messages and help texts.
std::string descriptor_type_names();
// The registered descriptor named `name` (InvalidArgument naming it and the
// registered ones when there is none).
DescriptorType find_descriptor_type(const std::string& name);

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
  // What the bins count (Descriptor::type, kept by Descriptor::view()):
  // nullptr or "" when not known (a stored frame's view, arrays). similarity(),
  // similarities() and match_top_k() refuse views that both know it and differ.
  const char* type = nullptr;

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
  // What its bins count: the descriptor type and its own options, as
  // segment_and_describe() with the descriptor options writes it
  // ("intensity", "gradient (threshold 1.5, orientations 32)"); "" when not
  // known (built from arrays or bytes). Descriptors that count different
  // things are never compared (similarity(), match_top_k() and their Python
  // forms refuse them: view() carries it).
  std::string type;

  DescriptorView view() const;
  // Bytes of histogram data this storage needs for `cells` cells.
  static std::size_t bytes_per_frame(HistogramStorage storage, int cells);
  // Throws InvalidArgument when the vectors' sizes do not match the grid and
  // storage (`what` names the descriptor in the message).
  void check_consistent(const char* what) const;
  // Throws InvalidArgument (`what` naming it) unless every cell's bins add up
  // as describe() and compact() make them: exact, to the cell's pixel count
  // (less only when a bin saturated at 65535); compact, to 0 (an empty cell)
  // or kCompactMass within the rounding of its 128 bins (less only when a bin
  // saturated at 255). For descriptors that come from outside (a described
  // frame's bytes, arrays); check_consistent() first.
  void check_counts(const char* what) const;
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
// The same with the descriptor `options.type` names: intensity as above; any
// other counts its codes (DescriptorType::make) of the working image after
// the segmentation (describe() of the codes). The exact descriptor either way.
void segment_and_describe(Segmenter& segmenter, const GrayImage& image, Segmentation& segmentation,
                          Descriptor& out, DescribeScratch& scratch, const DescriptorOptions& options);
// What a descriptor of `options` counts (Descriptor::type).
std::string descriptor_identity(const DescriptorOptions& options);

// Encodes an exact descriptor in compact storage (see HistogramStorage). An
// empty cell encodes as all zeros. Throws InvalidArgument when `exact` is not
// a consistent exact descriptor. Reuses out's storage.
void compact(const Descriptor& exact, Descriptor& out);

}  // namespace lsgd
