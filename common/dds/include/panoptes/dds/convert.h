// SPDX-License-Identifier: Apache-2.0
// Conversions between the core records and the DDS message types.
#pragma once

#include "panoptes/calibration.h"
#include "panoptes/records.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::dds {

msg::FeatureFrame to_message(const FeatureFrame& frame);
FeatureFrame from_message(const msg::FeatureFrame& message);

msg::Track to_message(const TrackRecord& track);
// The stamp comes from the enclosing TrackFrame.
TrackRecord from_message(const msg::Track& message, TimeNs stamp_ns);

msg::BodyPose to_message(const PoseRecord& pose);
PoseRecord from_message(const msg::BodyPose& message);

msg::CameraInfo to_camera_info(const std::string& camera_id, const CameraIntrinsics& intrinsics,
                               const std::optional<RigidTransform>& T_world_cam);
// Calibration carried by a CameraInfo; nullopt if it has no intrinsics (fx == 0).
std::optional<CameraCalibration> calibration_from(const msg::CameraInfo& info);

}  // namespace panoptes::dds
