#include "lsgd/descriptor.h"

#include <algorithm>
#include <optional>
#include <cmath>
#include <cstring>
#include <limits>

#include "internal/check.h"
#include "internal/kernels.h"
#include "internal/option_tables.h"
#include "internal/registry.h"
#include "lsgd/descriptors/gradient.h"
#include "lsgd/limits.h"

namespace lsgd {
namespace {

constexpr Count kBinMax = std::numeric_limits<Bin>::max();

// Recounts cell k in 32 bits and stores it saturated (only for cells of more
// than 65535 pixels, whose 16-bit bins may have wrapped).
void recount_saturated(const GrayImage& image, const Segmentation& segmentation, int k, Bin* h) {
  std::vector<Count> wide(kBins, 0);
  const std::size_t n = image.pixels.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (segmentation.labels[i] == k) ++wide[image.pixels[i]];
  }
  for (int b = 0; b < kBins; ++b) h[b] = static_cast<Bin>(std::min(wide[b], kBinMax));
}

}  // namespace

const char* to_string(HistogramStorage storage) {
  switch (storage) {
    case HistogramStorage::kExact:
      return "exact";
    case HistogramStorage::kCompact:
      return "compact";
  }
  return "unknown";
}

HistogramStorage parse_histogram_storage(const char* name) {
  for (auto s : {HistogramStorage::kExact, HistogramStorage::kCompact}) {
    if (std::strcmp(name, to_string(s)) == 0) return s;
  }
  internal::throw_invalid("descriptor storage '", internal::shown_value(name),
                          "' is unknown: expected exact or compact");
}

namespace {

// The intensity descriptor's codes: the gray levels themselves. The detector
// never calls it (segment_and_describe() counts intensity during the
// segmentation); it makes the entry complete for code that counts any
// descriptor's codes itself.
void intensity_codes(const GrayImage& work, const DescriptorOptions&, GrayImage& codes) { codes = work; }

// The registered descriptors: a built-in one is one line here (and its file
// pair in src/descriptors/, include/lsgd/descriptors/); others come from
// register_descriptor_type().
internal::Registry<DescriptorType>& registry() {
  static internal::Registry<DescriptorType> types(
      "descriptor",
      {
          {kIntensityDescriptor, "the paper's: a 256-bin gray-level histogram per cell", intensity_codes},
          {kGradientDescriptor, "gradient orientations per cell (lighting change; not the paper's)",
           gradient_codes, gradient_options()},
      });
  return types;
}

OptionTable<DescriptorOptions> descriptor_table() {
  using S = DescriptorOptions;
  OptionTable<S> t = {
      internal::registry_choice<S, DescriptorType>(
          "type", "what each cell's histogram counts: a registered descriptor (descriptor.h)",
          descriptor_types, find_descriptor_type, &S::type),
      enum_option("storage", &S::storage, {HistogramStorage::kExact, HistogramStorage::kCompact},
                  parse_histogram_storage,
                  "exact: 16-bit counts in 256 bins; compact: 8-bit shares in 128 bins (10 KB "
                  "per KITTI frame, faster search)"),
  };
  for (const DescriptorType& d : descriptor_types()) {
    const std::string name = d.name;
    add_own_options<S>(t, name, d.options, &S::own, [name](const S& s) { return s.type == name; },
                       "with the " + name + " descriptor");
  }
  return t;
}

}  // namespace

std::vector<DescriptorType> descriptor_types() { return registry().entries(); }

void register_descriptor_type(const DescriptorType& type) {
  registry().add(internal::with_checked_options<DescriptorOptions>(type, "register_descriptor_type",
                                                                   "descriptor", "descriptor"),
                 "register_descriptor_type");
  internal::count_registration();
}

std::string descriptor_type_names() { return registry().names(); }

DescriptorType find_descriptor_type(const std::string& name) { return registry().find(name); }

const OptionTable<DescriptorOptions>& DescriptorOptions::fields() {
  return internal::current_table(descriptor_table);
}

std::int64_t DescriptorOptions::own_integer(const std::string& name) const {
  return lsgd::own_integer(own, find_descriptor_type(type).options, type, name);
}

double DescriptorOptions::own_real(const std::string& name) const {
  return lsgd::own_real(own, find_descriptor_type(type).options, type, name);
}

