// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/solve_diagnostics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>

namespace panoptes::calib {

namespace {

// The camera centre in the world from T_cam_world (angle-axis, translation): C = -R^T t.
Eigen::Vector3d camera_centre(const std::array<double, 6>& pose) {
  CameraParameters camera;
  camera.pose = pose;
  return T_world_cam_of(camera).t;
}

// dC/d(pose), 3 x 6, by central differences (the pose block's own parameters: no manifold).
Eigen::Matrix<double, 3, 6> centre_jacobian(const std::array<double, 6>& pose) {
  Eigen::Matrix<double, 3, 6> jacobian;
  for (int i = 0; i < 6; ++i) {
    const double step = 1e-7;
    std::array<double, 6> plus = pose, minus = pose;
    plus[static_cast<std::size_t>(i)] += step;
    minus[static_cast<std::size_t>(i)] -= step;
    jacobian.col(i) = (camera_centre(plus) - camera_centre(minus)) / (2 * step);
  }
  return jacobian;
}

// The covariance's factor: the normal equations of the reprojection rows weighted by their own RMS
// per axis, plus the (already weighted) constraint rows. A tiny damping keeps a direction the data
// do not determine at all (--refine-intrinsics' p1, p2 against cx, cy) from breaking the factorisation.
struct Information {
  Eigen::SparseMatrix<double> normal;  // J_r^T J_r, unweighted
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor;
  double sigma_px = 0;  // reprojection RMS per axis
  double squared_sum = 0;
  int rows = 0;
  bool ok = false;
};

void factorise(const AdjustmentJacobian& jacobian, Information& out) {
  out.rows = static_cast<int>(jacobian.reprojection_residuals.size());
  if (out.rows == 0 || jacobian.columns == 0) return;
  out.squared_sum = jacobian.reprojection_residuals.squaredNorm();
  out.sigma_px = std::sqrt(out.squared_sum / out.rows);
  const double weight = 1.0 / std::max(1e-6, out.sigma_px * out.sigma_px);
  out.normal = jacobian.reprojection.transpose() * jacobian.reprojection;
  Eigen::SparseMatrix<double> H = weight * out.normal;
  if (jacobian.constraints.rows() > 0)
    H += Eigen::SparseMatrix<double>(jacobian.constraints.transpose() * jacobian.constraints);
  const double damping = 1e-12 * H.diagonal().maxCoeff();
  for (int i = 0; i < H.rows(); ++i) H.coeffRef(i, i) += damping;
  out.factor.compute(H);
  out.ok = out.factor.info() == Eigen::Success;
}

// Gradients (one column each) of the camera centre's x, y, z relative to the wand volume's centre,
// and of the mean focal length, over the Jacobian's columns.
Eigen::MatrixXd gradients(const BundleState& state, const AdjustmentJacobian& jacobian, std::size_t c,
                          std::size_t markers) {
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(jacobian.columns, 4);
  const auto& columns = jacobian.cameras[c];
  if (columns.pose >= 0) g.block(columns.pose, 0, 6, 3) = centre_jacobian(state.cameras[c].pose).transpose();
  int adjusted = 0;
  for (const int first : jacobian.instant_columns) adjusted += first >= 0 ? 1 : 0;
  const double share = 1.0 / std::max(1, adjusted * static_cast<int>(markers));
  for (const int first : jacobian.instant_columns) {
    if (first < 0) continue;
    for (std::size_t m = 0; m < markers; ++m)
      for (int k = 0; k < 3; ++k) g(first + static_cast<int>(m) * 3 + k, k) = -share;
  }
  if (columns.intrinsics < 0) return g;
  const auto& k = state.cameras[c].intrinsics;
  const bool evidence = jacobian.refinement == IntrinsicsRefinement::kEvidence;
  if (evidence && (c >= jacobian.free_intrinsics.size() || (jacobian.free_intrinsics[c] & kFreeFocal) == 0U))
    return g;  // the focal length stayed as given
  if (jacobian.refinement == IntrinsicsRefinement::kNominal || evidence) {
    g(columns.intrinsics, 3) = 0.5 * (1.0 + k[1] / k[0]);  // fx and fy move together
  } else {
    g(columns.intrinsics, 3) = 0.5;
    g(columns.intrinsics + 1, 3) = 0.5;
  }
  return g;
}

Eigen::Vector3d volume_centre(const BundleState& state, const AdjustmentJacobian& jacobian,
                              std::size_t markers) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (std::size_t s = 0; s < jacobian.instant_columns.size(); ++s) {
    if (jacobian.instant_columns[s] < 0) continue;
    for (std::size_t m = 0; m < markers; ++m) sum += Eigen::Vector3d(&state.points[(s * markers + m) * 3]);
    count += static_cast<int>(markers);
  }
  return count > 0 ? Eigen::Vector3d(sum / count) : sum;
}

FocalDepthStats camera_stats(const BundleState& state, const AdjustmentJacobian& jacobian,
                             const Information& information, const Eigen::Vector3d& centre, std::size_t c,
                             std::size_t markers) {
  FocalDepthStats stats;
  stats.available = true;
  const Eigen::MatrixXd g = gradients(state, jacobian, c, markers);
  const Eigen::MatrixXd covariance = g.transpose() * information.factor.solve(g);  // 4 x 4
  const Eigen::Vector3d v = camera_centre(state.cameras[c].pose) - centre;
  stats.depth_m = v.norm();
  const Eigen::Vector3d u = v / std::max(1e-12, stats.depth_m);
  const double depth_variance = std::max(0.0, u.dot(covariance.topLeftCorner<3, 3>() * u));
  stats.depth_sigma_mm = std::sqrt(depth_variance) * 1e3;
  stats.position_sigma_mm = std::sqrt(std::max(0.0, covariance.topLeftCorner<3, 3>().trace())) * 1e3;
  stats.focal_free = jacobian.cameras[c].intrinsics >= 0;
  if (!stats.focal_free || covariance(3, 3) <= 0 || depth_variance <= 0) return stats;
  const double focal_variance = covariance(3, 3);
  const double cross = u.dot(covariance.block<3, 1>(0, 3));
  stats.focal_sigma_px = std::sqrt(focal_variance);
  stats.correlation = std::clamp(cross / std::sqrt(depth_variance * focal_variance), -1.0, 1.0);
  // 1% of the focal length imposed, the rest re-fitted: the conditional mean shift of the depth,
  // and the rise of the residual sum (delta^2 / variance in units of the weighted sum).
  const double delta = 0.005 * (state.cameras[c].intrinsics[0] + state.cameras[c].intrinsics[1]);
  stats.shift_per_percent_mm = cross / focal_variance * delta * 1e3;
  const double added = information.sigma_px * information.sigma_px * delta * delta / focal_variance;
  stats.rms_increase_per_percent_px =
      std::sqrt((information.squared_sum + added) / information.rows) - information.sigma_px;
  return stats;
}

// Each adjusted instant's end-to-end length error that the reprojection noise alone gives, the
// cameras held fixed: var = u^T (S_first + S_last) u, S a marker's 3x3 covariance from its own rows.
double predicted_length_rms_mm(const BundleState& state, const AdjustmentJacobian& jacobian,
                               const Information& information, std::size_t markers) {
  if (markers < 2 || information.sigma_px <= 0) return 0;
  const Eigen::SparseMatrix<double>& normal = information.normal;
  const auto block = [&](int first) {
    Eigen::Matrix3d h;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) h(i, j) = normal.coeff(first + i, first + j);
    return h;
  };
  double sum = 0;
  int count = 0;
  const int last = 3 * (static_cast<int>(markers) - 1);
  for (std::size_t s = 0; s < jacobian.instant_columns.size(); ++s) {
    const int first = jacobian.instant_columns[s];
    if (first < 0) continue;
    const Eigen::Vector3d a(&state.points[s * markers * 3]);
    const Eigen::Vector3d b(&state.points[(s * markers + markers - 1) * 3]);
    const Eigen::Vector3d u = (b - a).normalized();
    const Eigen::Matrix3d h_a = block(first), h_b = block(first + last);
    if (h_a.determinant() <= 0 || h_b.determinant() <= 0) continue;
    sum += u.dot((h_a.inverse() + h_b.inverse()) * u);
    ++count;
  }
  if (count == 0) return 0;
  return information.sigma_px * std::sqrt(sum / count) * 1e3;
}

}  // namespace

