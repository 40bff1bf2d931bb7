// SPDX-License-Identifier: Apache-2.0
// What the wand solver is asked to do (solve_wand_calibration, wand_solver.h); the bundle-adjustment
// stage reads its part of it (bundle_adjustment.h).
#pragma once

#include <functional>
#include <string>

namespace panoptes::calib {

struct SolveOptions {
  bool refine_intrinsics = false;  // fx, fy, cx, cy and the five distortion terms per camera
  // Without refine_intrinsics, intrinsics are refined automatically: when a camera's intrinsics
  // are nominal (`nominal: true`) the focal length (fx, fy keeping their ratio), k1 and k2 of every
  // camera; otherwise from evidence after the first adjustment with the given intrinsics: when the
  // raw-frame median 2D error is above intrinsics_noise_factor x what centroid_noise_px alone gives,
  // the groups (focal length, principal point, k1, k2) whose posterior 1-sigma is at most
  // intrinsics_determined_ratio of their prior (intrinsics_evidence.h) are refined, kept if the
  // residual sum falls by more than the information criterion asks, reverted if the residuals or the
  // raw-frame (validation) error get worse. The tangential terms and k3 stay as given.
  // docs/calibration.md, "Intrinsics: what is automatic" and "Intrinsics from evidence".
  bool auto_intrinsics = true;
  double centroid_noise_px = 0.2;  // per axis
  double intrinsics_noise_factor = 1.25;
  double intrinsics_determined_ratio = 0.5;
  // A refined focal length more than this factor from the given one fails the camera: the given
  // intrinsics were wrong (wrong pixel pitch, lens or image size), not just imprecise.
  double max_focal_factor = 2.0;
  // Above this |correlation| of a camera's refined focal length with its distance to the wand volume
  // the result warns: the data hardly tell a longer focal length from a camera further away
  // (solve_diagnostics.h, docs/calibration.md "Focal length and depth").
  double focal_depth_correlation_warning = 0.9;
  // Above this ratio of the free wand length's RMS error to the RMS the reprojection noise predicts
  // the result warns: the cameras measure lengths inconsistently (intrinsics that do not fit).
  double length_consistency_warning = 1.6;
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

}  // namespace panoptes::calib
