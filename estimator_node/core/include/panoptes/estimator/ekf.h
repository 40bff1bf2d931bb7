// SPDX-License-Identifier: Apache-2.0
// The filter layer (the OpenVINS StateHelper habit): the one place where a filter's covariance is
// propagated and updated. The point filter (point_ekf.h) and the error-state body filter
// (body_ekf.h) hold their covariance as a FilterCovariance, which nobody outside this header can
// write: it is set once from a prior and then changes only through propagate() and update().
//
// The update form is P⁺ = P − K S Kᵀ, computed as P − K (H P), with K = P Hᵀ S⁻¹ the optimal gain
// and S = H P Hᵀ + R formed here from the same P (seed 003 eqs. A.33–A.35). For that gain it
// equals the Joseph form (I − K H) P (I − K H)ᵀ + K R Kᵀ exactly; in floating point both are
// symmetrised, and the test (tests/unit/estimator/test_ekf.cpp) checks them equal on random cases.
// It costs M·N² multiplications instead of ~2·N³ (15-state body filter: 450 against 6750), which
// the body filter's per-marker updates need (docs/bodies.md, "Acceptance scene, prediction and
// cost"); the Joseph form's robustness to a suboptimal gain is not needed because the gain is never
// anything else.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

namespace panoptes::estimator {

// Squared Mahalanobis distance rᵀ S⁻¹ r of an innovation (the chi-square gate's statistic).
template <int M>
double mahalanobis2(const Eigen::Matrix<double, M, M>& S_inverse,
                    const Eigen::Matrix<double, M, 1>& residual) {
  return residual.dot(S_inverse * residual);
}

// A filter state's predicted measurement in one camera, with what gating and the update need.
template <int N>
struct PixelMeasurement {
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // h(x̂)
  Eigen::Matrix<double, 2, N> H;                    // d(pixel)/d(x)
  Eigen::Matrix<double, 2, N> HP;                   // H P of the P it was made from (the update reuses it)
  Eigen::Matrix2d S;                                // innovation covariance H P Hᵀ + R
  Eigen::Matrix2d S_inverse;
};

// Squared Mahalanobis distance of the pixel `z` from a predicted measurement.
template <int N>
double mahalanobis2(const PixelMeasurement<N>& measurement, const Eigen::Vector2d& z) {
  return mahalanobis2<2>(measurement.S_inverse, z - measurement.pixel);
}

// L · X for an L made of RB x 3 blocks of which many are exactly zero (the body filter's transition
// has 12 non-zero 3 x 3 blocks of 36, a marker's Jacobian 2 of 6): the zero blocks are skipped.
// Sums the same terms as the dense product, in block order. Dense when N is not a multiple of 3.
template <int RB, int R, int N, int C>
Eigen::Matrix<double, R, C> block_sparse_product(const Eigen::Matrix<double, R, N>& L,
                                                 const Eigen::Matrix<double, N, C>& X) {
  if constexpr (N % 3 != 0 || R % RB != 0) {
    return L.lazyProduct(X);
  } else {
    Eigen::Matrix<double, R, C> out = Eigen::Matrix<double, R, C>::Zero();
    for (Eigen::Index i = 0; i < R / RB; ++i) {
      for (Eigen::Index j = 0; j < N / 3; ++j) {
        const auto block = L.template block<RB, 3>(RB * i, 3 * j);
        if (block.isZero(0.0)) continue;
        out.template middleRows<RB>(RB * i).noalias() += block.lazyProduct(X.template middleRows<3>(3 * j));
      }
    }
    return out;
  }
}

template <int N>
class FilterCovariance {
 public:
  using Matrix = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;

  FilterCovariance() : P_(Matrix::Identity()) {}
  // A track's prior (symmetrised): the only way to give the covariance a value from outside.
  explicit FilterCovariance(const Matrix& prior) : P_(0.5 * (prior + prior.transpose())) {}
  static FilterCovariance diagonal(const Vector& variances) {
    return FilterCovariance(Matrix(variances.asDiagonal()));
  }

  const Matrix& matrix() const { return P_; }
  double operator()(Eigen::Index row, Eigen::Index col) const { return P_(row, col); }

