// SPDX-License-Identifier: Apache-2.0
// Semi-automatic 7-LED marker calibration (seed 004 §3, Algorithm 3.1): initialisation from pairs
// of subsampled frames and the per-coordinate median (§3.1), then interleaved refinement of the
// camera poses and the LED positions with M0, M3 fixed (§3.2, eq. 8).
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "panoptes/estimator/led_marker.h"

namespace panoptes::estimator {

namespace {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;
using Leds = std::array<Vector3d, 7>;

constexpr double kInf = std::numeric_limits<double>::infinity();

Vector3d homogeneous(const Vector2d& m) {
  return Vector3d(m.x(), m.y(), 1.0);
}

struct RelativePose {  // X_b = R X_a + T
  Matrix3d R;
  Vector3d T;
};

// Midpoint triangulation in frame a; false if behind either camera.
bool triangulate(const RelativePose& rel, const Vector2d& ma, const Vector2d& mb, Vector3d* X,
                 double* error) {
  const Vector3d da = homogeneous(ma);
  const Vector3d cb = -rel.R.transpose() * rel.T;
  const Vector3d db = rel.R.transpose() * homogeneous(mb);
  // min |la da - (cb + lb db)|^2
  Eigen::Matrix2d A;
  A << da.dot(da), -da.dot(db), -da.dot(db), db.dot(db);
  const Eigen::Vector2d b(da.dot(cb), -db.dot(cb));
  const double det = A.determinant();
  if (std::abs(det) < 1e-15) return false;
  const Eigen::Vector2d l = A.inverse() * b;
  if (l(0) <= 0 || l(1) <= 0) return false;
  *X = 0.5 * (l(0) * da + cb + l(1) * db);
  const Vector3d xb = rel.R * *X + rel.T;
  if (X->z() <= 0 || xb.z() <= 0) return false;
  *error = (X->head<2>() / X->z() - ma).squaredNorm() + (xb.head<2>() / xb.z() - mb).squaredNorm();
  return true;
}

// Relative pose between two views of the marker plane. The paper uses the five-point algorithm
// (Nister 2004); six of our seven points are coplanar, where the plane-induced homography is the
// natural two-view model, so we decompose G = R + T N^T (calibrated views, plane N^T X_a = 1)
// after Faugeras & Lustman (Ma, Soatto, Kosecka & Sastry, "An Invitation to 3-D Vision", §5.3):
// four solutions, two with the plane in front of the camera, and the out-of-plane LED M6 (smaller
// reprojection error of all seven triangulated LEDs) picks between them.
std::optional<Leds> pair_structure(const LedPoints& a, const LedPoints& b) {
  auto G = six_point_homography(a, b);  // image-to-image: b ~ G a
  if (!G) return std::nullopt;
  double sign = 0;
  for (int i = 0; i < 6; ++i) sign += homogeneous(b[i]).dot(*G * homogeneous(a[i]));
  if (sign < 0) *G = -*G;
  Eigen::JacobiSVD<Matrix3d> svd(*G);
  const double s2 = svd.singularValues()(1);
  if (!(s2 > 0)) return std::nullopt;
  const Matrix3d H = *G / s2;
  Eigen::SelfAdjointEigenSolver<Matrix3d> eig(H.transpose() * H);
  const Vector3d& ev = eig.eigenvalues();  // ascending: sigma3^2, 1, sigma1^2
  const double l1 = ev(2), l3 = ev(0);
  if (!(l1 - l3 > 1e-9)) return std::nullopt;  // no translation: pure rotation
  const Vector3d v1 = eig.eigenvectors().col(2), v2 = eig.eigenvectors().col(1),
                 v3 = eig.eigenvectors().col(0);
  const double c1 = std::sqrt(std::max(0.0, 1 - l3)), c3 = std::sqrt(std::max(0.0, l1 - 1)),
               d = std::sqrt(l1 - l3);
  std::array<RelativePose, 4> candidates;
  std::array<Vector3d, 4> normals;
  for (std::size_t k = 0; k < 2; ++k) {
    const Vector3d u = (c1 * v1 + (k == 0 ? c3 : -c3) * v3) / d;
    Matrix3d U, W;
    U << v2, u, v2.cross(u);
    W << H * v2, H * u, (H * v2).cross(H * u);
    const Matrix3d R = W * U.transpose();
    const Vector3d N = v2.cross(u);
    const Vector3d T = (H - R) * N;
    candidates[2 * k] = {R, T};
    normals[2 * k] = N;
    candidates[2 * k + 1] = {R, -T};
    normals[2 * k + 1] = -N;
  }
  double best = kInf;
  Leds best_leds;
  for (int k = 0; k < 4; ++k) {
    bool in_front = true;
    for (int i = 0; i < 6; ++i) in_front &= normals[k].dot(homogeneous(a[i])) > 0;
    if (!in_front) continue;
    Leds X;
    double total = 0;
    bool ok = true;
    for (int i = 0; i < kLedCount && ok; ++i) {
      double e = 0;
      ok = triangulate(candidates[k], a[i], b[i], &X[i], &e);
      total += e;
    }
    if (ok && total < best) best = total, best_leds = X;
  }
  if (!std::isfinite(best)) return std::nullopt;
  return best_leds;
}

double median(std::vector<double> v) {
  const std::size_t h = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + h, v.end());
  if (v.size() % 2) return v[h];
  const double upper = v[h];
  return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + h));
}

}  // namespace

