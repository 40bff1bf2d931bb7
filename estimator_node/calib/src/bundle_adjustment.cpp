// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/bundle_adjustment.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <utility>

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "panoptes/calib/triangulate.h"
#include "panoptes/distortion.h"

namespace panoptes::calib {

namespace {

struct MarkerSegment {
  double t0_s, h_s;
  double p0[2], p1[2], m0[2], m1[2];
};

MarkerSegment marker_segment(const TrackSegment& segment, std::size_t m) {
  MarkerSegment s{};
  s.t0_s = segment.t0_s;
  s.h_s = segment.h_s;
  for (int i = 0; i < 2; ++i) {
    s.p0[i] = segment.p0[m][i];
    s.p1[i] = segment.p1[m][i];
    s.m0[i] = segment.m0[m][i];
    s.m1[i] = segment.m1[m][i];
  }
  return s;
}

template <class T>
void evaluate(const MarkerSegment& s, const T& dt, T* out) {
  for (int i = 0; i < 2; ++i) out[i] = cubic_hermite(s.t0_s, s.h_s, s.p0[i], s.m0[i], s.p1[i], s.m1[i], dt);
}

// Camera parameters as the bundle adjustment holds them: world -> camera (angle-axis, t), then
// intrinsics [fx, fy, cx, cy, k1, k2, p1, p2, k3] (OpenCV model, as CameraModel).
template <class T>
bool project(const T* pose, const T* intrinsics, const T* point, T* pixel) {
  T p[3];
  ceres::AngleAxisRotatePoint(pose, point, p);
  p[0] += pose[3];
  p[1] += pose[4];
  p[2] += pose[5];
  if (p[2] < T(1e-6)) return false;
  const Eigen::Matrix<T, 2, 1> xd = distort_normalized<T>(p[0] / p[2], p[1] / p[2], intrinsics + 4);
  pixel[0] = intrinsics[0] * xd[0] + intrinsics[2];
  pixel[1] = intrinsics[1] * xd[1] + intrinsics[3];
  return true;
}

// The observation is the camera's 2D track evaluated at the sample instant on the camera's own
// clock (instant + offset): the offset moves the observation along the track's velocity. A wand
// sample is one parameter block (all its markers), so that the length residuals stay inside it and
// every sample can be eliminated by the Schur complement.
template <int kMarkers>
struct ReprojectionCost {
  MarkerSegment segment;
  double shift_s;  // the segment was looked up at instant + shift_s
  int marker;
  template <class T>
  bool operator()(const T* pose, const T* intrinsics, const T* offset, const T* sample, T* residual) const {
    T pixel[2], observed[2];
    if (!project(pose, intrinsics, sample + 3 * marker, pixel)) return false;
    evaluate(segment, offset[0] - T(shift_s), observed);
    residual[0] = pixel[0] - observed[0];
    residual[1] = pixel[1] - observed[1];
    return true;
  }
};

template <int kMarkers>
struct LengthCost {
  int i, j;
  double length, inv_sigma;
  template <class T>
  bool operator()(const T* sample, T* residual) const {
    const T* a = sample + 3 * i;
    const T* b = sample + 3 * j;
    const T dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    residual[0] = (ceres::sqrt(dx * dx + dy * dy + dz * dz + T(1e-18)) - T(length)) * T(inv_sigma);
    return true;
  }
};

template <int kMarkers>
ceres::CostFunction* reprojection_cost(const MarkerSegment& segment, double shift_s, int marker) {
  return new ceres::AutoDiffCostFunction<ReprojectionCost<kMarkers>, 2, 6, 9, 1, 3 * kMarkers>(
      new ReprojectionCost<kMarkers>{segment, shift_s, marker});
}

template <int kMarkers>
ceres::CostFunction* length_cost(int i, int j, double length, double inv_sigma) {
  return new ceres::AutoDiffCostFunction<LengthCost<kMarkers>, 1, 3 * kMarkers>(
      new LengthCost<kMarkers>{i, j, length, inv_sigma});
}

ceres::CostFunction* make_reprojection(std::size_t markers, const MarkerSegment& segment, double shift_s,
                                       int marker) {
  switch (markers) {
    case 1:
      return reprojection_cost<1>(segment, shift_s, marker);
    case 2:
      return reprojection_cost<2>(segment, shift_s, marker);
    case 3:
      return reprojection_cost<3>(segment, shift_s, marker);
    case 4:
      return reprojection_cost<4>(segment, shift_s, marker);
    default:
      return reprojection_cost<5>(segment, shift_s, marker);
  }
}

ceres::CostFunction* make_length(std::size_t markers, int i, int j, double length, double inv_sigma) {
  switch (markers) {
    case 2:
      return length_cost<2>(i, j, length, inv_sigma);
    case 3:
      return length_cost<3>(i, j, length, inv_sigma);
    case 4:
      return length_cost<4>(i, j, length, inv_sigma);
    default:
      return length_cost<5>(i, j, length, inv_sigma);
  }
}

struct DistanceCost {  // single-light gauge: fixes the scale to the initial one
  double distance;
  template <class T>
  bool operator()(const T* pose_a, const T* pose_b, T* residual) const {
    T center_a[3], center_b[3], minus_a[3], minus_b[3];
    for (int i = 0; i < 3; ++i) {
      minus_a[i] = -pose_a[i];
      minus_b[i] = -pose_b[i];
    }
    ceres::AngleAxisRotatePoint(minus_a, pose_a + 3, center_a);
    ceres::AngleAxisRotatePoint(minus_b, pose_b + 3, center_b);
    const T dx = center_a[0] - center_b[0], dy = center_a[1] - center_b[1], dz = center_a[2] - center_b[2];
    residual[0] = (ceres::sqrt(dx * dx + dy * dy + dz * dz) - T(distance)) * T(1e3);
    return true;
  }
};

// The intrinsics block [fx, fy, cx, cy, k1, k2, p1, p2, k3] moved only along fixed directions:
// x + B delta. The automatic refinement moves fx and fy together (their given ratio, square pixels
// for a nominal camera), k1 and k2, and, if asked, cx and cy; the rest stays as given.
class LinearManifold : public ceres::Manifold {
 public:
  explicit LinearManifold(Eigen::Matrix<double, 9, Eigen::Dynamic> basis)
      : basis_(std::move(basis)), inverse_((basis_.transpose() * basis_).inverse() * basis_.transpose()) {}
  int AmbientSize() const override { return 9; }
  int TangentSize() const override { return static_cast<int>(basis_.cols()); }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    using Vector9 = Eigen::Matrix<double, 9, 1>;
    Eigen::Map<Vector9> out(x_plus_delta);
    out = Eigen::Map<const Vector9>(x) + basis_ * Eigen::Map<const Eigen::VectorXd>(delta, basis_.cols());
    return true;
  }
  bool PlusJacobian(const double* /*x*/, double* jacobian) const override {
    Eigen::Map<Eigen::Matrix<double, 9, Eigen::Dynamic, Eigen::RowMajor>> out(jacobian, 9, basis_.cols());
    out = basis_;
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    using Vector9 = Eigen::Matrix<double, 9, 1>;
    Eigen::Map<Eigen::VectorXd> out(y_minus_x, basis_.cols());
    out = inverse_ * (Eigen::Map<const Vector9>(y) - Eigen::Map<const Vector9>(x));
    return true;
  }
  bool MinusJacobian(const double* /*x*/, double* jacobian) const override {
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 9, Eigen::RowMajor>> out(jacobian, basis_.cols(), 9);
    out = inverse_;
    return true;
  }