std::string DescriptorOptions::own_choice(const std::string& name) const {
  return lsgd::own_choice(own, find_descriptor_type(type).options, type, name);
}

void DescriptorOptions::check() const {
  try {
    find_descriptor_type(type);
  } catch (const InvalidArgument& e) {
    internal::throw_invalid("descriptor.type: ", e.what());
  }
  if (storage != HistogramStorage::kExact && storage != HistogramStorage::kCompact) {
    internal::throw_invalid("descriptor.storage = ", static_cast<int>(storage), " is unknown");
  }
  check_options(fields(), *this, "descriptor");
}

DescriptorView Descriptor::view() const {
  DescriptorView v;
  v.cells = grid.cells();
  v.type = type.empty() ? nullptr : type.c_str();
  if (storage == HistogramStorage::kCompact) {
    v.compact = compact.data();
    v.cell_pixels = cell_pixels;
  } else {
    v.hist = hist.data();
    v.pixels = pixels.data();
  }
  return v;
}

std::size_t Descriptor::bytes_per_frame(HistogramStorage storage, int cells) {
  const auto n = static_cast<std::size_t>(cells);
  return storage == HistogramStorage::kCompact ? n * kCompactBins * sizeof(CompactBin)
                                               : n * (kBins * sizeof(Bin) + sizeof(Count));
}

void Descriptor::check_consistent(const char* what) const {
  const int cells = grid.cells();
  const auto n = static_cast<std::size_t>(cells);
  const bool ok =
      cells > 0 && (storage == HistogramStorage::kCompact
                        ? compact.size() == n * kCompactBins && hist.empty() && pixels.empty() &&
                              cell_pixels > 0 && std::isfinite(cell_pixels)
                        : hist.size() == n * kBins && pixels.size() == n && compact.empty());
  if (!ok) {
    internal::throw_invalid(what, ": ", to_string(storage), " descriptor of a ", grid.rows, "x",
                            grid.cols, " grid has ", hist.size(), " exact bins, ", pixels.size(),
                            " pixel counts and ", compact.size(), " compact bins (cell_pixels ",
                            cell_pixels, ")");
  }
}

void Descriptor::check_counts(const char* what) const {
  const int cells = grid.cells();
  for (int k = 0; k < cells; ++k) {
    std::uint64_t sum = 0;
    bool saturated = false;
    if (storage == HistogramStorage::kCompact) {
      const CompactBin* h = &compact[static_cast<std::size_t>(k) * kCompactBins];
      for (int b = 0; b < kCompactBins; ++b) {
        sum += h[b];
        saturated = saturated || h[b] == std::numeric_limits<CompactBin>::max();
      }
      // Each bin rounds to the nearest: the cell's mass within half a unit a bin.
      const std::uint64_t lo = kCompactMass - kCompactBins / 2, hi = kCompactMass + kCompactBins / 2;
      // Cells of more than 65535 pixels may have saturated in exact storage
      // before they were encoded: their mass may fall short.
      const bool big = cell_pixels > static_cast<double>(kBinMax);
      if (sum == 0 || (sum <= hi && (sum >= lo || saturated || big))) continue;
      internal::throw_invalid(what, ": cell ", k, "'s compact bins add up to ", sum, ", not ",
                              kCompactMass, " (+-", kCompactBins / 2, "): not a histogram compact() made");
    }
    const Bin* h = &hist[static_cast<std::size_t>(k) * kBins];
    for (int b = 0; b < kBins; ++b) {
      sum += h[b];
      saturated = saturated || h[b] == kBinMax;
    }
    const std::uint64_t n = pixels[static_cast<std::size_t>(k)];
    if (n > static_cast<std::uint64_t>(kMaxImagePixels)) {
      internal::throw_invalid(what, ": cell ", k, " has ", n, " pixels, more than a frame may (",
                              kMaxImagePixels, ")");
    }
    if (sum == n || (saturated && sum < n)) continue;
    internal::throw_invalid(what, ": cell ", k, "'s bins add up to ", sum, " pixels but its pixel count is ",
                            n, ": not a histogram of the cell");
  }
}

