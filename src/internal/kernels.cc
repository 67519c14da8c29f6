// SIMD kernels (see kernels.h). Highway compiles the code between
// HWY_BEFORE_NAMESPACE and HWY_AFTER_NAMESPACE once per target; the
// HWY_ONCE part dispatches to the best target at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "internal/kernels.cc"
#include "internal/kernels.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"

HWY_BEFORE_NAMESPACE();
namespace lsgd::internal {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Vector c covers pixels [xs, xs + lanes) (see assign_lists()); the best
// distances and labels of its lanes stay in registers over its segments.
void AssignRowSimd(const AssignRow& r) {
  const hn::ScalableTag<float> df;
  const hn::RebindToSigned<decltype(df)> di;
  const hn::Rebind<std::uint8_t, decltype(df)> d8;
  const int lanes = static_cast<int>(hn::Lanes(df));
  const int width = r.width;
  // Narrower than one vector, or tables and lists made for another vector
  // width (dispatch changed since): pixel by pixel, the same operations.
  if (width < lanes || r.lanes != lanes) {
    for (int x = 0; x < width; ++x) {
      float best = std::numeric_limits<float>::infinity();
      std::int32_t label = -1;
      for (int s = 0; s < r.count; ++s) {
        const RowSegment& seg = r.segments[s];
        if (x < seg.x0 || x > seg.x1) continue;
        const float d = fuse_distance(r, seg, x);
        if (d < best) best = d, label = seg.label;
      }
      r.labels[x] = label;
    }
    return;
  }
  const int chunks = (width + lanes - 1) / lanes;
  const std::int32_t* const start = r.lists;
  const std::int32_t* const items = r.lists + chunks + 1;
  const auto inv_i = hn::Set(df, r.inv_intensity);
  const auto infinity = hn::Set(df, std::numeric_limits<float>::infinity());
  const auto unreached = hn::Set(di, -1);
  for (int c = 0; c < chunks; ++c) {
    const int xs = std::min(c * lanes, width - lanes);
    const auto pix = hn::ConvertTo(df, hn::PromoteTo(di, hn::LoadU(d8, r.pixels + xs)));
    auto best = infinity;
    auto label = unreached;
    for (std::int32_t i = start[c]; i < start[c + 1]; ++i) {
      const RowSegment& seg = r.segments[items[i]];
      const auto dI = hn::Sub(pix, hn::Set(df, seg.intensity));
      const auto xterm = hn::LoadU(df, seg.xterm + (xs - seg.xterm_first));
      const auto d =
          hn::Add(hn::Add(hn::Mul(hn::Mul(dI, dI), inv_i), xterm), hn::Set(df, seg.row_term));
      const auto closer = hn::Lt(d, best);  // +infinity outside the window: never
      best = hn::IfThenElse(closer, d, best);
      label = hn::IfThenElse(hn::RebindMask(di, closer), hn::Set(di, seg.label), label);
    }
    hn::StoreU(label, di, r.labels + xs);
  }
}

std::int32_t AssignLanes() {
  return static_cast<std::int32_t>(hn::Lanes(hn::ScalableTag<float>()));
}

int RowSumsSimd(const std::int32_t* labels, const std::uint8_t* pixels, int width, int y,
                std::int64_t* sums, int x) {
  const hn::ScalableTag<std::int32_t> di;
  const hn::Rebind<std::uint8_t, decltype(di)> d8;
  const int lanes = static_cast<int>(hn::Lanes(di));
  while (x < width) {
    const std::int32_t k = labels[x];
    if (k < 0) return x;
    const auto vk = hn::Set(di, k);
    auto acc = hn::Zero(di);  // at most 4096 * 255 per lane: no overflow
    const int start = x;
    std::int64_t tail = 0;
    for (;;) {
      if (x + lanes > width) {  // the row's last few pixels
        for (; x < width && labels[x] == k; ++x) tail += pixels[x];
        break;
      }
      const auto same = hn::Eq(hn::LoadU(di, labels + x), vk);
      const auto pix = hn::PromoteTo(di, hn::LoadU(d8, pixels + x));
      if (hn::AllTrue(di, same)) {
        acc = hn::Add(acc, pix);
        x += lanes;
        continue;
      }
      const auto n = static_cast<std::size_t>(hn::FindFirstTrue(di, hn::Not(same)));
      acc = hn::Add(acc, hn::IfThenElseZero(hn::FirstN(di, n), pix));
      x += static_cast<int>(n);
      break;
    }
    const std::int64_t n = x - start;
    std::int64_t* s = sums + static_cast<std::size_t>(k) * 4;
    s[0] += n * (start + x - 1) / 2;  // sum of start .. x-1 (n * (a + b) is even)
    s[1] += n * y;
    s[2] += hn::GetLane(hn::SumOfLanes(di, acc)) + tail;
    s[3] += n;
  }
  return width;
}

int LabelRunsSimd(const std::int32_t* labels, int width, LabelRun* runs) {
  const hn::ScalableTag<std::int32_t> di;
  const int lanes = static_cast<int>(hn::Lanes(di));
  int n = 0;
  int x = 0;
  while (x < width) {
    const std::int32_t k = labels[x];
    runs[n++] = LabelRun{x, k};
    const auto vk = hn::Set(di, k);
    for (;;) {
      if (x + lanes > width) {  // the row's last few pixels
        while (x < width && labels[x] == k) ++x;
        break;
      }
      const auto differ = hn::Ne(hn::LoadU(di, labels + x), vk);
      if (hn::AllFalse(di, differ)) {
        x += lanes;
        continue;
      }
      x += static_cast<int>(hn::FindFirstTrue(di, differ));
      break;
    }
  }
  return n;
}

void CellL1Simd(const Bin* a, const Bin* b, int cells, std::uint32_t* out) {
#if HWY_TARGET == HWY_SCALAR
  // One lane: no pair of 16-bit lanes to split a 32-bit lane into.
  for (int k = 0; k < cells; ++k) {
    const Bin* pa = a + static_cast<std::size_t>(k) * kBins;
    const Bin* pb = b + static_cast<std::size_t>(k) * kBins;
    std::uint32_t sum = 0;
    for (int i = 0; i < kBins; ++i) sum += pa[i] > pb[i] ? pa[i] - pb[i] : pb[i] - pa[i];
    out[k] = sum;
  }
#else
  // |a - b| of a full vector of 16-bit bins (it fits: both are 16-bit), then
  // its even and odd lanes added into 32-bit lanes: half the operations of
  // promoting each half to 32 bits first. Integer sums: the same values.
  const hn::ScalableTag<std::uint16_t> d16;
  const hn::Repartition<std::uint32_t, decltype(d16)> d32;
  const std::size_t lanes = hn::Lanes(d16);
  const auto low = hn::Set(d32, 0xFFFFu);
  for (int k = 0; k < cells; ++k) {
    const Bin* pa = a + static_cast<std::size_t>(k) * kBins;
    const Bin* pb = b + static_cast<std::size_t>(k) * kBins;
    auto even = hn::Zero(d32);
    auto odd = hn::Zero(d32);
    std::size_t i = 0;
    for (; i + lanes <= static_cast<std::size_t>(kBins); i += lanes) {
      const auto va = hn::LoadU(d16, pa + i);
      const auto vb = hn::LoadU(d16, pb + i);
      const auto diff = hn::BitCast(d32, hn::Sub(hn::Max(va, vb), hn::Min(va, vb)));
      even = hn::Add(even, hn::And(diff, low));
      odd = hn::Add(odd, hn::ShiftRight<16>(diff));
    }
    std::uint32_t sum = hn::GetLane(hn::SumOfLanes(d32, hn::Add(even, odd)));
    for (; i < static_cast<std::size_t>(kBins); ++i) {  // only when the lanes do not divide 256
      sum += pa[i] > pb[i] ? pa[i] - pb[i] : pb[i] - pa[i];
    }
    out[k] = sum;
  }
#endif
}

// Sums of |a - b| over each 8 bytes, in u64 lanes: one psadbw on x86 (this
// Highway version has no SumsOf8AbsDiff), portable operations elsewhere.
template <class D64, class V8>
HWY_INLINE hn::Vec<D64> SumsOf8AbsDiff(D64 /* d64: the result type */, V8 a, V8 b) {
#if HWY_TARGET == HWY_AVX3 || HWY_TARGET == HWY_AVX3_DL
  return hn::Vec<D64>{_mm512_sad_epu8(a.raw, b.raw)};
#elif HWY_TARGET == HWY_AVX2
  return hn::Vec<D64>{_mm256_sad_epu8(a.raw, b.raw)};
#elif HWY_TARGET == HWY_SSE4 || HWY_TARGET == HWY_SSSE3
  return hn::Vec<D64>{_mm_sad_epu8(a.raw, b.raw)};
#else
  // |a - b| of unsigned bytes: one of the two saturated differences is 0.
  return hn::SumsOf8(hn::Or(hn::SaturatedSub(a, b), hn::SaturatedSub(b, a)));
#endif
}

// The SAD vector of one cell: u64 lanes whose total is the cell's SAD, at
// most kCompactBins * 255 = 32640, so every lane fits 16 bits.
template <class D8, class D64>
HWY_INLINE hn::Vec<D64> CellSadVector(D8 d8, D64 d64, const CompactBin* pa, const CompactBin* pb) {
  const std::size_t lanes = hn::Lanes(d8);
  auto acc = hn::Zero(d64);
  for (std::size_t i = 0; i < static_cast<std::size_t>(kCompactBins); i += lanes) {
    acc = hn::Add(acc, SumsOf8AbsDiff(d64, hn::LoadU(d8, pa + i), hn::LoadU(d8, pb + i)));
  }
  return acc;
}

// Four cells share one horizontal sum: their SAD vectors are packed into the
// four 16-bit fields of each u64 lane (no field can carry into the next: a
// cell's total is at most 32640), so the sum of the lanes holds all four.
void CellSadSimd(const CompactBin* a, const CompactBin* b, int cells, std::uint32_t* out) {
  const hn::ScalableTag<std::uint8_t> d8;
  const hn::Repartition<std::uint64_t, decltype(d8)> d64;
  if (kCompactBins % hn::Lanes(d8) != 0) {  // vectors wider than a cell: bin by bin
    cell_sad_scalar(a, b, cells, out);
    return;
  }
  const auto cell = [&](int k) {
    const std::size_t off = static_cast<std::size_t>(k) * kCompactBins;
    return CellSadVector(d8, d64, a + off, b + off);
  };
  int k = 0;
  for (; k + 4 <= cells; k += 4) {
    auto packed = cell(k);
    packed = hn::Or(packed, hn::ShiftLeft<16>(cell(k + 1)));
    packed = hn::Or(packed, hn::ShiftLeft<32>(cell(k + 2)));
    packed = hn::Or(packed, hn::ShiftLeft<48>(cell(k + 3)));
    const std::uint64_t sums = hn::GetLane(hn::SumOfLanes(d64, packed));
    for (int j = 0; j < 4; ++j)
      out[k + j] = static_cast<std::uint32_t>((sums >> (16 * j)) & 0xFFFF);
  }
  for (; k < cells; ++k)
    out[k] = static_cast<std::uint32_t>(hn::GetLane(hn::SumOfLanes(d64, cell(k))));
}

// Vectors of doubles through the same correctly rounded operations as the
// scalar reference: int -> double is exact, and * (1 / kBins) equals
// / kBins exactly (a power of two).
void CellDistancesSimd(const std::uint32_t* l1, int cells, double scale, double* out) {
  const hn::ScalableTag<double> dd;
  const hn::Rebind<std::int32_t, decltype(dd)> di;  // L1 <= kBins * 65535 < 2^31
  const int lanes = static_cast<int>(hn::Lanes(dd));
  const auto vscale = hn::Set(dd, scale);
  const auto inv_bins = hn::Set(dd, 1.0 / kBins);
  int k = 0;
  for (; k + lanes <= cells; k += lanes) {
    const auto v = hn::PromoteTo(dd, hn::LoadU(di, reinterpret_cast<const std::int32_t*>(l1 + k)));
    hn::StoreU(hn::Mul(hn::Sqrt(hn::Mul(v, vscale)), inv_bins), dd, out + k);
  }
  cell_distances_scalar(l1 + k, cells - k, scale, out + k);
}

std::int64_t TargetOf() { return HWY_TARGET; }

}  // namespace HWY_NAMESPACE
}  // namespace lsgd::internal
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace lsgd::internal {

HWY_EXPORT(AssignRowSimd);
HWY_EXPORT(AssignLanes);
HWY_EXPORT(CellL1Simd);
HWY_EXPORT(LabelRunsSimd);
HWY_EXPORT(CellSadSimd);
HWY_EXPORT(CellDistancesSimd);
HWY_EXPORT(RowSumsSimd);
HWY_EXPORT(TargetOf);

void assign_row(const AssignRow& row) { HWY_DYNAMIC_DISPATCH(AssignRowSimd)(row); }

void assign_row_scalar(const AssignRow& r) {
  std::vector<float> distance(static_cast<std::size_t>(r.width),
                              std::numeric_limits<float>::infinity());
  std::fill(r.labels, r.labels + r.width, -1);
  for (int s = 0; s < r.count; ++s) {
    const RowSegment& seg = r.segments[s];
    for (int x = seg.x0; x <= seg.x1; ++x) {
      const float d = fuse_distance(r, seg, x);
      if (d < distance[x]) distance[x] = d, r.labels[x] = seg.label;
    }
  }
}

int assign_lanes() { return HWY_DYNAMIC_DISPATCH(AssignLanes)(); }

void assign_lists(const RowSegment* segments, int count, int width, int lanes,
                  std::vector<std::int32_t>& lists) {
  const int chunks = (width + lanes - 1) / lanes;
  // A segment's last vector; the row's last vector starts at width - lanes.
  const auto last_of = [&](const RowSegment& seg) {
    return seg.x1 >= width - lanes ? chunks - 1 : seg.x1 / lanes;
  };
  lists.assign(static_cast<std::size_t>(chunks) + 1, 0);  // a counting sort by vector
  for (int s = 0; s < count; ++s) {
    if (segments[s].x1 < segments[s].x0) continue;
    for (int c = segments[s].x0 / lanes, c1 = last_of(segments[s]); c <= c1; ++c) ++lists[c + 1];
  }
  for (int c = 0; c < chunks; ++c) lists[c + 1] += lists[c];
  lists.resize(lists.size() + static_cast<std::size_t>(lists[chunks]));
  std::int32_t* const start = lists.data();
  std::int32_t* const items = start + chunks + 1;
  for (int s = 0; s < count; ++s) {  // start[c] moves to the end of list c, i.e. start[c + 1]
    if (segments[s].x1 < segments[s].x0) continue;
    for (int c = segments[s].x0 / lanes, c1 = last_of(segments[s]); c <= c1; ++c) {
      items[start[c]++] = s;
    }
  }
  for (int c = chunks; c > 0; --c) start[c] = start[c - 1];
  start[0] = 0;
}

void x_terms(float cx, int x0, int x1, float inv_distance, int lanes, float* out) {
  const int first = x_terms_first(x0, lanes);
  const int size = x_terms_size(x0, x1, lanes);
  std::fill(out, out + size, std::numeric_limits<float>::infinity());
  for (int x = x0; x <= x1; ++x) {
    const float dx = static_cast<float>(x) - cx;
    out[x - first] = (dx * dx) * inv_distance;
  }
}

int row_sums(const std::int32_t* labels, const std::uint8_t* pixels, int width, int y,
             std::int64_t* sums, int start) {
  return HWY_DYNAMIC_DISPATCH(RowSumsSimd)(labels, pixels, width, y, sums, start);
}

int row_sums_scalar(const std::int32_t* labels, const std::uint8_t* pixels, int width, int y,
                    std::int64_t* sums, int start) {
  int x = start;
  while (x < width) {
    const std::int32_t k = labels[x];
    if (k < 0) return x;
    const int run_start = x;
    std::int64_t intensity = 0;
    for (; x < width && labels[x] == k; ++x) intensity += pixels[x];
    const std::int64_t n = x - run_start;
    std::int64_t* s = sums + static_cast<std::size_t>(k) * 4;
    s[0] += n * (run_start + x - 1) / 2;
    s[1] += n * y;
    s[2] += intensity;
    s[3] += n;
  }
  return width;
}

int label_runs(const std::int32_t* labels, int width, LabelRun* runs) {
  return HWY_DYNAMIC_DISPATCH(LabelRunsSimd)(labels, width, runs);
}

int label_runs_scalar(const std::int32_t* labels, int width, LabelRun* runs) {
  int n = 0;
  for (int x = 0; x < width; ++x) {
    if (x == 0 || labels[x] != labels[x - 1]) runs[n++] = LabelRun{x, labels[x]};
  }
  return n;
}

void cell_l1(const Bin* a, const Bin* b, int cells, std::uint32_t* out) {
  HWY_DYNAMIC_DISPATCH(CellL1Simd)(a, b, cells, out);
}

void cell_l1_scalar(const Bin* a, const Bin* b, int cells, std::uint32_t* out) {
  for (int k = 0; k < cells; ++k) {
    const Bin* pa = a + static_cast<std::size_t>(k) * kBins;
    const Bin* pb = b + static_cast<std::size_t>(k) * kBins;
    std::uint32_t sum = 0;
    for (int i = 0; i < kBins; ++i) sum += pa[i] > pb[i] ? pa[i] - pb[i] : pb[i] - pa[i];
    out[k] = sum;
  }
}

void cell_sad(const CompactBin* a, const CompactBin* b, int cells, std::uint32_t* out) {
  HWY_DYNAMIC_DISPATCH(CellSadSimd)(a, b, cells, out);
}

void cell_sad_scalar(const CompactBin* a, const CompactBin* b, int cells, std::uint32_t* out) {
  for (int k = 0; k < cells; ++k) {
    const CompactBin* pa = a + static_cast<std::size_t>(k) * kCompactBins;
    const CompactBin* pb = b + static_cast<std::size_t>(k) * kCompactBins;
    std::uint32_t sum = 0;
    for (int i = 0; i < kCompactBins; ++i) sum += pa[i] > pb[i] ? pa[i] - pb[i] : pb[i] - pa[i];
    out[k] = sum;
  }
}

void cell_distances(const std::uint32_t* l1, int cells, double scale, double* out) {
  HWY_DYNAMIC_DISPATCH(CellDistancesSimd)(l1, cells, scale, out);
}

void cell_distances_scalar(const std::uint32_t* l1, int cells, double scale, double* out) {
  for (int k = 0; k < cells; ++k) out[k] = std::sqrt(static_cast<double>(l1[k]) * scale) / kBins;
}

std::vector<std::int64_t> simd_targets() {
  std::vector<std::int64_t> out;
  const auto supported = static_cast<std::uint64_t>(hwy::SupportedTargets() & HWY_TARGETS);
  for (int shift = 0; shift < 64; ++shift) {  // unsigned: no shift into the sign bit
    const std::uint64_t bit = std::uint64_t{1} << shift;
    if (supported & bit) out.push_back(static_cast<std::int64_t>(bit));
  }
  return out;  // lower bits are the better targets on x86
}

std::string simd_target_name(std::int64_t target) { return hwy::TargetName(target); }

void force_simd_target(std::int64_t target) { hwy::SetSupportedTargetsForTest(target); }

std::string active_simd_target() { return hwy::TargetName(HWY_DYNAMIC_DISPATCH(TargetOf)()); }

}  // namespace lsgd::internal
#endif  // HWY_ONCE
