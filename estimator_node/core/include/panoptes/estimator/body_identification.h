// SPDX-License-Identifier: Apache-2.0
// Rigid-body identification from unlabelled 3D points (seed 000 §6.1.6, generalised): an
// association graph whose nodes pair a measured point with a model marker and whose edges join
// two pairs when the measured and the model distance agree within a tolerance; the largest
// clique (≥ 3 pairs) is the identification, and Kabsch/Umeyama (panoptes/rigid_fit.h) gives the pose.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calibration.h"
#include "panoptes/geometry.h"

namespace panoptes::estimator {

struct IdentificationOptions {
  double tolerance_floor_m = 0.002;  // distances agree within floor + sigmas·σ(distance)
  double tolerance_sigmas = 4.0;
  double max_rms_m = 0.003;  // the fitted pose must explain the points this well
  int min_markers = 3;
  std::size_t max_points = 256;           // points offered beyond this are ignored
  std::size_t max_clique_steps = 200000;  // bound on the clique search
};

struct MeasuredPoint {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  double sigma_m = 0.0;  // 1-σ position uncertainty (isotropic)
};

struct BodyMatch {
  std::vector<std::pair<int, int>> pairs;  // (point index, marker index), by marker
  RigidTransform T_world_body;
  double rms_m = 0.0;
};

// Best identification of `markers` (body frame) among `points`: the most markers, then the lowest
// RMS. nullopt if fewer than min_markers match.
std::optional<BodyMatch> identify_body(const std::vector<Eigen::Vector3d>& markers,
                                       const std::vector<MeasuredPoint>& points,
                                       const IdentificationOptions& options = {});

// Throws ConfigError naming the body: fewer than 3 markers, non-finite, coincident (closer than
// 1 mm) or all collinear markers. Duplicate names are rejected when the file is read.
void validate_body(const BodyDefinition& body, const std::string& file_for_errors = "bodies");

// Human-readable warnings for bodies that identification cannot tell apart: two bodies of which
// ≥ 3 markers have the same distances within the tolerance (so those markers alone are ambiguous;
// "cannot be told apart" when every marker of the smaller one matches).
std::vector<std::string> distinguishability_warnings(const std::vector<BodyDefinition>& bodies,
                                                     const IdentificationOptions& options = {});

}  // namespace panoptes::estimator
