#include "lsgd/detector.h"

#include <algorithm>
#include <cmath>

#include "detector_internal.h"
#include "internal/check.h"
#include "lsgd/limits.h"

// Detector's persistence: every frame's state (its components' records),
// restoring a stored frame, and forgetting frames (the kept ones restored
// into a new detector).
namespace lsgd {

void Detector::FrameTags::save_frame(std::int64_t frame, StateWriter& out) const {
  out.put_i64(ids.at(static_cast<std::size_t>(frame)));
  out.put_f64(stamps.at(static_cast<std::size_t>(frame)));
}

void Detector::FrameTags::check_frame(std::int64_t, int, int, std::uint32_t version,
                                      StateReader in) const {
  if (!in.present()) return;
  check_state_version(in.what(), name(), version, 1);
  const std::int64_t id = in.get_i64();
  const double stamp = in.get_f64();
  in.finish();
  if (id <= last() || id > kMaxFrameId) {
    internal::throw_invalid(in.what(), ": id ", id, " is not above the last frame's id ", last());
  }
  if (given_id >= 0 && id != given_id) {
    internal::throw_invalid(in.what(), ": id ", id, ", but its row says ", given_id);
  }
  if (std::isinf(stamp)) internal::throw_invalid(in.what(), ": time stamp ", stamp);
}

void Detector::FrameTags::restore_frame(std::int64_t, int, int, std::uint32_t, StateReader in) {
  if (in.present()) {
    ids.push_back(in.get_i64());
    stamps.push_back(in.get_f64());
    return;
  }
  ids.push_back(given_id >= 0 ? given_id : last() + 1);
  stamps.push_back(kNoStamp);
}

std::int64_t Detector::forget(std::int64_t first_id, std::int64_t last_id) {
  const Exclusive exclusive(busy_, "forget");
  if (first_id > last_id) {
    internal::throw_invalid("Detector::forget: the first id ", first_id, " is above the last ",
                            last_id);
  }
  if (first_id < 0 || last_id > kMaxFrameId) {
    internal::throw_invalid("Detector::forget: ids ", first_id, " .. ", last_id,
                            " are outside the frame ids 0 .. ", kMaxFrameId);
  }
  for (const Stateful* c : stateful()) {
    if (!c->forgets()) {
      internal::throw_invalid("Detector::forget: ", c->name(), " keeps per-frame state and cannot "
                              "forget frames (Stateful::forgets())");
    }
  }
  const auto first = std::lower_bound(tags_.ids.begin(), tags_.ids.end(), first_id);
  const auto last = std::upper_bound(first, tags_.ids.end(), last_id);
  const std::int64_t forgotten = last - first;
  if (forgotten == 0) return 0;
  std::vector<std::int64_t> after(static_cast<std::size_t>(size()));
  const auto from = static_cast<std::int64_t>(first - tags_.ids.begin());
  for (std::int64_t f = 0; f < size(); ++f) {
    after[static_cast<std::size_t>(f)] = f < from ? f : f < from + forgotten ? -1 : f - forgotten;
  }
  const bool last_kept = after.back() >= 0;
  const bool cut_pending = continuity().held.loop < 0 && decision_.ranking_track().held.loop < 0;
  auto kept = std::make_unique<Detector>(options_);
  kept->restore_kept(*this, FrameRenumbering(std::move(after)));
  // A cut() since the last frame still holds for the next one.
  if (last_kept && cut_pending) kept->decision_.cut();
  // Everything allocated: nothing below throws.
  std::swap(store_, kept->store_);
  std::swap(search_, kept->search_);
  std::swap(evidence_, kept->evidence_);
  std::swap(query_evidence_, kept->query_evidence_);
  std::swap(stages_, kept->stages_);
  std::swap(stage_list_, kept->stage_list_);
  std::swap(decision_, kept->decision_);
  std::swap(place_cuts_, kept->place_cuts_);
  std::swap(tags_, kept->tags_);
  return forgotten;
}

namespace {

// A stored frame's descriptor as one to store again.
Descriptor copy_of(const DescriptorView& v, const GridSize& grid) {
  Descriptor d;
  d.grid = grid;
  const auto cells = static_cast<std::size_t>(v.cells);
  if (v.storage() == HistogramStorage::kCompact) {
    d.storage = HistogramStorage::kCompact;
    d.compact.assign(v.compact, v.compact + cells * kCompactBins);
    d.cell_pixels = v.cell_pixels;
  } else {
    d.hist.assign(v.hist, v.hist + cells * kBins);
    d.pixels.assign(v.pixels, v.pixels + cells);
  }
  return d;
}

}  // namespace

void Detector::restore_kept(const Detector& from, const FrameRenumbering& renumbered) {
  const std::vector<Stateful*> mine = stateful(), theirs = from.stateful();
  StateWriter writer;
  std::int64_t frame = 0;
  for (std::int64_t f = 0; f < from.size(); ++f) {
    if (renumbered.after(f) < 0) continue;
    for (std::size_t c = 0; c < mine.size(); ++c) {
      writer.clear();
      theirs[c]->save_frame(f, writer);
      const std::string what =
          internal::concat("forget: frame ", f, "'s ", theirs[c]->name(), " state");
      mine[c]->restore_renumbered(frame, from.width_, from.height_, theirs[c]->state_version(),
                                  StateReader(writer.bytes().data(), writer.bytes().size(), what),
                                  renumbered);
    }
    const std::int64_t group = search_->has_groups() ? search_->group_of(frame) : 0;
    store_.add(copy_of(from.store_.view(f), from.store_.grid()),
               std::clamp<std::int64_t>(group, 0, store_.groups()));
    ++frame;
  }
  width_ = from.width_;
  height_ = from.height_;
}

std::vector<Stateful*> Detector::stateful() const {
  std::vector<Stateful*> out;
  if (search_->has_state()) out.push_back(search_.get());
  for (const auto& stage : stages_) {
    if (stage->has_state()) out.push_back(stage.get());
  }
  out.push_back(const_cast<LoopDecision*>(&decision_));
  if (place_cuts_.has_state()) out.push_back(const_cast<PlaceCuts*>(&place_cuts_));
  out.push_back(const_cast<FrameTags*>(&tags_));
  return out;
}

std::vector<std::uint8_t> Detector::frame_state(std::int64_t frame) const {
  if (frame < 0 || frame >= store_.size()) {
    internal::throw_invalid("frame_state: frame ", frame, " is not stored (", store_.size(),
                            " frames)");
  }
  std::vector<StateRecord> records;
  StateWriter writer;
  for (const Stateful* c : stateful()) {
    writer.clear();
    c->save_frame(frame, writer);
    records.push_back({c->name(), c->state_version(), writer.bytes()});
  }
  return encode_records(records);
}

void Detector::restore_index(const std::uint8_t* data, std::size_t size) {
  const Exclusive exclusive(busy_, "restore_index");
  search_->restore_index(store_, options_.similarity.metric, data, size);
}

void Detector::restore_frame(int width, int height, const Descriptor& descriptor,
                             const std::vector<std::uint8_t>& state, std::int64_t id) {
  const Exclusive exclusive(busy_, "restore_frame");
  const std::int64_t frame = store_.size();
  if (width <= 0 || height <= 0 || (frame > 0 && (width != width_ || height != height_))) {
    internal::throw_invalid("restore_frame: frame ", frame, " is ", width, "x", height,
                            " but the detector holds ", width_, "x", height_, " frames");
  }
  const GridSize expected = frame_grid(width, height, options_.segmentation);
  if (descriptor.grid != expected) {
    internal::throw_invalid("restore_frame: frame ", frame, " has a ", descriptor.grid.rows, "x",
                            descriptor.grid.cols, " grid, but ", width, "x", height,
                            " frames have a ", expected.rows, "x", expected.cols, " grid");
  }
  if (descriptor.storage != options_.descriptor.storage) {
    internal::throw_invalid("restore_frame: frame ", frame, " has a ",
                            to_string(descriptor.storage), " descriptor but descriptor.storage is ",
                            to_string(options_.descriptor.storage));
  }
  descriptor.check_consistent("restore_frame");
  // A compact descriptor's cells hold the pixels of the frame as described
  // (its working size).
  const FrameSize work = working_size(width, height, options_.segmentation);
  const double pixels = static_cast<double>(work.width) * work.height;
  if (descriptor.storage == HistogramStorage::kCompact &&
      std::fabs(descriptor.cell_pixels * expected.cells() - pixels) > 0.5) {
    internal::throw_invalid("restore_frame: frame ", frame, " has ", descriptor.cell_pixels,
                            " pixels per cell, but ", width, "x", height, " frames have ",
                            pixels / expected.cells());
  }
  std::vector<StateRecord> records;
  try {
    records = decode_records(state.data(), state.size());
  } catch (const InvalidArgument& e) {
    internal::throw_invalid("restore_frame: frame ", frame, ": ", e.what());
  }
  const std::vector<Stateful*> components = stateful();
  for (const StateRecord& r : records) {
    if (std::none_of(components.begin(), components.end(),
                     [&](const Stateful* c) { return r.component == c->name(); })) {
      internal::throw_invalid("restore_frame: frame ", frame, " has state of '", r.component,
                              "', which these options do not have (search mode ", search_->name(),
                              ", verification stages ", verification_stages(options_.verification),
                              options_.verification.has(kTemporalStage)
                                  ? ", verification.temporal.place_cut " +
                                        option_text(options_, "verification.temporal.place_cut")
                                  : std::string(),
                              ")");
    }
  }
  // Every component checks its record before any changes, so that a
  // refused frame leaves the detector unchanged.
  const auto reader = [&](const Stateful* c) {
    const std::string what = internal::concat("restore_frame: frame ", frame, "'s ", c->name(),
                                              " state");
    for (const StateRecord& r : records) {
      if (r.component == c->name()) return StateReader(r.bytes.data(), r.bytes.size(), what);
    }
    return StateReader(what);
  };
  const auto version = [&](const Stateful* c) {
    for (const StateRecord& r : records) {
      if (r.component == c->name()) return r.version;
    }
    return c->state_version();
  };
  if (id < -1 || id > kMaxFrameId || (id >= 0 && id <= tags_.last())) {
    internal::throw_invalid("restore_frame: frame ", frame, "'s id ", id, " is not above the last frame's id ",
                            tags_.last());
  }
  tags_.given_id = id;
  for (const Stateful* c : components) c->check_frame(frame, width, height, version(c), reader(c));
  for (Stateful* c : components) c->restore_frame(frame, width, height, version(c), reader(c));
  // The search's group places the frame beside the group's other frames.
  const std::int64_t group = search_->has_groups() ? search_->group_of(frame) : 0;
  store_.add(descriptor, std::clamp<std::int64_t>(group, 0, store_.groups()));
  width_ = width;
  height_ = height;
}

}  // namespace lsgd