 private:
  Eigen::Matrix<double, 9, Eigen::Dynamic> basis_;
  Eigen::Matrix<double, Eigen::Dynamic, 9> inverse_;
};

// kEvidence's basis: the groups `free` names, in IntrinsicsGroup order.
Eigen::Matrix<double, 9, Eigen::Dynamic> evidence_basis(const double* intrinsics, unsigned free) {
  std::vector<Eigen::Matrix<double, 9, 1>> columns;
  const auto unit = [](int i) { return Eigen::Matrix<double, 9, 1>::Unit(i); };
  if ((free & kFreeFocal) != 0U) columns.push_back(unit(0) + (intrinsics[1] / intrinsics[0]) * unit(1));
  if ((free & kFreeAspect) != 0U) columns.push_back(unit(1));
  if ((free & kFreeCentre) != 0U) {
    columns.push_back(unit(2));
    columns.push_back(unit(3));
  }
  if ((free & kFreeK1) != 0U) columns.push_back(unit(4));
  if ((free & kFreeK2) != 0U) columns.push_back(unit(5));
  Eigen::Matrix<double, 9, Eigen::Dynamic> basis(9, static_cast<Eigen::Index>(columns.size()));
  for (std::size_t i = 0; i < columns.size(); ++i) basis.col(static_cast<Eigen::Index>(i)) = columns[i];
  return basis;
}

ceres::Manifold* refinement_manifold(const double* intrinsics, IntrinsicsRefinement refinement) {
  const bool nominal = refinement == IntrinsicsRefinement::kNominal;
  Eigen::Matrix<double, 9, Eigen::Dynamic> basis =
      Eigen::Matrix<double, 9, Eigen::Dynamic>::Zero(9, nominal ? 3 : 6);
  if (nominal) {
    basis(0, 0) = 1.0;
    basis(1, 0) = intrinsics[1] / intrinsics[0];
    basis(4, 1) = 1.0;
    basis(5, 2) = 1.0;
  } else {
    for (int i = 0; i < 6; ++i) basis(i, i) = 1.0;
  }
  return new LinearManifold(basis);
}

// The adjustment's Ceres problem over a state it points into (the state must outlive it).
struct Problem {
  ceres::Problem problem;
  std::vector<double*> point_blocks;
  std::set<int> cameras;
  std::vector<ceres::ResidualBlockId> reprojection_blocks, constraint_blocks;

