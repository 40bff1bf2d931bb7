// SPDX-License-Identifier: Apache-2.0
// P3P: on random cameras and triangles one of the (at most four) solutions is the true pose to
// 1e-8; every solution puts the points on their rays; collinear points give none.
#include <gtest/gtest.h>

#include <random>

#include <Eigen/Geometry>

#include "panoptes/p3p.h"

namespace panoptes {
namespace {

TEST(P3P, RecoversTheTruePoseAmongItsSolutions) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int found = 0, trials = 200;
  std::size_t most_solutions = 0;
  for (int trial = 0; trial < trials; ++trial) {
    RigidTransform T_cam_world;
    T_cam_world.q =
        Eigen::Quaterniond(Eigen::Vector4d(unit(rng), unit(rng), unit(rng), unit(rng)).normalized());
    T_cam_world.t = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    std::array<Eigen::Vector3d, 3> points, bearings;
    for (int i = 0; i < 3; ++i) {
      // Points 1-6 m in front of the camera, inside a 90° cone.
      const Eigen::Vector3d in_camera =
          Eigen::Vector3d(unit(rng), unit(rng), 1.0).normalized() * (3.5 + 2.5 * unit(rng));
      points[static_cast<std::size_t>(i)] = T_cam_world.inverse().apply(in_camera);
      bearings[static_cast<std::size_t>(i)] = in_camera.normalized();
    }
    const auto solutions = solve_p3p(bearings, points);
    most_solutions = std::max(most_solutions, solutions.size());
    bool match = false;
    for (const auto& solution : solutions) {
      for (std::size_t i = 0; i < 3; ++i) {
        const Eigen::Vector3d in_camera = solution.apply(points[i]);
        EXPECT_GT(in_camera.z(), 0.0);
        EXPECT_LT((in_camera.normalized() - bearings[i]).norm(), 1e-6);
      }
      match = match || ((solution.t - T_cam_world.t).norm() < 1e-8 &&
                        solution.q.angularDistance(T_cam_world.q) < 1e-8);
    }
    found += match ? 1 : 0;
  }
  EXPECT_EQ(found, trials);
  EXPECT_LE(most_solutions, 4U);
}

TEST(P3P, CollinearPointsHaveNoSolution) {
  const std::array<Eigen::Vector3d, 3> points = {Eigen::Vector3d(0, 0, 2), Eigen::Vector3d(1, 0, 2),
                                                 Eigen::Vector3d(2, 0, 2)};
  std::array<Eigen::Vector3d, 3> bearings;
  for (std::size_t i = 0; i < 3; ++i) bearings[i] = points[i].normalized();
  EXPECT_TRUE(solve_p3p(bearings, points).empty());
}

}  // namespace
}  // namespace panoptes
