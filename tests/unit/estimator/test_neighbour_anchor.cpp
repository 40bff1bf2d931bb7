// SPDX-License-Identifier: Apache-2.0
// neighbour_anchor.h: the nearest neighbours kept, and a rigid motion of the neighbourhood carried
// over to the anchored marker (the tracker's reacquisition by neighbours).
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "panoptes/estimator/neighbour_anchor.h"

namespace panoptes::estimator {
namespace {

const Eigen::Vector3d kMarker(1.0, 2.0, 1.0);

std::vector<AnchorPoint> neighbourhood() {
  return {{7, kMarker + Eigen::Vector3d(0.30, 0.0, 0.0)},   {3, kMarker + Eigen::Vector3d(0.0, 0.10, 0.0)},
          {9, kMarker + Eigen::Vector3d(0.0, 0.0, 0.60)},   {4, kMarker + Eigen::Vector3d(-0.12, 0.0, 0.05)},
          {5, kMarker + Eigen::Vector3d(0.05, -0.2, 0.0)},  {8, kMarker + Eigen::Vector3d(0.0, 0.0, -0.25)},
          {11, kMarker + Eigen::Vector3d(0.0, -0.45, 0.0)}, {10, kMarker + Eigen::Vector3d(-0.4, 0.0, 0.0)}};
}

NeighbourAnchor anchor_at_rest(const std::vector<AnchorPoint>& points, double radius_m = 0.5) {
  return make_anchor(123, kMarker, Eigen::Vector3d::Zero(), points, radius_m, 0.0);
}

TEST(NeighbourAnchor, KeepsTheNearestWithinTheRadiusNearestFirst) {
  const auto points = neighbourhood();
  const NeighbourAnchor anchor = anchor_at_rest(points);
  EXPECT_EQ(anchor.stamp_ns, 123);
  EXPECT_EQ(anchor.position, kMarker);
  ASSERT_EQ(anchor.count, kAnchorNeighbours);
  // 0.10, 0.13, 0.206, 0.25, 0.30, 0.40 m; 11 at 0.45 m is seventh, 9 at 0.6 m beyond the radius
  const std::vector<std::int64_t> expected{3, 4, 5, 8, 7, 10};
  for (int k = 0; k < anchor.count; ++k) EXPECT_EQ(anchor.neighbours[k].id, expected[k]) << k;
  EXPECT_EQ(anchor_at_rest(points, 0.11).count, 1);  // only 3 within 0.11 m
  EXPECT_EQ(anchor_at_rest({}).count, 0);
}

TEST(NeighbourAnchor, RanksAMarkerPassingFastBehindSlowerOnesFartherOff) {
  auto points = neighbourhood();
  points[1].velocity = Eigen::Vector3d(3.0, 0.0, 0.0);  // 3, the nearest (0.10 m), passes at 3 m/s
  const Eigen::Vector3d still = Eigen::Vector3d::Zero();
  const NeighbourAnchor by_distance = make_anchor(0, kMarker, still, points, 0.5, 0.0);
  EXPECT_EQ(by_distance.neighbours[0].id, 3);
  const NeighbourAnchor with_horizon = make_anchor(0, kMarker, still, points, 0.5, 0.2);  // 3 ranks at 0.70
  EXPECT_EQ(with_horizon.neighbours[0].id, 4);
  for (int k = 0; k < with_horizon.count; ++k) EXPECT_NE(with_horizon.neighbours[k].id, 3) << k;
  // Moving with it, 3 is the nearest again: only the difference in velocity counts.
  EXPECT_EQ(make_anchor(0, kMarker, points[1].velocity, {points.data() + 1, 1}, 0.5, 0.2).neighbours[0].id,
            3);
}

TEST(NeighbourAnchor, CarriesTheMarkerWithItsNeighboursRigidMotion) {
  const NeighbourAnchor anchor = anchor_at_rest(neighbourhood());
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.3, 1.0).normalized()));
  const Eigen::Vector3d shift(0.4, -0.9, 0.05);
  std::vector<AnchorPoint> now;
  for (int k = 0; k < anchor.count; ++k)
    now.push_back({anchor.neighbours[k].id, q * anchor.neighbours[k].position + shift});
  now.push_back({42, Eigen::Vector3d(5, 5, 5)});  // not a neighbour: ignored
  const auto carried = carried_position(anchor, now);
  ASSERT_TRUE(carried.has_value());
  EXPECT_EQ(carried->neighbours, kAnchorNeighbours);
  EXPECT_LT(carried->fit_rms_m, 1e-9);
  EXPECT_LT((carried->position - (q * kMarker + shift)).norm(), 1e-9);
  // The neighbourhood turned: the shift alone would put it far off.
  EXPECT_GT((carried->position - (kMarker + shift)).norm(), 0.1);
  // A neighbour that moved on its own shows in the fit's residual.
  now[0].position += Eigen::Vector3d(0.0, 0.0, 0.08);
  const auto bent = carried_position(anchor, now);
  ASSERT_TRUE(bent.has_value());
  EXPECT_GT(bent->fit_rms_m, 0.02);
}

