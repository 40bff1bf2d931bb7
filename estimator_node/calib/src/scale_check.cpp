// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/scale_check.h"

#include <cmath>
#include <cstdio>
#include <limits>

namespace panoptes::calib {

ScaleCheck check_scale(const std::vector<double>& measured_m, const std::vector<double>& known_m,
                       double tolerance) {
  ScaleCheck check;
  double cross = 0, known_squared = 0;
  for (std::size_t i = 0; i < measured_m.size() && i < known_m.size(); ++i) {
    if (!(known_m[i] > 0)) continue;
    cross += measured_m[i] * known_m[i];
    known_squared += known_m[i] * known_m[i];
    const double error_mm = (measured_m[i] - known_m[i]) * 1e3;
    if (std::abs(error_mm) > std::abs(check.max_error_mm)) check.max_error_mm = error_mm;
    ++check.lengths;
  }
  if (check.lengths == 0) return check;
  check.scale_error_ppm = (cross / known_squared - 1.0) * 1e6;
  check.exceeded = std::abs(check.scale_error_ppm) > tolerance * 1e6;
  return check;
}

std::string scale_check_summary(const ScaleCheck& check, const std::string& what, double tolerance) {
  char line[700];
  if (check.lengths == 0) {
    std::snprintf(line, sizeof(line), "scale check (%s): no length measured\n", what.c_str());
    return line;
  }
  if (!check.exceeded) {
    std::snprintf(line, sizeof(line),
                  "scale check (%s): the calibration's scale is %+.0f ppm off (largest length error %+.3f "
                  "mm), within the tolerance of %.0f ppm\n",
                  what.c_str(), check.scale_error_ppm, check.max_error_mm, tolerance * 1e6);
    return line;
  }
  std::snprintf(line, sizeof(line),
                "WARNING: scale check (%s): the calibration measures lengths %+.0f ppm off (largest length "
                "error %+.3f mm; tolerance %.0f ppm, --scale-tolerance): check the known lengths and the "
                "wand given to `calibrate solve`; if they are right, the intrinsics (focal length against "
                "depth) are suspect: see the solve's report and docs/calibration.md, \"Scale check\"\n",
                what.c_str(), check.scale_error_ppm, check.max_error_mm, tolerance * 1e6);
  return line;
}

std::vector<double> lframe_arm_lengths(const std::vector<Eigen::Vector3d>& points,
                                       const RigidTransform& T_new_old, double x_arm_m, double y_arm_m) {
  if (points.size() < 3) return {};
  const auto nearest = [&](const Eigen::Vector3d& target) {
    Eigen::Vector3d best = Eigen::Vector3d::Zero();
    double distance = std::numeric_limits<double>::max();
    for (const auto& p : points) {
      const Eigen::Vector3d q = T_new_old.apply(p);
      if ((q - target).norm() < distance) {
        distance = (q - target).norm();
        best = q;
      }
    }
    return best;
  };
  const Eigen::Vector3d corner = nearest(Eigen::Vector3d::Zero());
  return {(nearest(Eigen::Vector3d(x_arm_m, 0, 0)) - corner).norm(),
          (nearest(Eigen::Vector3d(0, y_arm_m, 0)) - corner).norm()};
}

}  // namespace panoptes::calib
