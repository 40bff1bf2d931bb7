// SPDX-License-Identifier: Apache-2.0
// One camera's pose again from world points the other cameras determine (issue 36 item 3,
// docs/continuous_calibration.md "Correction without a wand"): a bumped camera's blobs against the
// positions of confirmed tracks, every other camera held fixed (they fix the world frame). Maths
// only: no DDS, no files; the estimator collects the samples while the camera is quarantined.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/camera_model.h"
#include "panoptes/geometry.h"

namespace panoptes::estimator {

// One monitored frame of the camera: where the tracks the other cameras determine were at its
// stamp, and the blobs it saw. Which blob is which track is not known (a bump moves them all).
struct ResectionSample {
  std::vector<Eigen::Vector3d> points_world;
  std::vector<Eigen::Vector2d> blobs;  // px, as the camera reported them (distorted)
  // Per point, the weight of its residual (empty: all 1). Anchor markers, whose positions are
  // known and not estimated by the cameras being refined, weigh more (they hold the world frame).
  std::vector<double> weights;
};

struct ResectionOptions {
  // Association. A bump moves the image by nearly one shift (a turn about an axis in the image
  // plane); it is found by voting over every (blob - prediction) within vote_radius_px, in cells
  // of vote_cell_px. Then each prediction takes the nearest blob within associate_px, if the next
  // is unique_ratio times farther.
  double vote_radius_px = 250.0;
  double vote_cell_px = 4.0;
  double associate_px = 6.0;
  double unique_ratio = 2.0;
  // Gauss-Newton on the pose (rotation vector, translation) with a Huber loss, from the old pose;
  // rounds of association and adjustment, the association radius shrinking to inlier_px.
  double huber_px = 1.0;
  double inlier_px = 2.0;
  int rounds = 3;
  int iterations = 15;
  double converged = 1e-12;  // a step (rad, m) this small ends a round's iterations
  // > 0: a prior that the camera's centre stays where the old pose has it, with this 1-sigma (mm),
  // weighed against residuals of prior_pixel_sigma_px. A camera on a truss mostly turns; from a
  // narrow cloud of tracks a turn across the image and a shift across it look alike, and without
  // the prior a refined camera's centre wandered (walk8, every camera drifting).
  double centre_prior_mm = 0.0;
  double prior_pixel_sigma_px = 0.25;
  // Applied only when well determined: enough pairs, a small residual and a small uncertainty.
  std::size_t min_inliers = 40;
  double max_rms_px = 0.8;
  double max_rotation_sigma_deg = 0.02;
  double max_translation_sigma_mm = 2.0;
  // ... and plausible: a new pose that turns the camera by more than this or moves it by more is
  // not applied, and the reason says so (a wrong association, not a bump).
  double max_rotation_change_deg = 10.0;
  double max_translation_change_mm = 100.0;
};

struct ResectionResult {
  bool ok = false;
  std::string reason;          // why not (empty when ok)
  RigidTransform T_world_cam;  // the new pose (the old one when nothing could be solved)
  Eigen::Vector2d shift_px = Eigen::Vector2d::Zero();  // the voted image shift of the bump
  std::size_t candidates = 0;                          // predictions in the image, over every sample
  std::size_t inliers = 0;                             // pairs within inlier_px of the new pose's projection
  double rms_px = 0.0;                                 // of the inliers
  double rotation_sigma_deg = 0.0;
  double translation_sigma_mm = 0.0;
  double rotation_change_deg = 0.0;  // new pose against the old
  double translation_change_mm = 0.0;
};

// The camera's pose from `samples`, starting from `old_model`'s (its intrinsics are kept).
ResectionResult resect_camera(const CameraModel& old_model, const std::vector<ResectionSample>& samples,
                              const ResectionOptions& options = {});

}  // namespace panoptes::estimator
