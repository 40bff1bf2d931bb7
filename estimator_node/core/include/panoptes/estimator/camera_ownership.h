// SPDX-License-Identifier: Apache-2.0
// Which writer speaks for each camera id (docs/estimator.md, "Two writers for one camera"). The
// first writer to send a frame for an id owns it; a second writer claiming the same id is refused
// while the owner keeps sending, so its frames never reach the tracker (a second camera_node
// started as c0 with another camera's data made 69 ghost tracks, issue 34). An owner silent for
// longer than the hand-over time (a restarted camera node: its new writer has a new GUID) hands the
// id to the next writer that sends. Writers are opaque strings (the live node passes DDS writer
// GUIDs); times are wall times the caller passes in: no DDS and no clock here. Thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

#include "panoptes/time.h"

namespace panoptes::estimator {

class CameraOwnership {
 public:
  enum class Verdict {
    kOwner,       // the id's owner (or a first writer, which becomes it)
    kHandedOver,  // a new writer took over an id whose owner had gone silent
    kRefused,     // another writer owns the id and is still sending
  };
  struct Decision {
    Verdict verdict = Verdict::kOwner;
    bool first_refusal = false;  // kRefused: the first frame refused from this writer for this id
    std::string owner;           // the writer owning the id after the decision
  };

  explicit CameraOwnership(TimeNs handover_after_ns) : handover_after_ns_(handover_after_ns) {}

  // A frame for `camera_id` from `writer` arrived at `now_ns`. An empty writer (unknown) is
  // always accepted and does not claim the id.
  Decision claim(const std::string& camera_id, const std::string& writer, TimeNs now_ns);

  // The writer owning `camera_id` ("" if none).
  std::string owner(const std::string& camera_id) const;
  std::uint64_t refused_frames() const;

 private:
  struct Claim {
    std::string owner;
    TimeNs last_ns = 0;                     // the owner's last frame
    std::map<std::string, TimeNs> refused;  // writers refused for this id, at their first refusal
  };
  static constexpr std::size_t kMaxCameras = 1024;  // garbage ids must not grow the table
  static constexpr std::size_t kMaxRefusedPerCamera = 64;

  TimeNs handover_after_ns_;
  mutable std::mutex mutex_;
  std::map<std::string, Claim> claims_;
  std::uint64_t refused_frames_ = 0;
};

const char* to_string(CameraOwnership::Verdict verdict);

}  // namespace panoptes::estimator
