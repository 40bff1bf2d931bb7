// SPDX-License-Identifier: Apache-2.0
// The small summaries the wand solver's stages hand on to its result: a camera pair's two-view
// figures (two_view.h), reprojection-error statistics (bundle_adjustment.h), the wand's length
// check (solve_finish.h). docs/calibration.md, "Stages".
#pragma once

#include <string>

namespace panoptes::calib {

struct PairEdge {
  std::string camera_a, camera_b;
  int samples = 0;
  int inliers = 0;
  double residual_px = 0;  // RMS reprojection of the two-view reconstruction
  double scale = 0;        // metres per unit baseline (0 without a metric wand)
  bool used = false;       // became part of the spanning unification
};

// Statistics of reprojection errors (2D norm, pixels).
struct ErrorStats {
  int count = 0;
  double mean_px = 0, median_px = 0;
  double rms_axis_px = 0;  // RMS per image axis (comparable with a centroid noise sigma)
  double within_5px = 0;   // share of the observations within 5 px
};

// Raw frames are inliers within this 2D error of the solved path (px).
inline constexpr double kRawInlierPx = 5.0;

struct LengthStats {
  int count = 0;  // samples triangulated with all markers seen by >= 2 cameras
  double mean_error_mm = 0, sigma_mm = 0, max_abs_error_mm = 0;
  double median_error_mm = 0, rms_error_mm = 0;
};

// How well the final adjustment separates a camera's focal length from its distance to the wand
// volume (the centroid of the adjusted wand markers): from the adjustment's normal equations at the
// solution, the reprojection residuals weighted by their own RMS (solve_diagnostics.h,
// docs/calibration.md "Focal length and depth").
struct FocalDepthStats {
  bool available = false;        // the camera took part in the adjustment
  bool focal_free = false;       // its focal length was refined (else correlation is 0)
  double depth_m = 0;            // distance from the camera centre to the wand volume's centre
  double depth_sigma_mm = 0;     // 1-sigma of that distance
  double position_sigma_mm = 0;  // 1-sigma of the camera centre (3D) relative to the volume's centre
  double focal_sigma_px = 0;     // 1-sigma of the focal length
  double correlation = 0;        // focal length against depth, -1..1
  // What the ambiguity costs: a focal length 1% off, everything else re-fitted, moves the camera
  // this far along the depth and raises the reprojection RMS (per axis) by this much.
  double shift_per_percent_mm = 0;
  double rms_increase_per_percent_px = 0;
};

}  // namespace panoptes::calib
