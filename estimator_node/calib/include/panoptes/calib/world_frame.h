// SPDX-License-Identifier: Apache-2.0
// The world frame of a calibration: z up, from the floor (markers or the wand laid on it), from an
// L-frame, or provisionally from the cameras' layout.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calibration.h"
#include "panoptes/geometry.h"
#include "panoptes/records.h"

namespace panoptes::calib {

struct SolveResult;

// Provisional frame right after a wand solve (no floor known yet): z is the normal of the plane
// through the camera centres, pointing away from where the cameras look (cameras look down);
// the origin is below the centroid of the wand samples at the height of the lowest 2% of them;
// x points towards the first camera. Returns T_new_old.
RigidTransform provisional_world_frame(const std::vector<RigidTransform>& T_world_cam,
                                       const std::vector<Eigen::Vector3d>& points);

// Maps every pose and point of `result` by T_new_old.
void apply_world_transform(SolveResult& result, const RigidTransform& T_new_old);
// Maps every camera pose by T_new_old, then scales positions by `scale` (metres per unit of an
// unscaled calibration; 1 keeps it rigid): p_new = scale * T_new_old(p_old).
void apply_world_transform(SystemCalibration& calibration, const RigidTransform& T_new_old,
                           double scale = 1.0);

// Plane fit (least squares) to >= 3 points on the floor: z = the plane's normal oriented towards
// `up_hint` (e.g. the mean camera centre), origin = the points' centroid on the plane, x = the
// direction from the first point to the second, projected onto the plane. T_new_old.
std::optional<RigidTransform> floor_frame(const std::vector<Eigen::Vector3d>& floor_points,
                                          const Eigen::Vector3d& up_hint, std::string* error = nullptr);

// An L-frame of three markers: the corner (origin), one on the x arm, one on the y arm; identified
// among `points` by the right angle and, if given, the arm lengths (the longer arm is x when the
// lengths are not given). z = x × y, which must point towards `up_hint`. T_new_old.
// With `scale` (an unscaled single-light calibration, docs/calibration.md "Single LED"), the arm
// lengths (required) are matched by their ratio and `*scale` receives metres per unit of `points`:
// the least-squares fit of the two measured arms to the given ones.
std::optional<RigidTransform> lframe_frame(const std::vector<Eigen::Vector3d>& points,
                                           const Eigen::Vector3d& up_hint, double x_arm_m = 0,
                                           double y_arm_m = 0, std::string* error = nullptr,
                                           double* scale = nullptr);

// Static markers seen by calibrated cameras over a short recording: per camera the blobs are
// averaged over the frames (clustered within `cluster_px`), matched across cameras by
// triangulation and reprojection, and triangulated. Returns world points seen by >= 2 cameras.
std::vector<Eigen::Vector3d> triangulate_static_markers(const SystemCalibration& calibration,
                                                        const std::vector<FeatureFrame>& frames,
                                                        double cluster_px = 3.0, double match_px = 3.0);

}  // namespace panoptes::calib
