// SPDX-License-Identifier: Apache-2.0
// A stop flag that wakes sleepers: how paced sources (sim, features) wait for a frame's wall-clock
// time and still end promptly on stop() (private to panoptes_camera).
#pragma once

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <mutex>

#include "panoptes/time.h"

namespace panoptes::camera {

class StopSignal {
 public:
  void stop() {
    {
      std::lock_guard lock(mutex_);
      stopped_ = true;
    }
    wake_.notify_all();
  }

  bool stopped() const {
    std::lock_guard lock(mutex_);
    return stopped_;
  }

  // Sleeps until the wall clock reaches `target_ns`; false if stop() came first.
  bool sleep_until_wall(TimeNs target_ns) {
    // Sleeping in slices keeps a missed notification or a wall-clock step from stranding a stop.
    constexpr TimeNs kMaxSliceNs = 10 * kNsPerMillisecond;
    std::unique_lock lock(mutex_);
    while (!stopped_) {
      const TimeNs remaining = target_ns - wall_now_ns();
      if (remaining <= 0) return true;
      wake_.wait_for(lock, std::chrono::nanoseconds(std::min(remaining, kMaxSliceNs)));
    }
    return false;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopped_ = false;
};

}  // namespace panoptes::camera
