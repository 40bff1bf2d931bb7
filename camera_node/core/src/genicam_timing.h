// SPDX-License-Identifier: Apache-2.0
// GenICam timing features of an open Aravis camera: PTP (IEEE 1588), a hardware frame trigger and
// an exposure-active (strobe) output line (private to panoptes_camera; docs/camera_node.md, "PTP
// and hardware triggers"). Feature names follow the SFNC, with GigE Vision's older GevIEEE1588
// names for PTP.
#pragma once

#include <arv.h>

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "panoptes/camera/sources.h"

namespace panoptes::camera {

// A timing feature the camera lacks, refuses or does not keep; the message names the feature.
class GenicamTimingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct TimingApplied {
  bool ptp_timed = false;
  std::vector<std::pair<std::string, std::string>> features;  // read back after writing, in order
};

// Writes the PTP, trigger and strobe settings (each only when asked for) and reads every feature
// back. With PTP, waits up to settings.ptp_timeout_s for the PTP status to reach Slave or Master
// (when the camera has a status feature). Throws GenicamTimingError. Call before acquisition
// starts: cameras lock trigger features while acquiring.
TimingApplied apply_genicam_timing(ArvCamera* camera, const SourceSettings& settings);

// The camera's PTP status now (PtpStatus or GevIEEE1588Status, latched first when the camera has
// a latch command); "" when it has no status feature. Throws GenicamTimingError if it cannot be read.
std::string read_ptp_status(ArvCamera* camera);

// Whether a PTP status means the camera's clock follows (or is) the grandmaster.
inline bool ptp_locked(const std::string& status) {
  return status == "Slave" || status == "Master";
}

}  // namespace panoptes::camera
