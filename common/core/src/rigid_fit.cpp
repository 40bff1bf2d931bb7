// SPDX-License-Identifier: Apache-2.0
#include "panoptes/rigid_fit.h"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>
#include <Eigen/SVD>

namespace panoptes {

namespace {

Eigen::Matrix3d rotation_from_svd(const Eigen::JacobiSVD<Eigen::Matrix3d>& svd) {
  Eigen::Matrix3d U = svd.matrixU();
  if ((U * svd.matrixV().transpose()).determinant() < 0) U.col(2) = -U.col(2);  // no reflection
  return U * svd.matrixV().transpose();
}

}  // namespace

Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& M) {
  return rotation_from_svd(Eigen::JacobiSVD<Eigen::Matrix3d>(M, Eigen::ComputeFullU | Eigen::ComputeFullV));
}

namespace {

// Horn's closed form (J. Opt. Soc. Am. A 4(4), 1987): the rotation that maximises Σ bᵢ·R aᵢ is the
// unit quaternion of the largest eigenvalue λ of a symmetric 4×4 matrix N built from
// S = Σ aᵢ bᵢᵀ (centred points), and Σ |bᵢ − R aᵢ|² = Ga + Gb − 2λ. λ is found by Newton's method
// on N's characteristic polynomial from the bound (Ga + Gb) / 2, above every root, where it
// converges monotonically (the idea of Theobald's QCP, Acta Cryst. A 61, 2005); the quaternion is
// the largest column of the adjugate of N − λI, which has rank one there. Cheaper than the 3×3
// Jacobi SVD, which was half of labelling's time (bench_label: labelling 0.63× with this, side by
// side). nullopt when Newton does not settle or the adjugate vanishes (a double root: the rotation
// is not unique).
struct HornRotation {
  Eigen::Quaterniond q;
  double lambda = 0.0;  // Σ bᵢ·R aᵢ at q
};
std::optional<HornRotation> horn_rotation(const Eigen::Matrix3d& S, double bound) {
  const double sxx = S(0, 0), sxy = S(0, 1), sxz = S(0, 2);
  const double syx = S(1, 0), syy = S(1, 1), syz = S(1, 2);
  const double szx = S(2, 0), szy = S(2, 1), szz = S(2, 2);
  Eigen::Matrix4d N;
  N << sxx + syy + szz, syz - szy, szx - sxz, sxy - syx,  //
      syz - szy, sxx - syy - szz, sxy + syx, szx + sxz,   //
      szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy,  //
      sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz;
  // det(λI − N) = λ⁴ + c2 λ² + c1 λ + c0 (N is traceless): Newton's identities.
  const Eigen::Matrix4d N2 = N * N;
  const double c2 = -0.5 * N2.trace();
  const double c1 = -(N2 * N).trace() / 3.0;
  const double c0 = N.determinant();
  double lambda = bound;
  bool settled = false;
  for (int i = 0; i < 60 && !settled; ++i) {
    const double l2 = lambda * lambda;
    const double p = (l2 + c2) * l2 + c1 * lambda + c0;
    const double dp = 4.0 * l2 * lambda + 2.0 * c2 * lambda + c1;
    if (!(dp > 0.0)) break;
    const double step = p / dp;
    lambda -= step;
    settled = std::abs(step) <= 1e-13 * bound;
  }
  if (!settled) return std::nullopt;
  const Eigen::Matrix4d A = N - lambda * Eigen::Matrix4d::Identity();
  // adj(A) = det(A) A⁻¹ has rank one, ∝ v vᵀ, where A = N − λI is singular with a simple root.
  Eigen::Vector4d best = Eigen::Vector4d::Zero();
  const int rest[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (int j = 0; j < 4; ++j) {
    Eigen::Vector4d column;
    for (int i = 0; i < 4; ++i) {
      Eigen::Matrix3d minor;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) minor(r, c) = A(rest[i][r], rest[j][c]);
      column(i) = ((i + j) % 2 == 0 ? 1.0 : -1.0) * minor.determinant();
    }
    if (column.squaredNorm() > best.squaredNorm()) best = column;
  }
  const double norm = best.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return std::nullopt;
  best /= norm;
  return HornRotation{Eigen::Quaterniond(best(0), best(1), best(2), best(3)), lambda};
}

}  // namespace

std::optional<RigidTransform> fit_rigid_transform(const std::vector<Eigen::Vector3d>& from,
                                                  const std::vector<Eigen::Vector3d>& to, double* rms) {
  const std::size_t n = from.size();
  if (n < 3 || to.size() != n) return std::nullopt;
  Eigen::Vector3d mean_from = Eigen::Vector3d::Zero(), mean_to = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mean_from += from[i];
    mean_to += to[i];
  }
  mean_from /= static_cast<double>(n);
  mean_to /= static_cast<double>(n);
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();  // Σ (toᵢ − mean) (fromᵢ − mean)ᵀ
  double spread = 0.0;                              // Ga + Gb
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d a = from[i] - mean_from;
    const Eigen::Vector3d b = to[i] - mean_to;
    cross += b * a.transpose();
    spread += a.squaredNorm() + b.squaredNorm();
  }
  // Collinear points (rank ≤ 1: every 2×2 minor vanishes; the minors' squared sum is
  // σ₀²σ₁² + σ₀²σ₂² + σ₁²σ₂²): the rotation about their line is undetermined.
  const double cross_norm2 = cross.squaredNorm();
  const double minors2 = cross.col(1).cross(cross.col(2)).squaredNorm() +
                         cross.col(2).cross(cross.col(0)).squaredNorm() +
                         cross.col(0).cross(cross.col(1)).squaredNorm();
  if (!(minors2 > 1e-24 * cross_norm2 * cross_norm2)) return std::nullopt;
  const auto residual = [&](const Eigen::Matrix3d& R) {
    double sum = 0;
    for (std::size_t i = 0; i < n; ++i) sum += (R * (from[i] - mean_from) - (to[i] - mean_to)).squaredNorm();
    return sum;
  };
  RigidTransform T;
  std::optional<double> sum;
  // Horn's eigenvalue gap is 2 (σ₁ + σ₂): nearly collinear points (σ₁ < 1e-3 σ₀) go to the SVD,
  // which keeps the rotation about their line where the closed form would lose it.
  const bool well_spread = minors2 > 1e-6 * cross_norm2 * cross_norm2;
  if (const auto horn = well_spread ? horn_rotation(cross.transpose(), 0.5 * spread) : std::nullopt) {
    // Taken when its residual is the least one possible, Ga + Gb − 2λ, to rounding (a rotation
    // error δθ adds about λ δθ² to it: 1e-11 of the spread is δθ ~ 3e-6 rad at worst).
    const double s = residual(horn->q.toRotationMatrix());
    if (std::abs(s - (spread - 2.0 * horn->lambda)) <= 1e-11 * spread) {
      T.q = horn->q;
      sum = s;
    }
  }
  if (!sum) {
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d R = rotation_from_svd(svd);
    T.q = Eigen::Quaterniond(R).normalized();
    sum = residual(R);
  }
  T.t = mean_to - T.q * mean_from;
  if (rms != nullptr) *rms = std::sqrt(*sum / static_cast<double>(n));
  return T;
}

}  // namespace panoptes
