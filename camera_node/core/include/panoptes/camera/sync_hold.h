// SPDX-License-Identifier: Apache-2.0
// Hold-until-synced: feature frames wait until the node's clock is first synchronised with the
// time service, at most until a deadline (--clock-sync-wait); then their stamps are moved to the
// common time base (docs/camera_node.md, "Clock synchronisation"). If the time service has not
// answered by the deadline, frames go out with the node's own stamps (counted as unsynchronised)
// until it does. Without a clock-sync view (--no-clock-sync) frames pass as read.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <utility>

#include "panoptes/camera/node_clock.h"
#include "panoptes/camera/node_log.h"
#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes::camera {

class SyncHold {
 public:
  static constexpr std::size_t kHoldCapacity = 8192;  // frames; 16 s at 500 Hz

  // `sync` may be null; `log` receives the one warning when the hold times out unsynchronised.
  SyncHold(const ClockSyncView* sync, const NodeLog& log) : sync_(sync), log_(log) {}

  void set_deadline(TimeNs hold_until_wall_ns) { hold_until_wall_ns_ = hold_until_wall_ns; }

  // `frame` has its stamps on the node's clock. Emits it (and what was held) unless holding.
  // `emit(FeatureFrame&, const ClockEstimate*)` gets each frame with its stamps converted and the
  // estimate used (null when unsynchronised).
  template <class Emit>
  void add(FeatureFrame frame, TimeNs wall_now_ns, Emit&& emit) {
    held_.push_back(std::move(frame));
    if (holding(wall_now_ns)) {
      ++held_total_;
      if (held_.size() > kHoldCapacity) {
        held_.pop_front();
        ++hold_overflow_;
      }
      return;
    }
    release(false, wall_now_ns, emit);
  }

  // Emits what is held once synchronised, or once the hold has timed out (or `force`).
  template <class Emit>
  void release(bool force, TimeNs wall_now_ns, Emit&& emit) {
    if (held_.empty() || (!force && holding(wall_now_ns))) return;
    std::optional<ClockEstimate> estimate;
    if (sync_ != nullptr) {
      ClockEstimate current = sync_->estimate();
      if (current.synchronised) estimate = current;
    }
    if (sync_ != nullptr && !estimate && !warned_) {
      warned_ = true;
      log_(
          "no time service answered within the hold time; publishing the node's own stamps until one does "
          "(counted as unsynchronised)");
    }
    for (FeatureFrame& frame : held_) {
      if (estimate) {
        frame.stamp_ns = estimate->to_server(frame.stamp_ns);
        frame.arrival_ns = estimate->to_server(frame.arrival_ns);
      } else if (sync_ != nullptr) {
        ++unsynchronised_;
      }
      emit(frame, estimate ? &*estimate : nullptr);
    }
    held_.clear();
  }

  std::size_t held_now() const { return held_.size(); }
  std::uint64_t held_total() const { return held_total_; }
  std::uint64_t unsynchronised() const { return unsynchronised_; }
  std::uint64_t hold_overflow() const { return hold_overflow_; }
  bool warned() const { return warned_; }

 private:
  bool holding(TimeNs wall_now_ns) const {
    return sync_ != nullptr && !sync_->synchronised() && wall_now_ns < hold_until_wall_ns_;
  }

  const ClockSyncView* sync_;
  const NodeLog& log_;
  TimeNs hold_until_wall_ns_ = 0;
  std::deque<FeatureFrame> held_;
  std::uint64_t held_total_ = 0;
  std::uint64_t unsynchronised_ = 0;
  std::uint64_t hold_overflow_ = 0;
  bool warned_ = false;
};

}  // namespace panoptes::camera