Leds canonical_led_frame(const Leds& leds) {
  const Vector3d x = (leds[0] - leds[3]).normalized();
  Vector3d y = leds[5] - leds[3];
  y = (y - x * x.dot(y)).normalized();
  Matrix3d R;
  R << x, y, x.cross(y);
  Leds out;
  for (int i = 0; i < kLedCount; ++i) out[i] = R.transpose() * (leds[i] - leds[3]);
  return out;
}

LedCalibrationResult calibrate_led_marker(const std::vector<LedPoints>& frames, double d03,
                                          const LedCalibrationOptions& options) {
  if (!(d03 > 0)) throw std::invalid_argument("marker calibration: d03 must be positive");
  std::vector<const LedPoints*> usable;
  for (const auto& f : frames) {
    bool ok = true;
    for (const auto& p : f) ok &= p.allFinite();
    if (ok) usable.push_back(&f);
  }
  const int n = int(usable.size());
  if (n < 2)
    throw std::invalid_argument("marker calibration: needs at least 2 frames, got " + std::to_string(n));

  // §3.1: every o-th frame (o reduced so that at least min_init_frames remain), all pairs k < k',
  // relative pose, triangulation, similarity T_l of eq. 7, per-coordinate median.
  const int o = std::max(1, std::min(options.subsample, n / std::max(2, options.min_init_frames)));
  std::vector<const LedPoints*> coarse;
  for (int j = 0; j < n; j += o) coarse.push_back(usable[j]);
  std::array<std::array<std::vector<double>, 3>, 7> samples;
  LedCalibrationResult result;
  for (std::size_t k = 0; k < coarse.size(); ++k) {
    for (std::size_t k2 = k + 1; k2 < coarse.size(); ++k2) {
      const auto X = pair_structure(*coarse[k], *coarse[k2]);
      if (!X) continue;
      const double scale = d03 / ((*X)[0] - (*X)[3]).norm();
      if (!std::isfinite(scale)) continue;
      const Leds M = canonical_led_frame(*X);
      for (int i = 0; i < kLedCount; ++i)
        for (int c = 0; c < 3; ++c) samples[i][c].push_back(M[i](c) * scale);
      ++result.pairs_used;
    }
  }
  if (result.pairs_used == 0)
    throw std::runtime_error("marker calibration: no frame pair gave a structure (too little motion?)");
  Leds leds;
  for (int i = 0; i < kLedCount; ++i)
    for (int c = 0; c < 3; ++c) leds[i](c) = median(samples[i][c]);
  leds[3].setZero();
  leds[0] = Vector3d(d03, 0, 0);  // eq. 7
  result.initial = leds;

  // §3.2: alternate poses (§2.2.3 with the current LEDs) and re-triangulation of M1, M2, M4, M5,
  // M6 from all frames (eq. 8, least squares over the rays); M0, M3 stay fixed (scale).
  const int refined[] = {1, 2, 4, 5, 6};
  double previous_moved = kInf;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    std::string error;
    const auto model = LedMarkerModel::create("calibration", leds, &error);
    if (!model)
      throw std::runtime_error("marker calibration: not a valid 7-LED layout after " +
                               std::to_string(iteration) + " refinement iterations: " + error);
    std::array<Matrix3d, 7> A;
    std::array<Vector3d, 7> b;
    for (int i : refined) A[i].setZero(), b[i].setZero();
    int used = 0;
    for (const LedPoints* f : usable) {
      const auto pose = estimate_led_marker_pose(*model, *f);
      if (!pose) continue;
      ++used;
      // P_C = [R^T | -R^T t]: camera centre and rays in the marker frame.
      const Matrix3d Rc = pose->T_cam_marker.rotation().transpose();
      const Vector3d c = -Rc * pose->T_cam_marker.t;
      for (int i : refined) {
        const Vector3d v = (Rc * homogeneous((*f)[i])).normalized();
        const Matrix3d P = Matrix3d::Identity() - v * v.transpose();
        A[i] += P;
        b[i] += P * c;
      }
    }
    if (used < 2) throw std::runtime_error("marker calibration: fewer than 2 frames with a pose");
    double moved = 0;
    for (int i : refined) {
      const Vector3d x = A[i].ldlt().solve(b[i]);
      if (!x.allFinite())
        throw std::runtime_error("marker calibration: LED " + std::to_string(i) + " diverged");
      moved += (x - leds[i]).norm();
      leds[i] = x;
    }
    result.iterations = iteration + 1;
    result.frames_used = used;
    // "until Delta e < epsilon" (Algorithm 3.1): e is the total LED motion of this iteration.
    if (moved < options.epsilon || std::abs(previous_moved - moved) < options.epsilon) break;
    previous_moved = moved;
  }
  leds = canonical_led_frame(leds);
  result.leds = leds;
  std::string error;
  const auto model = LedMarkerModel::create("calibration", leds, &error);
  if (!model) throw std::runtime_error("marker calibration: result is not a valid 7-LED layout: " + error);
  double sum = 0;
  int count = 0;
  for (const LedPoints* f : usable) {
    const auto pose = estimate_led_marker_pose(*model, *f);
    if (!pose) continue;
    sum += pose->rms * pose->rms;
    ++count;
  }
  result.rms = count > 0 ? std::sqrt(sum / count) : kInf;
  return result;
}

}  // namespace panoptes::estimator
