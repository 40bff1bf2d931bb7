// SPDX-License-Identifier: Apache-2.0
// The node's own clock and the stamp correction that moves its stamps to the common time base
// (docs/camera_node.md, "Clock synchronisation").
#pragma once

#include <optional>
#include <string>

#include "panoptes/clock_sync.h"
#include "panoptes/time.h"

namespace panoptes::camera {

// --clock-skew "<offset_ms>,<drift_ppm>", a testing aid.
struct ClockSkew {
  TimeNs offset_ns = 0;
  double drift_ppm = 0;
};

// Parses "<offset_ms>,<drift_ppm>" ("" = no skew). Throws std::invalid_argument with a message
// naming the option, the text and what is wrong.
ClockSkew parse_clock_skew(const std::string& text);

// The node's own clock, on which its stamps are read and which the time-sync client measures.
// Normally the host's wall clock. A sim camera's scene `clock_offset` is part of it (that camera's
// stamps carry the offset), and --clock-skew makes it run off by offset + drift · (wall − start).
// Everything the node stamps is read on this clock, so one correction fixes all of it. With no
// offset and no skew it is the identity on wall-clock stamps (the offline mode).
class NodeClock {
 public:
  NodeClock() = default;
  NodeClock(TimeNs start_wall_ns, TimeNs source_offset_ns, ClockSkew skew)
      : start_wall_ns_(start_wall_ns),
        source_offset_ns_(source_offset_ns),
        skew_offset_ns_(skew.offset_ns),
        skew_drift_(skew.drift_ppm * 1e-6) {}

  TimeNs now() const { return from_wall(wall_now_ns()); }
  TimeNs from_wall(TimeNs wall_ns) const { return wall_ns + source_offset_ns_ + skew(wall_ns); }
  // A stamp delivered by the source (the wall clock plus the source's own offset).
  TimeNs from_source(TimeNs stamp_ns) const { return stamp_ns + skew(stamp_ns - source_offset_ns_); }

  bool skewed() const { return skew_offset_ns_ != 0 || skew_drift_ != 0; }
  double drift_ppm() const { return skew_drift_ * 1e6; }

 private:
  TimeNs skew(TimeNs wall_ns) const;

  TimeNs start_wall_ns_ = 0;
  TimeNs source_offset_ns_ = 0;
  TimeNs skew_offset_ns_ = 0;
  double skew_drift_ = 0;
};

// The scene's `clock_offset` of a sim:<scene>#<camera> source (0 for any other source). Throws
// ConfigError if the scene file is bad.
TimeNs source_clock_offset_ns(const std::string& spec);

// What the stamp correction needs to know about the clock synchronisation (the live node adapts
// its time-sync client to it; unit tests use a fake).
class ClockSyncView {
 public:
  virtual ~ClockSyncView() = default;
  virtual bool synchronised() const = 0;
  virtual ClockEstimate estimate() const = 0;
  // The common time of a local stamp; nullopt until synchronised.
  virtual std::optional<TimeNs> to_server(TimeNs local_ns) const = 0;
};

// Stamps on the node's clock, and their common time once synchronised. Without a clock-sync view
// (--no-clock-sync, offline) local stamps are taken as common ones.
class StampCorrection {
 public:
  StampCorrection(const NodeClock& clock, const ClockSyncView* sync) : clock_(clock), sync_(sync) {}
  const NodeClock& clock() const { return clock_; }
  const ClockSyncView* sync() const { return sync_; }
  // A local stamp on the common time base (unchanged while not synchronised).
  TimeNs to_common(TimeNs local_ns) const {
    if (sync_ == nullptr) return local_ns;
    return sync_->to_server(local_ns).value_or(local_ns);
  }

 private:
  const NodeClock& clock_;
  const ClockSyncView* sync_;
};

}  // namespace panoptes::camera