SolveDiagnostics solve_diagnostics(const BundleState& state, const WandDefinition& wand,
                                   const PassOptions& options) {
  SolveDiagnostics out;
  out.cameras.resize(state.cameras.size());
  const AdjustmentJacobian jacobian = adjustment_jacobian(state, wand, options);
  Information information;
  factorise(jacobian, information);
  if (!information.ok) return out;
  out.reprojection_rms_axis_px = information.sigma_px;
  const std::size_t markers = wand.marker_count();
  out.predicted_length_rms_mm = predicted_length_rms_mm(state, jacobian, information, markers);
  const Eigen::Vector3d centre = volume_centre(state, jacobian, markers);
  for (std::size_t c = 0; c < state.cameras.size(); ++c) {
    const auto& columns = jacobian.cameras[c];
    const bool adjusted = columns.pose >= 0 || columns.intrinsics >= 0 || columns.offset >= 0 ||
                          static_cast<int>(c) == options.reference;
    if (state.cameras[c].registered && adjusted)
      out.cameras[c] = camera_stats(state, jacobian, information, centre, c, markers);
  }
  return out;
}

IntrinsicsPosterior intrinsics_posterior(const BundleState& state, const WandDefinition& wand,
                                         const PassOptions& options) {
  IntrinsicsPosterior out;
  out.sigma.resize(state.cameras.size());
  const AdjustmentJacobian jacobian = adjustment_jacobian(state, wand, options);
  Information information;
  factorise(jacobian, information);
  if (!information.ok) return out;
  out.ok = true;
  out.rms_axis_px = information.sigma_px;
  for (std::size_t c = 0; c < state.cameras.size(); ++c) {
    const int first = jacobian.cameras[c].intrinsics;
    if (first < 0) continue;
    const unsigned free = c < options.free_intrinsics.size() ? options.free_intrinsics[c] : 0U;
    const int next = first + evidence_tangent_size(free);
    for (int k = first; k < next; ++k) {
      Eigen::VectorXd unit = Eigen::VectorXd::Zero(jacobian.columns);
      unit(k) = 1.0;
      out.sigma[c].push_back(std::sqrt(std::max(0.0, information.factor.solve(unit)(k))));
    }
  }
  return out;
}