  static ceres::Problem::Options problem_options() {
    ceres::Problem::Options options;
    options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
    return options;
  }
  Problem() : problem(problem_options()) {}
};

// Reprojection residuals of every instant seen by two or more active observations, and the
// wand-length residuals between every pair of its markers: they fix the scale and, with three
// or more markers, keep the bar straight (seed 000 eq. 4.76).
void add_residuals(BundleState& state, const WandDefinition& wand, const PassOptions& options, bool robust,
                   Problem& out) {
  const std::size_t markers = wand.marker_count();
  ceres::LossFunction* loss = robust ? new ceres::HuberLoss(options.huber_px) : nullptr;
  for (std::size_t s = 0; s < state.instants.size(); ++s) {
    const auto& instant = state.instants[s];
    int active = 0;
    for (const auto& observation : instant.observations) active += observation.active ? 1 : 0;
    if (active < 2) continue;
    double* point = &state.points[s * markers * 3];
    for (const auto& observation : instant.observations) {
      if (!observation.active) continue;
      CameraParameters& camera = state.cameras[observation.camera];
      out.cameras.insert(observation.camera);
      for (std::size_t m = 0; m < markers; ++m)
        out.reprojection_blocks.push_back(out.problem.AddResidualBlock(
            make_reprojection(markers, marker_segment(observation.segment, m), observation.shift_s,
                              static_cast<int>(m)),
            loss, camera.pose.data(), camera.intrinsics.data(), &camera.offset_s, point));
    }
    out.point_blocks.push_back(point);
    for (std::size_t i = 0; i < markers; ++i)
      for (std::size_t j = i + 1; j < markers; ++j)
        out.constraint_blocks.push_back(out.problem.AddResidualBlock(
            make_length(markers, static_cast<int>(i), static_cast<int>(j),
                        wand.positions[j] - wand.positions[i], 1.0 / options.length_sigma_m),
            nullptr, point));
  }
}

// Gauge of scale for a single light: the distance from the reference to its nearest camera.
void add_single_light_gauge(BundleState& state, const PassOptions& options, Problem& out) {
  int nearest = -1;
  double best = 1e300;
  const Eigen::Vector3d c_ref = T_world_cam_of(state.cameras[options.reference]).t;
  for (int c : out.cameras) {
    if (c == options.reference) continue;
    const double d = (T_world_cam_of(state.cameras[c]).t - c_ref).norm();
    if (d < best) {
      best = d;
      nearest = c;
    }
  }
  if (nearest >= 0)
    out.constraint_blocks.push_back(out.problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<DistanceCost, 1, 6, 6>(new DistanceCost{best}), nullptr,
        state.cameras[options.reference].pose.data(), state.cameras[nearest].pose.data()));
}

