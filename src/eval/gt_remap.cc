#include "lsgd/eval/gt_remap.h"

#include <cstddef>

#include "internal/check.h"
#include "lsgd/error.h"

namespace lsgd::eval {

using internal::concat;

GroundTruth select_rows(const GroundTruth& gt, const std::vector<std::int64_t>& rows) {
  // frames_of[r]: the new frames showing row r, ascending.
  std::vector<std::vector<std::int64_t>> frames_of(static_cast<std::size_t>(gt.frames()));
  for (std::size_t f = 0; f < rows.size(); ++f) {
    if (rows[f] < 0 || rows[f] >= gt.frames()) {
      internal::throw_invalid("frame ", f, " maps to ground-truth row ", rows[f],
                              ", outside the ground truth's ", gt.frames(), " rows");
    }
    frames_of[static_cast<std::size_t>(rows[f])].push_back(static_cast<std::int64_t>(f));
  }
  GroundTruth out(static_cast<std::int64_t>(rows.size()));
  for (std::int64_t q = 0; q < gt.frames(); ++q) {  // frames_of spans every row: bounded
    const auto& fq = frames_of[static_cast<std::size_t>(q)];
    if (fq.empty()) continue;
    for (std::size_t i = 0; i < fq.size(); ++i) {  // one row, several frames: one place
      for (std::size_t j = i + 1; j < fq.size(); ++j) out.add(fq[i], fq[j]);
    }
    for (std::int64_t m : gt.matches(q)) {
      for (std::int64_t b : frames_of[static_cast<std::size_t>(m)]) {
        for (std::int64_t a : fq) out.add(a, b);
      }
    }
  }
  return out;
}

SubsampleMatch parse_subsample_match(const std::string& name) {
  if (name == "exact") return SubsampleMatch::kExact;
  if (name == "block") return SubsampleMatch::kBlock;
  internal::throw_invalid("subsample match '", name, "' is not one of exact, block");
}

std::string to_string(SubsampleMatch match) {
  return match == SubsampleMatch::kExact ? "exact" : "block";
}

GroundTruth subsample(const GroundTruth& gt, std::int64_t every, std::int64_t first,
                      std::int64_t last, SubsampleMatch match) {
  const io::FrameSelection selection{first, last, every};
  const std::vector<std::int64_t> kept = selection.kept(gt.frames());
  if (match == SubsampleMatch::kExact) return select_rows(gt, kept);
  GroundTruth out(static_cast<std::int64_t>(kept.size()));
  const std::int64_t end = last < 0 ? gt.frames() - 1 : last;
  for (std::int64_t q = first; q <= end; ++q) {
    const std::int64_t a = (q - first) / every;
    for (std::int64_t m : gt.matches(q)) {
      if (m < first) continue;
      const std::int64_t b = (m - first) / every;
      if (a != b) out.add(a, b);
    }
  }
  return out;
}

GtRows parse_gt_rows(const std::string& name) {
  if (name == "pair") return GtRows::kPair;
  if (name == "image") return GtRows::kImage;
  internal::throw_invalid("ground-truth rows '", name, "' is not one of pair, image");
}

std::string to_string(GtRows rows) { return rows == GtRows::kPair ? "pair" : "image"; }

std::int64_t fabmap_gt_frames(std::int64_t pairs, GtRows rows) {
  return rows == GtRows::kPair ? pairs : 2 * pairs;
}

GroundTruth fabmap_groundtruth(const GroundTruth& gt, std::int64_t pairs, io::Side side) {
  if (pairs <= 0) internal::throw_invalid("FAB-MAP pairs = ", pairs, " must be > 0");
  const bool per_pair = gt.frames() == pairs;
  if (!per_pair && gt.frames() != 2 * pairs) {
    throw FormatError(concat("the ground truth has ", gt.frames(),
                             " rows but the FAB-MAP folder has ", pairs, " left/right pairs (",
                             2 * pairs, " images): expected one row per pair or one per image"));
  }
  const std::int64_t frames = side == io::Side::kBoth ? 2 * pairs : pairs;
  std::vector<std::int64_t> rows(static_cast<std::size_t>(frames));
  for (std::int64_t f = 0; f < frames; ++f) {
    std::int64_t row = f;  // per image with both sides, per pair with one side
    if (per_pair && side == io::Side::kBoth) row = f / 2;
    if (!per_pair && side == io::Side::kLeft) row = 2 * f;
    if (!per_pair && side == io::Side::kRight) row = 2 * f + 1;
    rows[static_cast<std::size_t>(f)] = row;
  }
  return select_rows(gt, rows);
}

}  // namespace lsgd::eval
