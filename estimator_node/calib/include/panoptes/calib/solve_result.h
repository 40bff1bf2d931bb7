// SPDX-License-Identifier: Apache-2.0
// The wand solver's result (solve_wand_calibration, wand_solver.h), completed by its last stage
// (finish_solution, solve_finish.h): the cameras, the wand path and residuals, and the figures
// that judge the solution.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calib/bar_labels.h"
#include "panoptes/calib/solve_stats.h"
#include "panoptes/calib/wand.h"
#include "panoptes/calibration.h"
#include "panoptes/time.h"

namespace panoptes::calib {

struct CameraResult {
  std::string id;
  CameraIntrinsics intrinsics;                // refined if asked
  std::optional<RigidTransform> T_world_cam;  // absent: not calibrated (see failure)
  std::string failure;                        // why it could not be calibrated; "" if calibrated
  double time_offset_s = 0;                   // camera clock minus reference clock
  int wand_frames = 0;                        // identified frames
  int observations = 0;                       // marker observations in the final adjustment
  double rms_px = 0;                          // reprojection RMS of those (2D norm, OpenCV's convention)
  double max_px = 0;
  // The raw frames (not interpolated) against the estimated wand path at their own instants, RMS
  // per image axis: comparable with the centroid noise of the camera.
  int raw_observations = 0;
  double raw_rms_axis_px = 0;
  // The same raw frames as 2D errors: every frame, and the inliers (within kRawInlierPx).
  ErrorStats raw_all, raw_inliers;
  bool intrinsics_refined = false;
  CameraIntrinsics given_intrinsics;  // as the cameras file gave them
  IdentifyCounters counters;
  FocalDepthStats focal_depth;  // focal length against depth (solve_diagnostics.h)
};

// A wand sample as finally estimated: marker positions in the world.
struct WandSample {
  TimeNs t_ns = 0;
  std::vector<Eigen::Vector3d> markers;
  int cameras = 0;
};

// One reprojection residual of the final solution, for reports and plots.
struct Residual {
  int camera = 0;  // index into SolveResult::cameras
  int marker = 0;  // index along the wand
  TimeNs t_ns = 0;
  Eigen::Vector2d observed = Eigen::Vector2d::Zero();  // pixel
  Eigen::Vector2d error = Eigen::Vector2d::Zero();     // projected - observed, px
};

struct SolveResult {
  std::vector<CameraResult> cameras;  // in input order
  std::vector<PairEdge> edges;
  std::vector<WandSample> samples;
  std::vector<Residual> residuals;
  std::string reference_camera;
  double rms_px = 0;           // all cameras, 2D norm
  double raw_rms_axis_px = 0;  // all cameras, raw frames, per axis
  // The headline: raw frames (not interpolated) against the solved path at their own instants,
  // 2D error in pixels, over every raw frame and over the inliers (within kRawInlierPx).
  ErrorStats raw_all, raw_inliers;
  // Whether intrinsics were refined and why ("" if not): "--refine-intrinsics", "nominal
  // intrinsics (cam0, cam1)" or "raw-frame error ... after the first adjustment".
  std::string intrinsics_refined;
  // Why the intrinsics were kept as given although the evidence step looked at them ("" if it did
  // not): at the noise, nothing determined, not worth its parameters, or reverted (worse).
  std::string intrinsics_declined;
  // Whether every bundle-adjustment pass converged (Ceres CONVERGENCE), not stopped at the
  // iteration cap; `convergence` says which pass stopped and why.
  bool converged = false;
  std::string convergence;
  // Samples are the cameras' own frames (synchronised cameras: the same stamps), not interpolated.
  bool synchronised = false;
  LengthStats lengths;  // end-to-end length of the wand triangulated freely from the result
  // The RMS of `lengths` the reprojection noise alone predicts (solve_diagnostics.h), mm; 0: unknown.
  double predicted_length_rms_mm = 0;
  // False for a single light: positions are in units of the first pair's baseline until `calibrate
  // world --lframe <x>,<y>` scales them (docs/calibration.md, "Single LED").
  bool metric = true;
  // For a wand whose ends look alike (a 2-marker bar): how the cameras' label runs were reconciled.
  std::optional<BarLabelReport> bar_labels;
  int iterations = 0;
  double seconds = 0;
  // Figures that call the result into doubt although it was solved (focal length and depth not
  // separated, solve_diagnostics.h): each names the camera and says what to do.
  std::vector<std::string> warnings;
  std::vector<std::string> errors;  // each names the cameras and the reason
  bool ok() const { return errors.empty(); }
  int calibrated_count() const;
};

}  // namespace panoptes::calib