void describe(const GrayImage& image, const Segmentation& segmentation, Descriptor& out) {
  if (image.width != segmentation.width || image.height != segmentation.height ||
      segmentation.labels.size() != image.pixels.size()) {
    internal::throw_invalid("describe: image ", image.width, "x", image.height,
                            " does not match its segmentation ", segmentation.width, "x",
                            segmentation.height);
  }
  const int cells = segmentation.grid.cells();
  out.grid = segmentation.grid;
  out.storage = HistogramStorage::kExact;
  out.compact.clear();
  out.cell_pixels = 0;
  out.hist.assign(static_cast<std::size_t>(cells) * kBins, 0);
  out.pixels.assign(static_cast<std::size_t>(cells), 0);
  // Labels come in runs along a row: count each run into its cell's histogram.
  for (int y = 0; y < image.height; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * image.width;
    const std::uint8_t* p = image.pixels.data() + row;
    const std::int32_t* labels = segmentation.labels.data() + row;
    int x = 0;
    while (x < image.width) {
      const std::int32_t label = labels[x];
      const auto k = static_cast<std::uint32_t>(label);  // -1 wraps: one compare
      if (k >= static_cast<std::uint32_t>(cells)) {
        internal::throw_invalid("describe: pixel ", row + x, " has label ", label, " outside the ",
                                cells, " cells of its segmentation");
      }
      Bin* h = &out.hist[static_cast<std::size_t>(k) * kBins];
      const int start = x;
      for (; x < image.width && labels[x] == label; ++x) ++h[p[x]];
      out.pixels[k] += static_cast<Count>(x - start);
    }
  }
  for (int k = 0; k < cells; ++k) {
    if (out.pixels[k] > kBinMax) {
      recount_saturated(image, segmentation, k, &out.hist[static_cast<std::size_t>(k) * kBins]);
    }
  }
}

struct DescribeScratch::Buffers {
  std::vector<Bin> second;               // second histogram set (HistogramRows)
  std::vector<internal::LabelRun> runs;  // one row's runs of equal labels
  GrayImage codes;                       // a descriptor's codes (DescriptorType::make)
  // The registered type last described with (a name, once registered, is
  // never replaced: looked up once, not once a frame).
  std::optional<DescriptorType> type;
  std::string identity;  // descriptor_identity() of the options it was looked up with
};

DescribeScratch::DescribeScratch() : buffers_(std::make_unique<Buffers>()) {}
DescribeScratch::~DescribeScratch() = default;
DescribeScratch::DescribeScratch(DescribeScratch&&) noexcept = default;
DescribeScratch& DescribeScratch::operator=(DescribeScratch&&) noexcept = default;

namespace {

// Counts each final row of `segmentation` into the histograms of `out`, run
// by run. Every other pixel of a run goes to a second set of histograms,
// added in at the end: neighbours often share a bin (flat areas), and one
// set would make each increment wait for the previous one's store.
class HistogramRows final : public RowSink {
 public:
  HistogramRows(const Segmentation& segmentation, Descriptor& out, DescribeScratch& scratch)
      : segmentation_(segmentation),
        out_(out),
        second_(scratch.buffers().second),
        runs_(scratch.buffers().runs) {}

  void row(int y, const std::uint8_t* p, const std::int32_t* labels, int width) override {
    if (y == 0) {  // the grid is known once the segmentation runs
      const auto cells = static_cast<std::size_t>(segmentation_.grid.cells());
      out_.grid = segmentation_.grid;
      out_.hist.assign(cells * kBins, 0);
      out_.pixels.assign(cells, 0);
      second_.assign(cells * kBins, 0);
      runs_.resize(static_cast<std::size_t>(width));
    }
    const int n = internal::label_runs(labels, width, runs_.data());
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(runs_[i].label);
      const int start = runs_[i].start;
      const int end = i + 1 < n ? runs_[i + 1].start : width;
      Bin* const h = &out_.hist[k * kBins];
      Bin* const h2 = &second_[k * kBins];
      int x = start;
      for (; x + 1 < end; x += 2) {
        ++h[p[x]];
        ++h2[p[x + 1]];
      }
      if (x < end) ++h[p[x]];
      out_.pixels[k] += static_cast<Count>(end - start);
    }
  }

  // Adds the second histograms in (16-bit, wrapping like the increments:
  // exact for cells of at most 65535 pixels; larger cells are recounted).
  void finish() {
    for (std::size_t i = 0; i < second_.size(); ++i) {
      out_.hist[i] = static_cast<Bin>(out_.hist[i] + second_[i]);
    }
  }

