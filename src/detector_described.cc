// Frames described apart from the map (FrameDescription, detector.h): a
// robot describes its frames (describe_frame), the map's process takes them
// (process / query of a description) with the Results of the images.
#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <opencv2/core.hpp>

#include "detector_internal.h"
#include "internal/check.h"
#include "internal/clock.h"
#include "internal/hash.h"
#include "lsgd/detector.h"

namespace lsgd {
using internal::ms_since;
using internal::now_ns;

namespace {

constexpr std::uint8_t kMagic[8] = {'L', 'S', 'G', 'D', 'F', 'R', 'M', 'D'};
// 2: the place signature (1 read as without); 3: a CRC-32 of every byte
// before it at the end (1 and 2 are read without one).
constexpr std::int64_t kVersion = 3;
constexpr std::size_t kChecksumBytes = 4;

std::uint32_t crc_of(const std::uint8_t* data, std::size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  while (size > 0) {  // zlib takes 32-bit lengths
    const auto chunk = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
    crc = crc32(crc, data, chunk);
    data += chunk;
    size -= chunk;
  }
  return static_cast<std::uint32_t>(crc);
}

bool describing_option(const std::string& name) {
  for (const char* prefix : {"segmentation.", "descriptor.", "verification."}) {
    if (name.compare(0, std::strlen(prefix), prefix) == 0) return true;
  }
  return false;
}

}  // namespace

std::uint64_t describing_options_key(const DetectorOptions& options) {
  std::uint64_t h = internal::kFnvOffset;  // FNV-1a over "name=value\n"
  for (const auto& field : DetectorOptions::fields()) {
    if (!describing_option(field.name)) continue;
    h = internal::fnv1a(field.name + "=" + field.text(options) + "\n", h);
  }
  return h;
}

std::vector<std::uint8_t> encode_frame_description(const FrameDescription& d) {
  d.descriptor.check_consistent("encode_frame_description: the descriptor");
  if (d.records.size() != d.stages.size()) {
    internal::throw_invalid("encode_frame_description: ", d.records.size(), " records for ",
                            d.stages.size(), " stages");
  }
  StateWriter out;
  out.put_bytes(kMagic, sizeof kMagic);
  out.put_i64(kVersion);
  out.put_i64(d.width);
  out.put_i64(d.height);
  out.put_i64(static_cast<std::int64_t>(d.options_key));
  out.put_f64(d.convert_ms);
  out.put_f64(d.segment_ms);
  out.put_f64(d.describe_ms);
  const Descriptor& x = d.descriptor;
  out.put_i64(x.grid.rows);
  out.put_i64(x.grid.cols);
  out.put_i64(x.storage == HistogramStorage::kCompact ? 1 : 0);
  out.put_f64(x.cell_pixels);
  if (x.storage == HistogramStorage::kCompact) {
    out.put_bytes(x.compact.data(), x.compact.size());
  } else {
    std::vector<std::uint8_t> le(2 * x.hist.size());
    for (std::size_t k = 0; k < x.hist.size(); ++k) {
      le[2 * k] = static_cast<std::uint8_t>(x.hist[k] & 0xff);
      le[2 * k + 1] = static_cast<std::uint8_t>(x.hist[k] >> 8);
    }
    out.put_bytes(le.data(), le.size());
    std::vector<std::uint8_t> pixels(4 * x.pixels.size());
    for (std::size_t k = 0; k < x.pixels.size(); ++k) {
      for (int b = 0; b < 4; ++b) pixels[4 * k + b] = static_cast<std::uint8_t>(x.pixels[k] >> (8 * b));
    }
    out.put_bytes(pixels.data(), pixels.size());
  }
  out.put_i64(static_cast<std::int64_t>(d.stages.size()));
  for (std::size_t k = 0; k < d.stages.size(); ++k) {
    out.put_i64(static_cast<std::int64_t>(d.stages[k].size()));
    out.put_bytes(reinterpret_cast<const std::uint8_t*>(d.stages[k].data()), d.stages[k].size());
    out.put_i64(static_cast<std::int64_t>(d.records[k].size()));
    out.put_bytes(d.records[k].data(), d.records[k].size());
  }
  out.put_i64(static_cast<std::int64_t>(d.signature.size()));
  out.put_bytes(d.signature.data(), d.signature.size());
  std::vector<std::uint8_t> bytes = out.take();
  const std::uint32_t crc = crc_of(bytes.data(), bytes.size());
  for (std::size_t b = 0; b < kChecksumBytes; ++b) bytes.push_back(static_cast<std::uint8_t>(crc >> (8 * b)));
  return bytes;
}

namespace {

// A count read from the bytes, checked against what is left (each unit at
// least `unit` bytes), so that nothing allocated exceeds the input.
std::size_t count_of(StateReader& in, std::size_t unit, const char* what) {
  const std::int64_t n = in.get_i64();
  if (n < 0 || static_cast<std::uint64_t>(n) > in.remaining() / unit) {
    throw FormatError(internal::concat("frame description: ", what, " ", n, " does not fit in the ",
                                       in.remaining(), " bytes left"));
  }
  return static_cast<std::size_t>(n);
}

FrameDescription decode(StateReader& in) {
  FrameDescription d;
  if (std::memcmp(in.get_bytes(sizeof kMagic), kMagic, sizeof kMagic) != 0) {
    throw FormatError("frame description: the bytes do not start with its mark (LSGDFRMD)");
  }
  const std::int64_t version = in.get_i64();
  if (version < 1 || version > kVersion) {
    throw FormatError(internal::concat("frame description: version ", version, ", this lsgd reads 1 to ",
                                       kVersion));
  }
  const std::int64_t width = in.get_i64(), height = in.get_i64();
  if (width <= 0 || height <= 0 || width > (1 << 20) || height > (1 << 20)) {
    throw FormatError(internal::concat("frame description: image size ", width, "x", height));
  }
  d.width = static_cast<int>(width);
  d.height = static_cast<int>(height);
  d.options_key = static_cast<std::uint64_t>(in.get_i64());
  d.convert_ms = in.get_f64();
  d.segment_ms = in.get_f64();
  d.describe_ms = in.get_f64();
  const std::int64_t rows = in.get_i64(), cols = in.get_i64(), storage = in.get_i64();
  if (rows <= 0 || cols <= 0 || rows > (1 << 12) || cols > (1 << 12) || (storage != 0 && storage != 1)) {
    throw FormatError(internal::concat("frame description: a descriptor grid of ", rows, " x ", cols,
                                       " cells, storage ", storage));
  }
  Descriptor& x = d.descriptor;
  x.grid = {static_cast<int>(rows), static_cast<int>(cols)};
  x.storage = storage == 1 ? HistogramStorage::kCompact : HistogramStorage::kExact;
  x.cell_pixels = in.get_f64();
  const auto cells = static_cast<std::size_t>(x.grid.cells());
  if (x.storage == HistogramStorage::kCompact) {
    if (cells > in.remaining() / kCompactBins) throw FormatError("frame description: the histograms are cut short");
    const std::uint8_t* h = in.get_bytes(cells * kCompactBins);
    x.compact.assign(h, h + cells * kCompactBins);
  } else {
    if (cells > in.remaining() / (2 * kBins + 4)) throw FormatError("frame description: the histograms are cut short");
    const std::uint8_t* h = in.get_bytes(cells * kBins * 2);
    x.hist.resize(cells * kBins);
    for (std::size_t k = 0; k < x.hist.size(); ++k) {
      x.hist[k] = static_cast<std::uint16_t>(h[2 * k] | (h[2 * k + 1] << 8));
    }
    const std::uint8_t* p = in.get_bytes(cells * 4);
    x.pixels.resize(cells);
    for (std::size_t k = 0; k < cells; ++k) {
      x.pixels[k] = static_cast<std::uint32_t>(p[4 * k]) | static_cast<std::uint32_t>(p[4 * k + 1]) << 8 |
                    static_cast<std::uint32_t>(p[4 * k + 2]) << 16 | static_cast<std::uint32_t>(p[4 * k + 3]) << 24;
    }
  }
  const std::size_t stages = count_of(in, 16, "stage count");
  for (std::size_t k = 0; k < stages; ++k) {
    const std::size_t n = count_of(in, 1, "stage name length");
    const std::uint8_t* name = in.get_bytes(n);
    d.stages.emplace_back(reinterpret_cast<const char*>(name), n);
    const std::size_t m = count_of(in, 1, "stage record length");
    const std::uint8_t* record = in.get_bytes(m);
    d.records.emplace_back(record, record + m);
  }
  if (version >= 2) {
    const std::size_t n = count_of(in, 1, "signature length");
    const std::uint8_t* signature = in.get_bytes(n);
    d.signature.assign(signature, signature + n);
  }
  in.finish();
  try {
    x.check_consistent("frame description: the descriptor");
    x.check_counts("frame description: the descriptor");
  } catch (const InvalidArgument& e) {
    throw FormatError(e.what());
  }
  return d;
}

// The version a description's bytes declare (0 when they are too short to
// say), read before they are decoded: version 3 and later end in a checksum.
std::int64_t declared_version(const std::uint8_t* data, std::size_t size) {
  if (size < sizeof kMagic + 8) return 0;
  std::uint64_t v = 0;
  for (int b = 7; b >= 0; --b) v = v << 8 | data[sizeof kMagic + static_cast<std::size_t>(b)];
  return static_cast<std::int64_t>(v);
}

}  // namespace

FrameDescription decode_frame_description(const std::uint8_t* data, std::size_t size) {
  // Not a description at all is said first; then a damaged one.
  if (size >= sizeof kMagic && std::memcmp(data, kMagic, sizeof kMagic) != 0) {
    throw FormatError("frame description: the bytes do not start with its mark (LSGDFRMD)");
  }
  // A version this lsgd does not read is said by decode(), whatever its end holds.
  if (const std::int64_t version = declared_version(data, size); version >= 3 && version <= kVersion) {
    if (size < sizeof kMagic + 8 + kChecksumBytes) throw FormatError("frame description: cut short");
    size -= kChecksumBytes;
    std::uint32_t stored = 0;
    for (std::size_t b = kChecksumBytes; b-- > 0;) stored = stored << 8 | data[size + b];
    const std::uint32_t computed = crc_of(data, size);
    if (stored != computed) {
      throw FormatError(internal::concat("frame description: its checksum ", stored,
                                         " does not match its bytes (", computed,
                                         "): they were damaged or cut"));
    }
  }
  StateReader in(data, size, "frame description");
  try {
    return decode(in);
  } catch (const InvalidArgument& e) {  // StateReader: a value cut short, bytes left over
    throw FormatError(e.what());
  }
}

void Detector::check_stages_describe(const char* call) const {
  for (const auto& stage : stages_) {
    if (!stage->describes()) {
      internal::throw_invalid("Detector::", call, ": verification stage ", stage->name(),
                              " cannot take a frame described apart from its image "
                              "(VerificationStage::describes())");
    }
  }
}

template <typename Image>
FrameDescription Detector::describe_image(const Image& frame) {
  const Exclusive exclusive(busy_, "describe_frame");
  check_stages_describe("describe_frame");
  FrameDescription out;
  std::int64_t t = now_ns();
  to_gray(frame, gray_);
  out.convert_ms = ms_since(t);
  check_size(gray_.width, gray_.height);
  out.width = gray_.width;
  out.height = gray_.height;
  out.options_key = describing_key_;
  t = now_ns();
  segment_and_describe(segmenter_, gray_, segmentation_, exact_, describe_scratch_, options_.descriptor);
  out.segment_ms = ms_since(t);
  t = now_ns();
  if (options_.descriptor.storage == HistogramStorage::kCompact) {
    compact(exact_, out.descriptor);
  } else {
    out.descriptor = exact_;
  }
  for (const auto& stage : stages_) {
    StateWriter record;
    stage->describe(gray_, record);
    out.stages.emplace_back(stage->name());
    out.records.push_back(record.take());
  }
  if (place_cuts_.enabled()) out.signature = place_signature(gray_);
  out.describe_ms = ms_since(t);
  return out;
}

FrameDescription Detector::describe_frame(const cv::Mat& frame) { return describe_image(frame); }
FrameDescription Detector::describe_frame(const ImageView& frame) { return describe_image(frame); }

void Detector::check_description(const FrameDescription& frame) const {
  if (frame.options_key != describing_key_) {
    internal::throw_invalid("the frame was described under other segmentation, descriptor or "
                            "verification options than this detector's (describing_options_key ",
                            frame.options_key, ", this detector's ", describing_key_, ")");
  }
  if (frame.width <= 0 || frame.height <= 0) {
    internal::throw_invalid("the described frame's size ", frame.width, "x", frame.height);
  }
  check_size(frame.width, frame.height);
  const Descriptor& x = frame.descriptor;
  const GridSize grid = frame_grid(frame.width, frame.height, options_.segmentation);
  if (x.storage != options_.descriptor.storage || x.grid.rows != grid.rows || x.grid.cols != grid.cols) {
    internal::throw_invalid("the described frame's descriptor (", x.grid.rows, " x ", x.grid.cols,
                            " cells, ", to_string(x.storage), ") is not the ", grid.rows, " x ",
                            grid.cols, " cells, ", to_string(options_.descriptor.storage),
                            " of a ", frame.width, "x", frame.height, " frame");
  }
  x.check_consistent("the described frame's descriptor");
  x.check_counts("the described frame's descriptor");
  const std::size_t signature = place_cuts_.enabled() ? static_cast<std::size_t>(kSignatureBytes) : 0;
  if (frame.signature.size() != signature) {
    internal::throw_invalid("the frame description has a place signature of ", frame.signature.size(),
                            " bytes; this detector takes ", signature,
                            " (verification.temporal.place_cut)");
  }
  if (frame.stages.size() != stages_.size() || frame.records.size() != stages_.size()) {
    internal::throw_invalid("the frame description has ", frame.stages.size(), " stages and ",
                            frame.records.size(), " records; this detector runs ", stages_.size());
  }
  for (std::size_t k = 0; k < stages_.size(); ++k) {
    if (frame.stages[k] != stages_[k]->name()) {
      internal::throw_invalid("the frame description's stage ", k + 1, " is '", frame.stages[k],
                              "', this detector's ", stages_[k]->name());
    }
    const std::vector<std::uint8_t>& record = frame.records[k];
    stages_[k]->check_description(StateReader(
        record.data(), record.size(), std::string("the frame description's ") + stages_[k]->name() + " record"));
  }
}

Result Detector::run_described(const FrameDescription& frame, bool store, std::int64_t id, double stamp) {
  const Exclusive exclusive(busy_, store ? "process" : "query");
  if (!store) check_answers_queries();
  check_stages_describe(store ? "process" : "query");
  const std::int64_t start = now_ns();
  const std::int64_t given = next_id(id, stamp);
  check_description(frame);
  Result result;
  result.frame = store_.size();
  result.id = given;
  result.stamp = stamp;
  result.timings.convert_ms = frame.convert_ms;
  result.timings.segment_ms = frame.segment_ms;
  result.timings.describe_ms = frame.describe_ms;
  descriptor_ = frame.descriptor;
  signature_ = frame.signature;
  Result out = process_described(std::move(result), start, store, &frame, frame.width, frame.height);
  // The whole frame's work, wherever it ran: describing and this call.
  out.timings.total_ms += frame.convert_ms + frame.segment_ms + frame.describe_ms;
  return out;
}

Result Detector::process(const FrameDescription& frame, std::int64_t id, double stamp) {
  return run_described(frame, true, id, stamp);
}

Result Detector::query(const FrameDescription& frame, std::int64_t id, double stamp) {
  return run_described(frame, false, id, stamp);
}

}  // namespace lsgd
