// SPDX-License-Identifier: Apache-2.0
// The world frame of a calibration: z up, from the floor (markers or the wand laid on it), from an
// L-frame, or provisionally from the cameras' layout.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calib/wand.h"
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

// The calibration wand laid on the floor at several places (and/or slid along it) while recording
// (`calibrate world --wand-floor`, docs/calibration.md step 4c). Thresholds are metric: on an
// unscaled calibration they apply after the wand's known length has set the scale.
struct WandFloorOptions {
  double floor_offset_m = 0.0;       // marker centres above the floor (a marker's radius)
  int min_instants = 20;             // triangulated wand instants needed
  double sample_rate_hz = 0.0;       // instants; 0: the fastest camera's frame rate
  double max_gap_frames = 1.6;       // a track is interpolated only between frames this close
  double max_reprojection_px = 2.0;  // an instant whose markers miss a camera by more is dropped
  double rest_speed_m_s = 0.02;      // the wand rests while every marker moves slower
  double min_rest_s = 0.3;           // shortest rest that counts as a placement
  double inlier_m = 0.003;           // RANSAC: a marker this close to the plane is on the floor
  int ransac_iterations = 400;
  double rms_warning_m = 0.002;     // plane RMS above: the wand was not (always) on the floor
  double off_plane_error_m = 0.02;  // a resting placement this far off the plane: refused
  double spread_error_m = 0.10;     // second-largest spread (SD) of the floor points below: refused
  double spread_warning_m = 0.30;   // ... below: warned (the tilt is poorly defined)
  double length_tolerance = 0.03;   // an instant whose wand length is off the median by more is dropped
  IdentifyOptions identify;
};

// A place where the wand rested: marker means over the rest, in the new (world) frame.
struct WandPlacement {
  double start_s = 0, end_s = 0;  // after the first wand instant
  int instants = 0;
  std::vector<Eigen::Vector3d> markers;
  double height_mm = 0;  // mean signed distance of its markers from the fitted plane
};

struct WandFloorResult {
  std::optional<RigidTransform> T_new_old;  // set unless `error`
  double scale = 1.0;                       // metres per unit of the input calibration
  bool scaled_by_wand = false;              // the calibration was unscaled; the wand set `scale`
  std::vector<std::pair<std::string, int>> camera_frames;  // identified wand frames per camera
  int instants = 0;        // wand instants triangulated (all markers, >= 2 cameras, consistent)
  int floor_instants = 0;  // of those, all markers on the plane (RANSAC inliers)
  std::vector<WandPlacement> placements;
  double median_length_m = 0;   // measured first-to-last marker distance (after `scale`)
  double plane_rms_mm = 0;      // distances of the floor points and the resting markers
  double max_distance_mm = 0;   // the largest of those
  double tilt_deg = 0;          // angle between the old z and the new one
  double spread_m[2] = {0, 0};  // SD of the floor points along the plane's two axes
  std::vector<std::string> warnings;
  std::string error;  // "" on success; names the reason
};

// Identifies the wand in every calibrated camera's frames (extract_wand_track), pairs the cameras
// at common instants by interpolating their tracks, triangulates the markers, finds the rests,
// and fits the floor plane robustly (RANSAC, then least squares over the inliers). z = the plane's
// normal towards the cameras; origin = the first rest's first marker on the plane, lowered by
// `floor_offset_m`; x = the wand's direction at the first rest (first to last marker). For a wand
// whose ends look alike, "first" is the end nearer the middle of the room (the camera centres'
// mean, on the plane). `unscaled`: a single-light calibration; the wand's length sets the scale.
WandFloorResult wand_floor_frame(const SystemCalibration& calibration,
                                 const std::vector<FeatureFrame>& frames, const WandDefinition& wand,
                                 bool unscaled, const WandFloorOptions& options = {});

// The terminal/report lines: placements, instants, plane RMS, max distance, tilt, warnings.
std::string wand_floor_summary(const WandFloorResult& result);

}  // namespace panoptes::calib
