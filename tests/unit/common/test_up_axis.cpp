// SPDX-License-Identifier: Apache-2.0
// The up-axis conventions (panoptes/up_axis.h): y up is the z-up world turned by one proper
// rotation, for points, covariances and body orientations alike, and a body's markers placed by a
// turned pose land on the turned markers.
#include <array>
#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "panoptes/errors.h"
#include "panoptes/up_axis.h"

namespace panoptes {
namespace {

// z up -> y up as a matrix, written independently of the code under test.
Eigen::Matrix3d z_to_y() {
  return Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

Eigen::Vector3d vec(const std::array<double, 3>& v) {
  return {v[0], v[1], v[2]};
}
std::array<double, 3> arr(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}
Eigen::Quaterniond quat(const std::array<double, 4>& q) {
  return {q[3], q[0], q[1], q[2]};
}  // x y z w

TEST(UpAxis, YUpPutsTheFormerZAxisAlongY) {
  EXPECT_EQ(vector_to_up_axis(UpAxis::kY, {0, 0, 1}), (std::array<double, 3>{0, 1, 0}));
  EXPECT_EQ(vector_to_up_axis(UpAxis::kY, {1, 2, 3}), (std::array<double, 3>{1, 3, -2}));
  EXPECT_EQ(vector_to_up_axis(UpAxis::kZ, {1, 2, 3}), (std::array<double, 3>{1, 2, 3}));
  EXPECT_NEAR(z_to_y().determinant(), 1.0, 1e-15);  // a rotation: handedness kept
}

TEST(UpAxis, PointsBodiesAndCovariancesAreTheZUpWorldRotated) {
  std::mt19937 random(34);
  std::uniform_real_distribution<double> uniform(-2.0, 2.0);
  const Eigen::Matrix3d R = z_to_y();
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d point(uniform(random), uniform(random), uniform(random));
    EXPECT_LT((vec(vector_to_up_axis(UpAxis::kY, arr(point))) - R * point).norm(), 1e-12);

    const Eigen::Quaterniond q =
        Eigen::Quaterniond(uniform(random), uniform(random), uniform(random), uniform(random)).normalized();
    const auto turned = orientation_to_up_axis(UpAxis::kY, {q.x(), q.y(), q.z(), q.w()});
    EXPECT_NEAR(quat(turned).norm(), 1.0, 1e-12);
    EXPECT_LT((quat(turned).toRotationMatrix() - R * q.toRotationMatrix()).norm(), 1e-12);
    // A body marker (body frame) placed by the turned pose is the z-up world marker, rotated.
    const Eigen::Vector3d layout(uniform(random), uniform(random), uniform(random));
    const Eigen::Vector3d world_z = point + q * layout;
    const Eigen::Vector3d world_y = vec(vector_to_up_axis(UpAxis::kY, arr(point))) + quat(turned) * layout;
    EXPECT_LT((world_y - R * world_z).norm(), 1e-12);

    Eigen::Matrix3d A = Eigen::Matrix3d::Random();
    const Eigen::Matrix3d C = A * A.transpose();
    const auto c = covariance_to_up_axis(UpAxis::kY, {C(0, 0), C(0, 1), C(0, 2), C(1, 1), C(1, 2), C(2, 2)});
    const Eigen::Matrix3d expected = R * C * R.transpose();
    const std::array<double, 6> want{expected(0, 0), expected(0, 1), expected(0, 2),
                                     expected(1, 1), expected(1, 2), expected(2, 2)};
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(c[i], want[i], 1e-12) << i;
  }
}

TEST(UpAxis, ParsesZAndYAndRefusesAnythingElseNamingTheOption) {
  EXPECT_EQ(parse_up_axis("z", "--up-axis"), UpAxis::kZ);
  EXPECT_EQ(parse_up_axis("Y", "--up-axis"), UpAxis::kY);
  EXPECT_STREQ(up_axis_name(UpAxis::kY), "y");
  for (const char* bad : {"", "x", "yup", "-y"}) {
    try {
      parse_up_axis(bad, "--up-axis");
      FAIL() << bad;
    } catch (const ConfigError& e) {
      EXPECT_EQ(std::string(e.what()), std::string("--up-axis=") + bad + ": not an up axis (z or y)");
    }
  }
}

}  // namespace
}  // namespace panoptes