void set_camera_blocks(BundleState& state, const PassOptions& options, Problem& out) {
  for (int c : out.cameras) {
    CameraParameters& camera = state.cameras[c];
    if (c == options.reference) out.problem.SetParameterBlockConstant(camera.pose.data());
    const unsigned free = options.refinement == IntrinsicsRefinement::kEvidence &&
                                  static_cast<std::size_t>(c) < options.free_intrinsics.size()
                              ? options.free_intrinsics[static_cast<std::size_t>(c)]
                              : 0U;
    if (options.refinement == IntrinsicsRefinement::kNone ||
        (options.refinement == IntrinsicsRefinement::kEvidence && free == 0U))
      out.problem.SetParameterBlockConstant(camera.intrinsics.data());
    else if (options.refinement == IntrinsicsRefinement::kEvidence)
      out.problem.SetManifold(camera.intrinsics.data(),
                              new LinearManifold(evidence_basis(camera.intrinsics.data(), free)));
    // Automatic refinement: only along the directions the data determines (docs/calibration.md).
    if (options.refinement == IntrinsicsRefinement::kNominal ||
        options.refinement == IntrinsicsRefinement::kSuspect)
      out.problem.SetManifold(camera.intrinsics.data(),
                              refinement_manifold(camera.intrinsics.data(), options.refinement));
    if (!options.time_offsets || c == options.reference)
      out.problem.SetParameterBlockConstant(&camera.offset_s);
  }
}

void build_problem(BundleState& state, const WandDefinition& wand, const PassOptions& options, bool robust,
                   Problem& out) {
  add_residuals(state, wand, options, robust, out);
  if (wand.marker_count() < 2) add_single_light_gauge(state, options, out);
  set_camera_blocks(state, options, out);
}

ceres::Solver::Options solver_options(const PassOptions& options, bool robust) {
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = options.threads;
  solver.function_tolerance = robust ? 1e-6 : 1e-10;
  solver.parameter_tolerance = 1e-10;
  solver.gradient_tolerance = 1e-12;
  return solver;
}

void summarise(const ceres::Solver::Summary& summary, PassReport& report) {
  report.rms_px = std::sqrt(2.0 * summary.final_cost / std::max(1, summary.num_residuals));
  report.summary = "bundle adjustment: " + std::to_string(summary.iterations.size()) + " iterations, " +
                   std::to_string(summary.num_residual_blocks) + " residual blocks, cost " +
                   std::to_string(summary.initial_cost) + " -> " + std::to_string(summary.final_cost) + " (" +
                   summary.message + ")";
}

// `crs` (Ceres's row-compressed Jacobian) as an Eigen sparse matrix.
Eigen::SparseMatrix<double> to_sparse(const ceres::CRSMatrix& crs) {
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(crs.values.size());
  for (int row = 0; row < crs.num_rows; ++row)
    for (int k = crs.rows[row]; k < crs.rows[row + 1]; ++k)
      entries.emplace_back(row, crs.cols[k], crs.values[k]);
  Eigen::SparseMatrix<double> out(crs.num_rows, crs.num_cols);
  out.setFromTriplets(entries.begin(), entries.end());
  return out;
}

