// SPDX-License-Identifier: Apache-2.0
// Extrinsic (and optionally intrinsic and time-offset) calibration of many asynchronous cameras
// from a waved wand or light: pairwise essential matrices, global unification ranked by residual
// (seed 003 §3.3.1), metric scale from the wand (seed 000 §4.5.8), then one bundle adjustment
// over cameras, wand samples and clock offsets (docs/calibration.md explains why it replaces the
// EKF virtual-object iteration of seed 003 §3.3.2).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calib/bar_labels.h"
#include "panoptes/calib/wand.h"
#include "panoptes/calibration.h"

namespace panoptes::calib {

struct SolveOptions {
  bool refine_intrinsics = false;  // fx, fy, cx, cy and the five distortion terms per camera
  // Without refine_intrinsics, intrinsics are refined automatically: when a camera's intrinsics
  // are nominal (`nominal: true`) the focal length (fx, fy keeping their ratio), k1 and k2 of every
  // camera; when, after the first adjustment, the raw-frame error is far above any centroid noise
  // (median 2D error above intrinsics_suspect_px), fx, fy, cx, cy, k1 and k2. The tangential terms
  // and k3 stay as given. docs/calibration.md, "Intrinsics: what is automatic".
  bool auto_intrinsics = true;
  double intrinsics_suspect_px = 0.5;
  // A refined focal length more than this factor from the given one fails the camera: the given
  // intrinsics were wrong (wrong pixel pitch, lens or image size), not just imprecise.
  double max_focal_factor = 2.0;
  bool time_offsets = false;    // one clock offset per camera (the reference camera's is 0)
  double sample_rate_hz = 0.0;  // instants at which the wand is estimated; 0: fastest camera
  double max_gap_frames = 1.6;  // a track is interpolated only between frames this close
  int min_camera_frames = 20;   // identified wand frames a camera needs
  int min_pair_samples = 25;    // common samples for a pairwise relative pose
  int max_pair_samples = 400;   // subsampled for the five-point RANSAC
  double ransac_threshold_px = 1.0;
  double huber_px = 1.0;           // robust loss on reprojection residuals
  double length_sigma_m = 0.0005;  // weight of the wand-length residuals
  int max_iterations = 100;        // per bundle-adjustment pass
  int threads = 2;
  // Seed 003 §3.3.2 alternation (resect every camera on the triangulated trace, re-triangulate)
  // run for this many iterations instead of the joint bundle adjustment; 0: bundle adjustment.
  int alternation_iterations = 0;
  std::string reference_camera;  // gauge: its pose is the initial world frame; "" = best-connected
  std::function<void(const std::string&)> progress;  // long steps report here
};

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

struct LengthStats {
  int count = 0;  // samples triangulated with all markers seen by >= 2 cameras
  double mean_error_mm = 0, sigma_mm = 0, max_abs_error_mm = 0;
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
  // Whether every bundle-adjustment pass converged (Ceres CONVERGENCE), not stopped at the
  // iteration cap; `convergence` says which pass stopped and why.
  bool converged = false;
  std::string convergence;
  // Samples are the cameras' own frames (synchronised cameras: the same stamps), not interpolated.
  bool synchronised = false;
  LengthStats lengths;  // end-to-end length of the wand triangulated freely from the result
  // False for a single light: positions are in units of the first pair's baseline until `calibrate
  // world --lframe <x>,<y>` scales them (docs/calibration.md, "Single LED").
  bool metric = true;
  // For a wand whose ends look alike (a 2-marker bar): how the cameras' label runs were reconciled.
  std::optional<BarLabelReport> bar_labels;
  int iterations = 0;
  double seconds = 0;
  std::vector<std::string> errors;  // each names the cameras and the reason
  bool ok() const { return errors.empty(); }
  int calibrated_count() const;
};

// `cameras` supplies the intrinsics (T_world_cam ignored); `tracks` one per camera (matched by
// id; a camera without a track "never saw the wand"). For a wand whose ends look alike, the
// tracks' label runs are first reconciled across cameras (resolve_bar_labels, on a copy). Never
// throws on bad data: problems go to SolveResult::errors and the cameras' failure fields.
SolveResult solve_wand_calibration(const std::vector<CameraCalibration>& cameras,
                                   const std::vector<CameraWandTrack>& tracks, const WandDefinition& wand,
                                   const SolveOptions& options = {});

// Triangulates one point seen by calibrated cameras (panoptes/triangulation.h: linear, then
// Gauss-Newton on the pixel error). nullopt with fewer than two rays, (near) parallel rays or a
// point behind a camera.
std::optional<Eigen::Vector3d> triangulate(const std::vector<CameraModel>& models,
                                           const std::vector<Eigen::Vector2d>& pixels);

}  // namespace panoptes::calib
