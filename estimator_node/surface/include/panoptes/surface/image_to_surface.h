// SPDX-License-Identifier: Apache-2.0
// From a camera's image to a flat surface's 2D coordinates (seed 003 §2.3.2, LumiPoint: each
// camera behind or in front of a display maps its laser spots onto the display plane). Either a
// plain 3 × 3 homography from pixels (measured by showing known points or clicking four corners,
// no camera calibration needed) or, for a calibrated camera, the plane's homography from
// undistorted normalised coordinates, so that lens distortion is removed exactly. docs/surface.md.
#pragma once

#include <optional>
#include <span>

#include <Eigen/Core>

#include "panoptes/camera_model.h"

namespace panoptes::surface {

// A plane in the world with its own 2D frame: the point origin + s·u_axis + t·v_axis has surface
// coordinates (s, t) in metres; u_axis and v_axis are orthonormal.
struct SurfacePlane {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d u_axis = Eigen::Vector3d::UnitX();
  Eigen::Vector3d v_axis = Eigen::Vector3d::UnitY();
  Eigen::Vector2d size = Eigen::Vector2d(1.0, 1.0);  // extent along u and v, metres

  Eigen::Vector3d at(const Eigen::Vector2d& st) const { return origin + st.x() * u_axis + st.y() * v_axis; }
  bool contains(const Eigen::Vector2d& st) const {
    return st.x() >= 0.0 && st.y() >= 0.0 && st.x() <= size.x() && st.y() <= size.y();
  }
};

class ImageToSurface {
 public:
  // H maps homogeneous pixels to homogeneous surface coordinates. Throws std::invalid_argument
  // when H is singular or not finite.
  static ImageToSurface from_homography(const Eigen::Matrix3d& H_surface_pixel);
  // The plane seen by a calibrated camera. Throws std::invalid_argument when the plane passes
  // through the camera centre (seen edge-on) or lies wholly behind the camera.
  static ImageToSurface from_plane(const CameraModel& camera, const SurfacePlane& plane);

  // Surface coordinates of `pixel`, with d(surface)/d(pixel) if asked; nullopt when the pixel's
  // ray does not meet the surface in front of the camera (the horizon line and beyond).
  std::optional<Eigen::Vector2d> map(const Eigen::Vector2d& pixel, Eigen::Matrix2d* J = nullptr) const;

  // The homography on the image side: pixels, or undistorted normalised coordinates for a camera.
  const Eigen::Matrix3d& homography() const { return H_; }

 private:
  Eigen::Matrix3d H_ = Eigen::Matrix3d::Identity();
  std::optional<CameraModel> camera_;  // set: H_ acts on undistorted normalised coordinates
};

// The homography from ≥ 4 pixel ↔ surface correspondences (direct linear transform with
// Hartley's normalisation). Throws std::invalid_argument when fewer than four points are given
// or three of the four are collinear (the homography is then not determined).
Eigen::Matrix3d fit_homography(std::span<const Eigen::Vector2d> pixels,
                               std::span<const Eigen::Vector2d> surface);

}  // namespace panoptes::surface