// The blocks the adjustment moves, cameras first: their order is the Jacobian's columns.
std::vector<double*> varying_blocks(BundleState& state, Problem& problem, AdjustmentJacobian& out) {
  std::vector<double*> blocks;
  const auto add = [&](double* block) {
    if (!problem.problem.HasParameterBlock(block) || problem.problem.IsParameterBlockConstant(block))
      return -1;
    blocks.push_back(block);
    const int first = out.columns;
    out.columns += problem.problem.ParameterBlockTangentSize(block);
    return first;
  };
  out.cameras.assign(state.cameras.size(), {});
  for (int c : problem.cameras) {
    CameraParameters& camera = state.cameras[static_cast<std::size_t>(c)];
    auto& columns = out.cameras[static_cast<std::size_t>(c)];
    columns.pose = add(camera.pose.data());
    columns.intrinsics = add(camera.intrinsics.data());
    columns.offset = add(&camera.offset_s);
  }
  out.instant_columns.assign(state.instants.size(), -1);
  const std::size_t stride = state.instants.empty() ? 0 : state.points.size() / state.instants.size();
  for (double* point : problem.point_blocks)
    out.instant_columns[static_cast<std::size_t>(point - state.points.data()) / stride] = add(point);
  return blocks;
}

}  // namespace

CameraParameters camera_parameters(const CameraIntrinsics& given,
                                   const std::optional<RigidTransform>& T_world_cam) {
  CameraParameters camera;
  camera.intrinsics = {given.fx,
                       given.fy,
                       given.cx,
                       given.cy,
                       given.distortion[0],
                       given.distortion[1],
                       given.distortion[2],
                       given.distortion[3],
                       given.distortion[4]};
  if (!T_world_cam) return camera;
  const RigidTransform T_cam_world = T_world_cam->inverse();
  const Eigen::AngleAxisd angle_axis(T_cam_world.q.normalized());
  const Eigen::Vector3d v = angle_axis.axis() * angle_axis.angle();
  for (int i = 0; i < 3; ++i) {
    camera.pose[i] = v[i];
    camera.pose[3 + i] = T_cam_world.t[i];
  }
  camera.registered = true;
  return camera;
}

RigidTransform T_world_cam_of(const CameraParameters& camera) {
  const auto& pose = camera.pose;
  const Eigen::Vector3d rotation_vector(pose[0], pose[1], pose[2]);
  const double angle = rotation_vector.norm();
  RigidTransform T_cam_world;
  T_cam_world.q = angle > 1e-15 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, rotation_vector / angle))
                                : Eigen::Quaterniond::Identity();
  T_cam_world.t = Eigen::Vector3d(pose[3], pose[4], pose[5]);
  return T_cam_world.inverse();
}

CameraIntrinsics intrinsics_of(const CameraParameters& camera, const CameraIntrinsics& given) {
  CameraIntrinsics k = given;
  const auto& v = camera.intrinsics;
  k.fx = v[0];
  k.fy = v[1];
  k.cx = v[2];
  k.cy = v[3];
  for (std::size_t i = 0; i < 5; ++i) k.distortion[i] = v[4 + i];
  return k;
}

CameraModel model_of(const CameraParameters& camera, const CameraIntrinsics& given) {
  return CameraModel(intrinsics_of(camera, given), T_world_cam_of(camera));
}

std::vector<CameraModel> registered_models(const BundleState& state,
                                           const std::vector<CameraIntrinsics>& given) {
  std::vector<CameraModel> models(state.cameras.size());
  for (std::size_t c = 0; c < state.cameras.size(); ++c)
    if (state.cameras[c].registered) models[c] = model_of(state.cameras[c], given[c]);
  return models;
}