 private:
  const Segmentation& segmentation_;
  Descriptor& out_;
  std::vector<Bin>& second_;
  std::vector<internal::LabelRun>& runs_;
};

}  // namespace

void segment_and_describe(Segmenter& segmenter, const GrayImage& image, Segmentation& segmentation,
                          Descriptor& out) {
  DescribeScratch scratch;
  segment_and_describe(segmenter, image, segmentation, out, scratch);
}

void segment_and_describe(Segmenter& segmenter, const GrayImage& image, Segmentation& segmentation,
                          Descriptor& out, DescribeScratch& scratch) {
  // At the working size (segmentation.working_side): the image itself by default.
  const GrayImage& work = segmenter.working(image);
  HistogramRows rows(segmentation, out, scratch);
  segmenter.segment(work, segmentation, rows);
  rows.finish();
  out.storage = HistogramStorage::kExact;
  out.compact.clear();
  out.cell_pixels = 0;
  for (int k = 0; k < out.grid.cells(); ++k) {
    if (out.pixels[k] > kBinMax) {
      recount_saturated(work, segmentation, k, &out.hist[static_cast<std::size_t>(k) * kBins]);
    }
  }
}

std::string descriptor_identity(const DescriptorOptions& options) {
  const DescriptorType type = find_descriptor_type(options.type);
  std::string out = options.type;
  const char* separator = " (";
  for (const OwnOption& o : type.options) {
    const std::string* value = options.own.find(options.type + "." + o.name);
    out += separator + o.name + " " + (value != nullptr ? *value : o.default_value);
    separator = ", ";
  }
  if (!type.options.empty()) out += ")";
  return out;
}

void segment_and_describe(Segmenter& segmenter, const GrayImage& image, Segmentation& segmentation,
                          Descriptor& out, DescribeScratch& scratch, const DescriptorOptions& options) {
  if (options.type == kIntensityDescriptor) {
    segment_and_describe(segmenter, image, segmentation, out, scratch);
    out.type = kIntensityDescriptor;
    return;
  }
  std::optional<DescriptorType>& type = scratch.buffers().type;
  if (!type || options.type != type->name) {
    type = find_descriptor_type(options.type);
    scratch.buffers().identity = descriptor_identity(options);
  }
  const GrayImage& work = segmenter.working(image);
  segmenter.segment(work, segmentation);
  GrayImage& codes = scratch.buffers().codes;
  type->make(work, options, codes);
  if (codes.width != work.width || codes.height != work.height ||
      codes.pixels.size() != work.pixels.size()) {
    internal::throw_invalid("descriptor ", options.type, ": its codes are ", codes.width, "x",
                            codes.height, " (", codes.pixels.size(), " values) for a ", work.width,
                            "x", work.height, " frame");
  }
  describe(codes, segmentation, out);
  out.type = scratch.buffers().identity;
}

Descriptor describe(const GrayImage& image, const Segmentation& segmentation) {
  Descriptor out;
  describe(image, segmentation, out);
  return out;
}

void compact(const Descriptor& exact, Descriptor& out) {
  if (exact.storage != HistogramStorage::kExact) {
    internal::throw_invalid("compact: the descriptor is already compact");
  }
  exact.check_consistent("compact");
  const int cells = exact.grid.cells();
  std::uint64_t total = 0;
  for (const Count n : exact.pixels) total += n;
  out.grid = exact.grid;
  out.type = exact.type;
  out.storage = HistogramStorage::kCompact;
  out.hist.clear();
  out.pixels.clear();
  out.cell_pixels = static_cast<double>(total) / cells;
  out.compact.resize(static_cast<std::size_t>(cells) * kCompactBins);
  for (int k = 0; k < cells; ++k) {
    const Bin* h = &exact.hist[static_cast<std::size_t>(k) * kBins];
    CompactBin* q = &out.compact[static_cast<std::size_t>(k) * kCompactBins];
    const std::uint64_t n = exact.pixels[k];
    for (int b = 0; b < kCompactBins; ++b) {
      const std::uint64_t pair = std::uint64_t{h[2 * b]} + h[2 * b + 1];
      // round(pair * mass / n), half up, in integers; 0 for an empty cell.
      const std::uint64_t v = n == 0 ? 0 : (2 * pair * kCompactMass + n) / (2 * n);
      q[b] = static_cast<CompactBin>(std::min<std::uint64_t>(v, 255));
    }
  }
}

}  // namespace lsgd
