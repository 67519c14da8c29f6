// Per-frame state of the detector's components, as versioned records the
// database stores without looking inside.
//
// Every component that keeps state across frames (the search mode, each
// verification stage, the loop decision) implements Stateful: after a frame
// is processed it writes what it added for that frame (the dynamic node the
// frame joined, its temporal place, its ORB features, the decision's loop)
// as a record in a format of its own, with a version number; restoring the
// records of frames 0, 1, 2, ... in order rebuilds its state exactly.
// Detector::frame_state() gathers one frame's records into a blob
// (encode_records); Detector::restore_frame() hands each record back to the
// component of that name. A new component with state needs no change to the
// database: docs/design.md, "Add a verification stage".
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace lsgd {

// Writes little-endian values into a record.
class StateWriter {
 public:
  void put_i64(std::int64_t v);
  void put_f64(double v);
  void put_f32s(const float* v, std::size_t n);
  void put_bytes(const std::uint8_t* data, std::size_t n);
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }
  void reserve(std::size_t n) { bytes_.reserve(n); }
  // Moves the bytes out (the writer is empty afterwards).
  std::vector<std::uint8_t> take() { return std::move(bytes_); }
  bool empty() const { return bytes_.empty(); }
  void clear() { bytes_.clear(); }

 private:
  std::vector<std::uint8_t> bytes_;
};

// Reads a record written by StateWriter. Every read checks the bounds and
// throws InvalidArgument "<what>: ..." for a record that is too short;
// finish() throws when bytes are left over.
class StateReader {
 public:
  // A frame without a record of the component (present() false).
  explicit StateReader(std::string what) : what_(std::move(what)) {}
  StateReader(const std::uint8_t* data, std::size_t size, std::string what)
      : data_(data), size_(size), present_(true), what_(std::move(what)) {}
  bool present() const { return present_; }
  bool empty() const { return size_ == 0; }
  std::size_t remaining() const { return size_ - pos_; }
  std::int64_t get_i64();
  double get_f64();
  void get_f32s(float* out, std::size_t n);
  const std::uint8_t* get_bytes(std::size_t n);  // a pointer into the record
  void finish() const;
  const std::string& what() const { return what_; }

 private:
  void need(std::size_t n) const;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
  std::size_t pos_ = 0;
  bool present_ = false;
  std::string what_;
};

// One component's record for one frame.
struct StateRecord {
  std::string component;      // the component's name(): "nodes", "temporal", "geometric", "decision"
  std::uint32_t version = 1;  // of the component's record format
  std::vector<std::uint8_t> bytes;
};

// A frame's records as one blob: u32 count, then per record u16 name length,
// the name, u32 version, u32 size, the bytes (little-endian).
std::vector<std::uint8_t> encode_records(const std::vector<StateRecord>& records);
// The records of a blob; InvalidArgument for a blob that is cut, too long or
// has an empty or repeated name.
std::vector<StateRecord> decode_records(const std::uint8_t* data, std::size_t size);

// InvalidArgument "<what>: version V of <component>'s state is not one this
// lsgd reads (1 to newest)" unless 1 <= version <= newest.
void check_state_version(const std::string& what, const char* component, std::uint32_t version,
                         std::uint32_t newest);

// The frames' numbers before and after some are forgotten: after(f) is old
// frame f's new number, -1 for a forgotten frame or for -1 (none).
// identity() keeps every number (restore_frame() as restore_renumbered()).
class FrameRenumbering {
 public:
  explicit FrameRenumbering(std::vector<std::int64_t> after) : after_(std::move(after)) {}
  static FrameRenumbering identity() { return FrameRenumbering(); }
  std::int64_t after(std::int64_t frame) const {
    if (frame < 0) return -1;
    if (identity_) return frame;
    return frame >= static_cast<std::int64_t>(after_.size()) ? -1
                                                             : after_[static_cast<std::size_t>(frame)];
  }

 private:
  FrameRenumbering() : identity_(true) {}
  std::vector<std::int64_t> after_;
  bool identity_ = false;
};

// A component with per-frame state (see the top of this file).
class Stateful {
 public:
  virtual ~Stateful() = default;
  // The name its records carry (unique among the detector's components).
  virtual const char* name() const = 0;
  // True when it keeps per-frame state: the detector then saves a record of
  // it for every frame (possibly empty) and hands back each frame's record,
  // or an absent one (StateReader::present() false) for a frame saved
  // without it.
  virtual bool has_state() const { return false; }
  // Version of its record format; restore_frame() gets the version a record
  // was written with.
  virtual std::uint32_t state_version() const { return 1; }
  // Writes what the component added for stored frame `frame` (any stored
  // frame, not only the last).
  virtual void save_frame(std::int64_t frame, StateWriter& out) const {
    (void)frame, (void)out;
  }
  // Checks that `in` is a record the
  // component can restore for frame `frame` (the number of frames restored
  // so far) of a width x height sequence; InvalidArgument naming what is
  // wrong. Must not change the component.
  virtual void check_frame(std::int64_t frame, int width, int height, std::uint32_t version,
                           StateReader in) const {
    (void)frame, (void)width, (void)height, (void)version;
    in.finish();
  }
  // Restores that record (check_frame() passed for it).
  virtual void restore_frame(std::int64_t frame, int width, int height, std::uint32_t version,
                             StateReader in) {
    (void)frame, (void)width, (void)height, (void)version, (void)in;
  }

  // Forgetting frames (Detector::forget, io::Database::forget): the
  // detector's components are made anew and each kept frame's record, as
  // save_frame() wrote it, is handed in order to restore_renumbered() with
  // the frames' numbers before and after (`renumbered`). A record that names
  // other frames (a place, a loop, a group's members) names them by their
  // new numbers afterwards, or by none when they were forgotten.
  // forgets(): whether the component can; by default one without state.
  // Detector::forget refuses (InvalidArgument naming it) one that cannot.
  virtual bool forgets() const { return !has_state(); }
  // Restores kept frame `frame` (its new number) from its record; by default
  // restore_frame(), right for records that name no frame (features, ids).
  virtual void restore_renumbered(std::int64_t frame, int width, int height,
                                  std::uint32_t version, StateReader in,
                                  const FrameRenumbering& renumbered) {
    (void)renumbered;
    restore_frame(frame, width, height, version, in);
  }
};

}  // namespace lsgd