BundleState triangulate_instants(BundleState state, const std::vector<CameraIntrinsics>& given,
                                 std::size_t markers) {
  state.points.assign(state.instants.size() * markers * 3, 0.0);
  for (std::size_t s = 0; s < state.instants.size(); ++s) {
    auto& instant = state.instants[s];
    std::vector<CameraModel> models;
    std::vector<const InstantObservation*> used;
    for (auto& observation : instant.observations) {
      const CameraParameters& camera = state.cameras[observation.camera];
      if (!camera.registered) observation.active = false;
      if (!observation.active) continue;
      models.push_back(model_of(camera, given[observation.camera]));
      used.push_back(&observation);
    }
    for (std::size_t m = 0; m < markers; ++m) {
      std::vector<Eigen::Vector2d> pixels;
      pixels.reserve(used.size());
      for (const auto* observation : used)
        pixels.push_back(observed_pixel(*observation, m, state.cameras[observation->camera].offset_s));
      const auto x = triangulate(models, pixels);
      if (!x) {
        for (auto& observation : instant.observations) observation.active = false;
        break;
      }
      std::copy(x->data(), x->data() + 3, &state.points[(s * markers + m) * 3]);
    }
  }
  return state;
}

PassResult adjust_pass(BundleState state, const WandDefinition& wand, const PassOptions& options,
                       bool robust) {
  PassResult result;
  ceres::Solver::Summary summary;
  {
    Problem problem;
    build_problem(state, wand, options, robust, problem);
    ceres::Solve(solver_options(options, robust), &problem.problem, &summary);
  }
  result.report.iterations = static_cast<int>(summary.iterations.size());
  result.report.steps = static_cast<int>(summary.iterations.size()) - 1;
  result.report.converged = summary.termination_type == ceres::CONVERGENCE;
  result.report.termination = summary.message;
  summarise(summary, result.report);
  result.state = std::move(state);
  return result;
}

AdjustmentJacobian adjustment_jacobian(BundleState state, const WandDefinition& wand,
                                       const PassOptions& options) {
  AdjustmentJacobian out;
  out.refinement = options.refinement;
  out.free_intrinsics = options.free_intrinsics;
  Problem problem;
  build_problem(state, wand, options, false, problem);
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = varying_blocks(state, problem, out);
  evaluate.apply_loss_function = false;
  evaluate.num_threads = options.threads;
  ceres::CRSMatrix crs;
  std::vector<double> residuals;
  evaluate.residual_blocks = problem.reprojection_blocks;
  if (evaluate.parameter_blocks.empty() || evaluate.residual_blocks.empty()) return out;
  problem.problem.Evaluate(evaluate, nullptr, &residuals, nullptr, &crs);
  out.reprojection = to_sparse(crs);
  out.reprojection_residuals =
      Eigen::Map<const Eigen::VectorXd>(residuals.data(), static_cast<Eigen::Index>(residuals.size()));
  out.constraints.resize(0, out.columns);
  evaluate.residual_blocks = problem.constraint_blocks;
  if (!evaluate.residual_blocks.empty()) {
    problem.problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &crs);
    out.constraints = to_sparse(crs);
  }
  return out;
}

PassResult alternate(BundleState state, const WandDefinition& wand, const PassOptions& options) {
  PassResult result;
  ceres::Solver::Summary summary;
  {
    Problem problem;
    build_problem(state, wand, options, true, problem);
    ceres::Solver::Options solver = solver_options(options, true);
    // Seed 003 §3.3.2: the reconstructed trace is a virtual calibration object; each camera is
    // re-calibrated against it, then the trace is rebuilt, and so on.
    solver.max_num_iterations = 20;
    for (int iteration = 0; iteration < options.alternation_iterations; ++iteration) {
      for (double* block : problem.point_blocks) problem.problem.SetParameterBlockConstant(block);
      for (int c : problem.cameras) {
        if (c != options.reference) problem.problem.SetParameterBlockVariable(state.cameras[c].pose.data());
        if (options.time_offsets && c != options.reference)
          problem.problem.SetParameterBlockVariable(&state.cameras[c].offset_s);
      }
      ceres::Solve(solver, &problem.problem, &summary);
      for (double* block : problem.point_blocks) problem.problem.SetParameterBlockVariable(block);
      for (int c : problem.cameras) {
        problem.problem.SetParameterBlockConstant(state.cameras[c].pose.data());
        if (options.time_offsets && c != options.reference)
          problem.problem.SetParameterBlockConstant(&state.cameras[c].offset_s);
      }
      ceres::Solve(solver, &problem.problem, &summary);
      result.report.iterations += 1;
    }
  }
  result.report.termination = summary.message;
  summarise(summary, result.report);
  result.state = std::move(state);
  return result;
}

