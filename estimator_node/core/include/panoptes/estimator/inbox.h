// SPDX-License-Identifier: Apache-2.0
// Time-ordered inbox for live mode (seed 003 §2.2.4.2): frames from all cameras wait until their
// stamp is older than the latency window, then leave in stamp order. Bounded; drops counted.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <vector>

#include "panoptes/records.h"

namespace panoptes::estimator {

class FrameInbox {
 public:
  FrameInbox(std::size_t capacity, TimeNs latency_window_ns);

  // Called from DDS listener threads. Returns false if the inbox was full (the oldest frame is
  // dropped to make room, and counted).
  bool push(FeatureFrame frame);
  // Frames with stamp <= now - window, oldest first.
  std::vector<FeatureFrame> pop_due(TimeNs now_ns);
  // Whether pop_due(now_ns) would return a frame: the live loop lets a waiting frame go before the
  // less urgent output of the frames it has processed.
  bool has_due(TimeNs now_ns) const;
  // Everything, oldest first (shutdown).
  std::vector<FeatureFrame> drain();
  // Blocks until a frame is pushed, the oldest frame falls due (on the clock `now_ns` is read
  // from), or `max_wait` has passed: a live loop wakes as frames arrive instead of polling.
  void wait(TimeNs now_ns, std::chrono::nanoseconds max_wait);

  // When the oldest waiting frame falls due (its stamp + the window); none when empty.
  std::optional<TimeNs> next_due_ns() const;

  TimeNs latency_window_ns() const { return window_ns_; }
  std::uint64_t drops() const;
  std::size_t size() const;

 private:
  const std::size_t capacity_;
  const TimeNs window_ns_;
  mutable std::mutex mutex_;
  std::vector<FeatureFrame> heap_;  // min-heap on stamp_ns
  std::uint64_t drops_ = 0;
  std::uint64_t pushes_ = 0;
  std::condition_variable pushed_;
};

}  // namespace panoptes::estimator