// With a trim limit, the neighbours that moved against the others (the other leg's markers beside a
// foot) leave the fit, the worst first, down to three; the rest carry the marker exactly.
TEST(NeighbourAnchor, LeavesOutNeighboursThatMovedOnTheirOwn) {
  const NeighbourAnchor anchor = anchor_at_rest(neighbourhood());
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d shift(0.3, 0.2, 0.0);
  std::vector<AnchorPoint> now;
  for (int k = 0; k < anchor.count; ++k)
    now.push_back({anchor.neighbours[k].id, q * anchor.neighbours[k].position + shift});
  now[1].position += Eigen::Vector3d(0.15, 0.0, 0.0);
  now[4].position += Eigen::Vector3d(0.0, -0.10, 0.05);
  const auto all = carried_position(anchor, now);
  ASSERT_TRUE(all.has_value());
  EXPECT_EQ(all->neighbours, kAnchorNeighbours);
  EXPECT_GT(all->fit_rms_m, 0.03);
  EXPECT_GT((all->position - (q * kMarker + shift)).norm(), 0.01);
  const auto trimmed = carried_position(anchor, now, 0.01);
  ASSERT_TRUE(trimmed.has_value());
  EXPECT_EQ(trimmed->neighbours, kAnchorNeighbours - 2);
  EXPECT_LT(trimmed->fit_rms_m, 1e-9);
  EXPECT_LT((trimmed->position - (q * kMarker + shift)).norm(), 1e-9);
  // Never below three: with every neighbour moved its own way, three are left and the residual shows.
  for (std::size_t k = 0; k < now.size(); ++k) now[k].position += Eigen::Vector3d(0.0, 0.0, 0.05 * (k % 3));
  const auto bent = carried_position(anchor, now, 0.001);
  ASSERT_TRUE(bent.has_value());
  EXPECT_EQ(bent->neighbours, 3);
}

TEST(NeighbourAnchor, NeedsThreeNeighboursNotInALine) {
  const NeighbourAnchor anchor = anchor_at_rest(neighbourhood());
  std::vector<AnchorPoint> two{anchor.neighbours[0], anchor.neighbours[1]};
  EXPECT_FALSE(carried_position(anchor, two).has_value());
  const std::vector<AnchorPoint> line{{1, kMarker + Eigen::Vector3d(0.1, 0, 0)},
                                      {2, kMarker + Eigen::Vector3d(0.2, 0, 0)},
                                      {6, kMarker + Eigen::Vector3d(0.3, 0, 0)}};
  const NeighbourAnchor collinear = anchor_at_rest(line);
  EXPECT_FALSE(carried_position(collinear, line).has_value());
}

}  // namespace
}  // namespace panoptes::estimator