std::vector<std::string> solve_warnings(const SolveResult& result, const SolveOptions& options) {
  std::vector<std::string> warnings;
  const CameraResult* weakest = nullptr;  // the largest depth shift per 1% of focal length
  for (const auto& camera : result.cameras) {
    const auto& stats = camera.focal_depth;
    if (!stats.available || !stats.focal_free || !camera.T_world_cam) continue;
    if (weakest == nullptr ||
        std::abs(stats.shift_per_percent_mm) > std::abs(weakest->focal_depth.shift_per_percent_mm))
      weakest = &camera;
    if (std::abs(stats.correlation) <= options.focal_depth_correlation_warning) continue;
    char line[700];
    std::snprintf(line, sizeof(line),
                  "%s: focal length and depth are not separated (correlation %+.3f, above %.2f): a focal "
                  "length 1%% off moves the camera %.1f mm along its line of sight and raises the "
                  "reprojection error by only %.3f px, so its position may be off by millimetres although "
                  "the reprojection error is small; wave the wand closer to and further from this camera, "
                  "or measure its intrinsics with a chessboard (calibrate intrinsics)",
                  camera.id.c_str(), stats.correlation, options.focal_depth_correlation_warning,
                  std::abs(stats.shift_per_percent_mm), stats.rms_increase_per_percent_px);
    warnings.emplace_back(line);
  }
  const double predicted = result.predicted_length_rms_mm;
  if (result.lengths.count < 10 || predicted <= 0 ||
      result.lengths.rms_error_mm <= options.length_consistency_warning * predicted)
    return warnings;
  char line[900];
  int n = std::snprintf(
      line, sizeof(line),
      "the wand's free length is off by %.3f mm RMS (median %+.3f mm, max %.3f mm), %.1f times "
      "the %.3f mm the reprojection error predicts (more than %.1f): the cameras do not "
      "measure lengths consistently, typically because intrinsics (focal length, principal "
      "point, distortion) do not fit",
      result.lengths.rms_error_mm, result.lengths.median_error_mm, result.lengths.max_abs_error_mm,
      result.lengths.rms_error_mm / predicted, predicted, options.length_consistency_warning);
  if (weakest != nullptr && n > 0 && n < static_cast<int>(sizeof(line)))
    std::snprintf(
        line + n, sizeof(line) - static_cast<std::size_t>(n),
        "; with the focal lengths refined, a 1%% focal length error moves %s %.1f mm along its line "
        "of sight at a cost of only %.3f px, so camera positions may be off by millimetres or more "
        "although the reprojection error is small: measure the intrinsics with a chessboard "
        "(calibrate intrinsics) or refine them with --refine-intrinsics and the wand waved through "
        "the whole volume",
        weakest->id.c_str(), std::abs(weakest->focal_depth.shift_per_percent_mm),
        weakest->focal_depth.rms_increase_per_percent_px);
  warnings.emplace_back(line);
  return warnings;
}

}  // namespace panoptes::calib
