// SPDX-License-Identifier: Apache-2.0
// OpenCV's (k1, k2, p1, p2, k3) lens distortion, templated on the scalar so that CameraModel
// (double) and the calibration's Ceres costs (Jets) evaluate the same expression. The model is
// cv::projectPoints' (OpenCV docs, "Camera Calibration and 3D Reconstruction", detailed description).
#pragma once

#include <Eigen/Core>

namespace panoptes {

// Normalised image coordinates (x/z, y/z) -> distorted normalised coordinates; `k` points at the
// five coefficients k1, k2, p1, p2, k3.
template <class T>
Eigen::Matrix<T, 2, 1> distort_normalized(const T& x, const T& y, const T* k) {
  const T& k1 = k[0];
  const T& k2 = k[1];
  const T& p1 = k[2];
  const T& p2 = k[3];
  const T& k3 = k[4];
  const T r2 = x * x + y * y;
  const T radial = T(1.0) + r2 * (k1 + r2 * (k2 + r2 * k3));
  return {x * radial + T(2.0) * p1 * x * y + p2 * (r2 + T(2.0) * x * x),
          y * radial + p1 * (r2 + T(2.0) * y * y) + T(2.0) * p2 * x * y};
}

}  // namespace panoptes
