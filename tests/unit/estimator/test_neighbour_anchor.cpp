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

// A foot's markers out of every view together: only one of the marker's neighbours is still
// followed; the others came back as new tracks without names. Placed by their distances, they
// carry the marker as their own motion would.
TEST(NeighbourAnchor, StandInsForNeighboursLostWithIt) {
  const NeighbourAnchor anchor = anchor_at_rest(neighbourhood());
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.5, Eigen::Vector3d(0.1, 0.2, 1.0).normalized()));
  const Eigen::Vector3d shift(0.6, 0.3, -0.1);
  const auto moved = [&](int k) -> Eigen::Vector3d { return q * anchor.neighbours[k].position + shift; };
  const std::vector<AnchorPoint> now{{anchor.neighbours[2].id, moved(2)}, {42, Eigen::Vector3d(4, 4, 4)}};
  EXPECT_FALSE(carried_position(anchor, now).has_value());  // one found: no fit
  // Stand-ins in another order, one unrelated track 0.5 m off among them.
  const std::vector<Eigen::Vector3d> stand_ins{moved(4), Eigen::Vector3d(2.5, 2.8, 1.0), moved(0), moved(1)};
  const auto carried = carried_with_stand_ins(anchor, now, stand_ins, 0.02, 0.03, 0.08);
  ASSERT_TRUE(carried.has_value());
  EXPECT_EQ(carried->neighbours, 4);
  EXPECT_EQ(carried->stood_in, 3);
  EXPECT_LT(carried->fit_rms_m, 1e-9);
  EXPECT_LT((carried->position - (q * kMarker + shift)).norm(), 1e-9);
  // Nothing to stand in: nothing carried (the neighbours found are carried_position's work).
  EXPECT_FALSE(carried_with_stand_ins(anchor, now, {}, 0.02, 0.03, 0.08).has_value());
  // With centimetres of noise the distances still agree within the tolerance.
  std::vector<Eigen::Vector3d> noisy = stand_ins;
  noisy[0] += Eigen::Vector3d(0.006, -0.004, 0.0);
  noisy[2] += Eigen::Vector3d(0.0, 0.005, 0.006);
  const auto near = carried_with_stand_ins(anchor, now, noisy, 0.02, 0.03, 0.08);
  ASSERT_TRUE(near.has_value());
  EXPECT_EQ(near->stood_in, 3);
  EXPECT_LT((near->position - (q * kMarker + shift)).norm(), 0.03);
  // A tight residual limit refuses the fit.
  EXPECT_FALSE(carried_with_stand_ins(anchor, now, noisy, 0.02, 0.001, 0.08).has_value());
}

// Neighbours at the corners of a square around the marker, none followed: any quarter turn of the
// placement (or half turn about a diagonal) fits as well; which stand-in is which is not known.
TEST(NeighbourAnchor, StandInsOfASymmetricGroupAreAmbiguous) {
  const std::vector<AnchorPoint> square{{1, kMarker + Eigen::Vector3d(0.1, 0.1, 0.0)},
                                        {2, kMarker + Eigen::Vector3d(-0.1, 0.1, 0.0)},
                                        {3, kMarker + Eigen::Vector3d(-0.1, -0.1, 0.0)},
                                        {4, kMarker + Eigen::Vector3d(0.1, -0.1, 0.0)}};
  const NeighbourAnchor anchor = anchor_at_rest(square);
  const Eigen::Vector3d shift(0.3, 0.0, 0.0);
  std::vector<Eigen::Vector3d> stand_ins;
  for (const AnchorPoint& point : square) stand_ins.push_back(point.position + shift);
  // At the square's centre every reading carries the marker to the same place.
  const auto centred = carried_with_stand_ins(anchor, {}, stand_ins, 0.01, 0.01, 0.02);
  ASSERT_TRUE(centred.has_value());
  EXPECT_LT((centred->position - (kMarker + shift)).norm(), 1e-9);
  // Off the centre it is ambiguous, even with one corner followed (a half turn about its diagonal).
  NeighbourAnchor off = anchor;
  off.position += Eigen::Vector3d(0.06, 0.0, 0.0);
  EXPECT_FALSE(carried_with_stand_ins(off, {}, stand_ins, 0.01, 0.01, 0.02).has_value());
  const std::vector<AnchorPoint> one{{1, stand_ins[0]}};
  const std::vector<Eigen::Vector3d> three(stand_ins.begin() + 1, stand_ins.end());
  EXPECT_FALSE(carried_with_stand_ins(off, one, three, 0.01, 0.01, 0.02).has_value());
  // Two corners of one side followed settle which is which.
  const std::vector<AnchorPoint> side{{1, stand_ins[0]}, {2, stand_ins[1]}};
  const std::vector<Eigen::Vector3d> two{stand_ins[3], stand_ins[2]};
  const auto settled = carried_with_stand_ins(off, side, two, 0.01, 0.01, 0.02);
  ASSERT_TRUE(settled.has_value());
  EXPECT_EQ(settled->stood_in, 2);
  EXPECT_LT((settled->position - (off.position + shift)).norm(), 1e-9);
}

}  // namespace
}  // namespace panoptes::estimator
