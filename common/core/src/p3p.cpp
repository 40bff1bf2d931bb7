// SPDX-License-Identifier: Apache-2.0
#include "panoptes/p3p.h"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "panoptes/rigid_fit.h"

namespace panoptes {
namespace {

using Polynomial = std::vector<double>;  // coefficients, lowest degree first

Polynomial multiply(const Polynomial& a, const Polynomial& b) {
  Polynomial product(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) product[i + j] += a[i] * b[j];
  return product;
}

Polynomial add(const Polynomial& a, const Polynomial& b, double scale_b = 1.0) {
  Polynomial sum(std::max(a.size(), b.size()), 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) sum[i] += a[i];
  for (std::size_t i = 0; i < b.size(); ++i) sum[i] += scale_b * b[i];
  return sum;
}

double evaluate(const Polynomial& p, double x) {
  double value = 0;
  for (auto it = p.rbegin(); it != p.rend(); ++it) value = value * x + *it;
  return value;
}

// Real roots of a quartic (companion-matrix eigenvalues, each polished by Newton's method).
std::vector<double> real_roots_of_quartic(const Polynomial& p) {
  std::vector<double> roots;
  if (std::abs(p[4]) < 1e-14 * (std::abs(p[0]) + std::abs(p[1]) + std::abs(p[2]) + std::abs(p[3])))
    return roots;
  Eigen::Matrix4d companion = Eigen::Matrix4d::Zero();
  for (int i = 0; i < 3; ++i) companion(i + 1, i) = 1.0;
  for (int i = 0; i < 4; ++i) companion(i, 3) = -p[static_cast<std::size_t>(i)] / p[4];
  const Eigen::EigenSolver<Eigen::Matrix4d> solver(companion, false);
  const Polynomial derivative = {p[1], 2 * p[2], 3 * p[3], 4 * p[4]};
  for (const auto& root : solver.eigenvalues()) {
    if (std::abs(root.imag()) > 1e-6 * (1.0 + std::abs(root.real()))) continue;
    double x = root.real();
    for (int iteration = 0; iteration < 3; ++iteration) {
      const double slope = evaluate(derivative, x);
      if (slope == 0.0) break;
      x -= evaluate(p, x) / slope;
    }
    roots.push_back(x);
  }
  return roots;
}

}  // namespace

std::vector<RigidTransform> solve_p3p(const std::array<Eigen::Vector3d, 3>& bearings,
                                      const std::array<Eigen::Vector3d, 3>& points_world) {
  std::vector<RigidTransform> poses;
  const std::array<Eigen::Vector3d, 3> f = {bearings[0].normalized(), bearings[1].normalized(),
                                            bearings[2].normalized()};
  const double a2 = (points_world[1] - points_world[2]).squaredNorm();
  const double b2 = (points_world[0] - points_world[2]).squaredNorm();
  const double c2 = (points_world[0] - points_world[1]).squaredNorm();
  if ((points_world[1] - points_world[0]).cross(points_world[2] - points_world[0]).norm() <
      1e-9 * (a2 + b2 + c2))
    return poses;
  const double cos_alpha = f[1].dot(f[2]), cos_beta = f[0].dot(f[2]), cos_gamma = f[0].dot(f[1]);
  // s₁² D(v) = b² with D = 1 + v² − 2v cos β; subtracting the a- and c-equations leaves u linear:
  // u = N(v) / M(v), N = b²(1 − v²) + (a² − c²) D, M = 2b² (cos γ − v cos α).
  const Polynomial D = {1.0, -2.0 * cos_beta, 1.0};
  const Polynomial N = add({b2, 0.0, -b2}, D, a2 - c2);
  const Polynomial M = {2.0 * b2 * cos_gamma, -2.0 * b2 * cos_alpha};
  // The c-equation c² D = b² (1 + u² − 2u cos γ), times M²/b²: N² − 2 cos γ N M + (1 − c² D / b²) M² = 0.
  const Polynomial quartic = add(add(multiply(N, N), multiply(N, M), -2.0 * cos_gamma),
                                 multiply(add({1.0}, D, -c2 / b2), multiply(M, M)));
  for (const double v : real_roots_of_quartic(quartic)) {
    const double m = evaluate(M, v), d = evaluate(D, v);
    if (v <= 0.0 || std::abs(m) < 1e-12 || d <= 0.0) continue;
    const double u = evaluate(N, v) / m;
    if (u <= 0.0) continue;
    const double s1 = std::sqrt(b2 / d);
    const std::vector<Eigen::Vector3d> in_camera = {s1 * f[0], u * s1 * f[1], v * s1 * f[2]};
    const std::vector<Eigen::Vector3d> in_world(points_world.begin(), points_world.end());
    double rms = 0;
    const auto T_cam_world = fit_rigid_transform(in_world, in_camera, &rms);
    if (T_cam_world && rms < 1e-6 * std::sqrt(a2 + b2 + c2)) poses.push_back(*T_cam_world);
  }
  return poses;
}

}  // namespace panoptes
