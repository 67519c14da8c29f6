// Detector's parts shared by its source files (detector.cc, detector_state.cc).
#pragma once

#include <atomic>

#include "internal/check.h"
#include "lsgd/detector.h"

namespace lsgd {

// Marks the detector busy for one call that changes it; a second call while
// one runs (another thread) throws instead of corrupting the state.
class Detector::Exclusive {
 public:
  Exclusive(std::atomic<bool>& busy, const char* call) : busy_(busy) {
    if (busy_.exchange(true, std::memory_order_acquire)) {
      internal::throw_invalid(
          "Detector::", call, " was called while another call on the same Detector was running "
          "(from another thread): a Detector is used by one thread at a time (one detector per "
          "thread, or a mutex around its calls)");
    }
  }
  ~Exclusive() { busy_.store(false, std::memory_order_release); }
  Exclusive(const Exclusive&) = delete;
  Exclusive& operator=(const Exclusive&) = delete;

 private:
  std::atomic<bool>& busy_;
};

}  // namespace lsgd
