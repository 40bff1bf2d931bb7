// SPDX-License-Identifier: Apache-2.0
// Inside-out mode of the estimator (docs/inside_out.md, issue 21 item 3): cameras marked
// `moving: true` in the calibration are carried by a rig (a headset); each one's frames go to its
// own InsideOutTracker (estimator core) instead of the point tracker, and the rig's pose is
// published like a body's (rt/panoptes/bodies, Pose JSONL) under the rig's name (calibration
// `rig:`, else the camera id). The landmarks come from a landmarks file (landmarks_file.h).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/estimator/inside_out.h"
#include "panoptes/estimator/tracker.h"
#include "panoptes/landmarks_file.h"
#include "panoptes/records.h"

namespace panoptes::session {

struct InsideOutSettings {
  estimator::InsideOutOptions tracker;
  // A cold start tries every blob triple: it uses at most this many blobs, the brightest, so a
  // frame full of clutter cannot stall the estimator (the cost grows with the cube).
  std::size_t acquire_max_blobs = 16;
};

class InsideOutCameras {
 public:
  // One tracker per moving camera, all sharing `landmarks`. Throws ConfigError naming
  // `landmarks_file` and the constellation it cannot use.
  void configure(const std::vector<LandmarkGroup>& landmarks, const std::vector<CameraCalibration>& moving,
                 const std::string& landmarks_file, const InsideOutSettings& settings = {});

  // Fusion (docs/inside_out.md): fixed cameras (`fixed`, with T_world_cam) that see markers carried
  // by a rig (`rig_markers`, rig frame, by rig name) update that rig's filter too. Throws
  // ConfigError naming `landmarks_file` for markers of a rig that no moving camera carries.
  void set_outside_in(const SystemCalibration& fixed, const RigMarkers& rig_markers,
                      const std::string& landmarks_file);
  // A fixed camera's frame (the point tracker has it too): each rig with markers updates from it.
  void observe_fixed(const FeatureFrame& frame);

  bool empty() const { return rigs_.empty(); }
  bool handles(const std::string& camera_id) const { return rigs_.count(camera_id) > 0; }
  // A frame of a moving camera (handles() is true): its rig's tracker update. kTooLate for a frame
  // older than its tracker's state (dropped, counted).
  estimator::FrameOutcome process(const FeatureFrame& frame);

  // The newest frame stamp of any moving camera (0 before).
  TimeNs last_stamp_ns() const { return last_stamp_ns_; }
  // Every tracking rig's pose, its filter predicted to `stamp_ns` and extrapolated `horizon_ns`.
  std::vector<PoseRecord> poses_at(TimeNs stamp_ns, TimeNs horizon_ns) const;
  // Every rig once, by name, with the markers it carries (rig frame; none without fusion): what
  // rt/panoptes/body_descriptions lists as kind "rig" so that clients learn the rigs' names.
  std::vector<BodyDefinition> rig_descriptions() const;
  // What became of each moving camera's frames, counted like the point tracker's cameras (usage,
  // utilisation): used = given to the filter; too_late = older than its state (dropped);
  // associated = landmark updates.
  const std::map<std::string, estimator::CameraCounters>& camera_counters() const { return counters_; }
  // One line per rig: frames, acquisitions, landmark updates, losses (run summaries).
  std::vector<std::string> summary_lines() const;

 private:
  struct Rig {
    std::string name;
    estimator::InsideOutTracker tracker;
    std::vector<Eigen::Vector3d> markers;  // carried, rig frame (fusion)
  };
  std::map<std::string, Rig> rigs_;                            // by camera id
  std::map<std::string, estimator::CameraCounters> counters_;  // by camera id
  std::map<std::string, CameraModel> fixed_cameras_;           // by camera id, when a rig carries markers
  InsideOutSettings settings_;
  TimeNs last_stamp_ns_ = 0;
};

// Moves the cameras marked `moving: true` out of `calibration` (the point tracker must not take
// their mount for a fixed pose) and returns them.
std::vector<CameraCalibration> take_moving_cameras(SystemCalibration& calibration);

// estimator_node's inside-out set-up: takes the moving cameras out of `calibration` (read from
// `calibration_file`) and gives them `cameras` with the landmarks of `landmarks_file` (empty: none
// given). Throws ConfigError naming the file and the camera or entry: a moving camera without
// landmarks, a missing or bad landmarks file. Logs what it set up.
void set_up_inside_out(InsideOutCameras& cameras, SystemCalibration& calibration,
                       const std::string& calibration_file, const std::string& landmarks_file);

}  // namespace panoptes::session
