// SPDX-License-Identifier: Apache-2.0
// Conversions between the core records and the DDS message types.
#pragma once

#include <string>
#include <string_view>

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

// `moving`: the camera is carried by a rig (docs/inside_out.md); T_world_cam is then its mount.
msg::CameraInfo to_camera_info(const std::string& camera_id, const CameraIntrinsics& intrinsics,
                               const std::optional<RigidTransform>& T_world_cam, bool moving = false);
// A camera or client id worth keeping: 1..256 characters, none of them a control character.
bool plausible_id(const std::string& id);
// Why a CameraInfo cannot be trusted ("bad_camera_id", "image_size_out_of_range",
// "non_finite_calibration", "zero_quaternion"); "" if it can.
std::string_view camera_info_problem(const msg::CameraInfo& info);
// Calibration carried by a CameraInfo; nullopt if it has no intrinsics (fx == 0) or a problem.
std::optional<CameraCalibration> calibration_from(const msg::CameraInfo& info);
// The calibration in use as rt/panoptes/calibration carries it (every camera; has_pose false for
// intrinsics only).
msg::SystemCalibration to_message(const SystemCalibration& calibration, TimeNs stamp_ns);

}  // namespace panoptes::dds