  // Prediction P ← A P Aᵀ + Q (seed 003 eq. A.32), as A (A P)ᵀ + Q (P symmetric) with A's zero
  // 3 x 3 blocks skipped: the body filter's 18 x 18 prediction in a third of the dense products.
  void propagate(const Matrix& A, const Matrix& Q) {
    const Matrix AP = block_sparse_product<3>(A, P_);
    const Matrix APA = block_sparse_product<3>(A, Matrix(AP.transpose()));
    P_ = APA + Q;
    symmetrise();
  }

  // The same prediction for A = [[I, Δt I], [0, I]] (constant velocity: 3 positions, 3
  // velocities) in closed form, P_pp + Δt (P_pv + P_vp) + Δt² P_vv, P_pv + Δt P_vv, P_vv: the
  // point tracks' most frequent operation without the two 6 x 6 products.
  void propagate_constant_velocity(double dt, const Matrix& Q) requires(N == 6) {
    const Eigen::Matrix3d P_pv = P_.template block<3, 3>(0, 3);
    const Eigen::Matrix3d P_vv = P_.template block<3, 3>(3, 3);
    const Eigen::Matrix3d cross = P_pv + dt * P_vv;
    Matrix predicted;
    predicted.template block<3, 3>(0, 0) =
        P_.template block<3, 3>(0, 0) + dt * (P_pv + P_pv.transpose()) + (dt * dt) * P_vv;
    predicted.template block<3, 3>(0, 3) = cross;
    predicted.template block<3, 3>(3, 0) = cross.transpose();
    predicted.template block<3, 3>(3, 3) = P_vv;
    P_ = predicted + Q;
    symmetrise();
  }

  // Innovation covariance S = H P Hᵀ + R of a measurement model H (M x N) with noise R.
  template <int M>
  Eigen::Matrix<double, M, M> innovation_covariance(const Eigen::Matrix<double, M, N>& H,
                                                    const Eigen::Matrix<double, M, M>& R) const {
    const Eigen::Matrix<double, M, N> HP = block_sparse_product<M>(H, P_);
    return HP.lazyProduct(H.transpose()) + R;
  }

  // The measurement `pixel` = h(x̂) with Jacobian H and isotropic pixel noise σ (R = σ² I).
  PixelMeasurement<N> pixel_measurement(const Eigen::Vector2d& pixel, const Eigen::Matrix<double, 2, N>& H,
                                        double sigma_px) const {
    PixelMeasurement<N> measurement;
    measurement.pixel = pixel;
    measurement.H = H;
    measurement.HP = block_sparse_product<2>(H, P_);
    measurement.S =
        measurement.HP.lazyProduct(H.transpose()) + sigma_px * sigma_px * Eigen::Matrix2d::Identity();
    measurement.S_inverse = measurement.S.inverse();
    return measurement;
  }

  // Update with the pixel `z` for `measurement`, which must have been made from this P (its H P and
  // S⁻¹ are used as they are): returns δx.
  Vector update(const PixelMeasurement<N>& measurement, const Eigen::Vector2d& z) {
    const Eigen::Matrix<double, N, 2> K = measurement.HP.transpose() * measurement.S_inverse;
    P_.noalias() -= K.lazyProduct(measurement.HP);
    symmetrise();
    return K * (z - measurement.pixel);
  }

  // EKF update with the innovation `residual` = z − h(x̂): updates P and returns the correction
  // δx = K r, which the caller adds to its state (or, in an error-state filter, injects into the
  // nominal state and resets).
  template <int M>
  Vector update(const Eigen::Matrix<double, M, N>& H, const Eigen::Matrix<double, M, M>& R,
                const Eigen::Matrix<double, M, 1>& residual) {
    const Eigen::Matrix<double, M, N> HP = block_sparse_product<M>(H, P_);
    const Eigen::Matrix<double, M, M> S = HP.lazyProduct(H.transpose()) + R;
    const Eigen::Matrix<double, N, M> K = HP.transpose() * S.inverse();
    P_.noalias() -= K.lazyProduct(HP);
    symmetrise();
    return K * residual;
  }

 private:
  // Evaluated into a temporary first: assigning 0.5 (P + Pᵀ) to P in place would read entries
  // already overwritten (Eigen does not guard transpose aliasing) and leave P slightly asymmetric.
  void symmetrise() {
    const Matrix symmetric = 0.5 * (P_ + P_.transpose());
    P_ = symmetric;
  }

  Matrix P_;
};

}  // namespace panoptes::estimator
