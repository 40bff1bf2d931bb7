// SPDX-License-Identifier: Apache-2.0
// Hand-overs from DDS listener threads to the processing loop: commands (applied between frames)
// and this camera's predicted search windows.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <deque>
#include <mutex>
#include <utility>
#include <vector>

#include "panoptes/camera/detector.h"
#include "panoptes/time.h"

namespace panoptes::camera {

// A FIFO written by one thread and emptied at once by another. Bounded: when full the oldest item
// is dropped, so a command storm cannot grow memory.
template <class T>
class Mailbox {
 public:
  static constexpr std::size_t kCapacity = 256;

  void push(T value) {
    std::lock_guard lock(mutex_);
    if (items_.size() >= kCapacity) {
      items_.pop_front();
      ++dropped_;
    }
    items_.push_back(std::move(value));
  }
  // Items dropped because the mailbox was full.
  std::uint64_t dropped() {
    std::lock_guard lock(mutex_);
    return dropped_;
  }
  std::deque<T> take_all() {
    std::lock_guard lock(mutex_);
    return std::exchange(items_, {});
  }

 private:
  std::mutex mutex_;
  std::deque<T> items_;
  std::uint64_t dropped_ = 0;
};

// Predicted windows for this camera, written by the DDS listener, read by the detection loop.
class PredictionBox {
 public:
  void store(TimeNs stamp_ns, std::vector<SearchWindow> windows) {
    std::lock_guard lock(mutex_);
    stamp_ns_ = stamp_ns;
    windows_ = std::move(windows);
    ++received_;
  }
  // The windows if they were predicted within `max_age_ns` of `frame_stamp_ns`, else empty (a
  // full-frame search). `out` is reused so the loop does not allocate per frame.
  void fresh_for(TimeNs frame_stamp_ns, TimeNs max_age_ns, std::vector<SearchWindow>& out) const {
    std::lock_guard lock(mutex_);
    out.clear();
    if (received_ > 0 && std::llabs(frame_stamp_ns - stamp_ns_) <= max_age_ns) out = windows_;
  }

 private:
  mutable std::mutex mutex_;
  TimeNs stamp_ns_ = 0;
  std::uint64_t received_ = 0;
  std::vector<SearchWindow> windows_;
};

}  // namespace panoptes::camera