ErrorStats error_stats(std::vector<double> errors) {
  ErrorStats stats;
  stats.count = static_cast<int>(errors.size());
  if (errors.empty()) return stats;
  double sum = 0, squared = 0;
  int within = 0;
  for (double e : errors) {
    sum += e;
    squared += e * e;
    within += e <= 5.0 ? 1 : 0;
  }
  const auto n = static_cast<double>(errors.size());
  stats.mean_px = sum / n;
  stats.rms_axis_px = std::sqrt(squared / (2 * n));
  stats.within_5px = within / n;
  const std::size_t half = errors.size() / 2;
  std::nth_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(half), errors.end());
  stats.median_px = errors[half];
  if (errors.size() % 2 == 0)
    stats.median_px =
        0.5 * (stats.median_px +
               *std::max_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(half)));
  return stats;
}

// The sample itself where the frame is one (synchronised cameras), else the path interpolated by
// a cubic Hermite spline over the samples.
std::vector<std::vector<double>> raw_frame_errors(const BundleState& state,
                                                  const std::vector<CameraModel>& models,
                                                  const std::vector<CameraWandTrack>& tracks,
                                                  std::size_t markers) {
  std::vector<std::vector<double>> errors(state.cameras.size());
  std::vector<TimeNs> times;
  std::vector<bool> valid;
  for (const auto& instant : state.instants) {
    int active = 0;
    for (const auto& observation : instant.observations) active += observation.active ? 1 : 0;
    times.push_back(instant.t_ns);
    valid.push_back(active >= 2);
  }
  if (times.size() < 4) return errors;
  const TimeNs step = times[1] - times[0];
  const auto point = [&](std::size_t k, std::size_t m) {
    return Eigen::Vector3d(&state.points[(k * markers + m) * 3]);
  };
  for (std::size_t c = 0; c < state.cameras.size(); ++c) {
    if (!state.cameras[c].registered) continue;
    for (const auto& frame : tracks[c].frames) {
      const TimeNs t = frame.stamp_ns - static_cast<TimeNs>(std::llround(state.cameras[c].offset_s * 1e9));
      const auto after = std::upper_bound(times.begin(), times.end(), t);
      if (after == times.begin()) continue;
      const std::size_t i = static_cast<std::size_t>(after - times.begin()) - 1;
      const bool exact = times[i] == t;
      if (exact && !valid[i]) continue;
      if (!exact) {
        if (i < 1 || i + 2 >= times.size()) continue;
        bool usable = true;
        for (std::size_t k = i - 1; k <= i + 2; ++k) usable = usable && valid[k];
        for (std::size_t k = i - 1; k < i + 2; ++k) usable = usable && times[k + 1] - times[k] == step;
        if (!usable) continue;
      }
      const double tau = static_cast<double>(t - times[i]) / static_cast<double>(step);
      const double tau2 = tau * tau, tau3 = tau2 * tau;
      const double h00 = 2 * tau3 - 3 * tau2 + 1, h10 = tau3 - 2 * tau2 + tau, h01 = -2 * tau3 + 3 * tau2,
                   h11 = tau3 - tau2;
      for (std::size_t m = 0; m < markers; ++m) {
        const Eigen::Vector3d X =
            exact ? point(i, m)
                  : Eigen::Vector3d(h00 * point(i, m) + h10 * 0.5 * (point(i + 1, m) - point(i - 1, m)) +
                                    h01 * point(i + 1, m) + h11 * 0.5 * (point(i + 2, m) - point(i, m)));
        const auto projected = models[c].project(X);
        if (!projected) continue;
        errors[c].push_back((*projected - frame.pixels[m]).norm());
      }
    }
  }
  return errors;
}

}  // namespace panoptes::calib
