// SPDX-License-Identifier: Apache-2.0
// The assignment solver against brute force, and the blob grid and the x-sorted points against a
// linear scan.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include "../../../estimator_node/core/src/blob_grid.h"
#include "../../../estimator_node/core/src/points_by_x.h"
#include "panoptes/estimator/assignment.h"

#include <Eigen/LU>

namespace panoptes::estimator {
namespace {

// Exhaustive minimum over every partial matching.
double brute_force(const std::vector<double>& cost, int rows, int cols, double row_cost, double col_cost) {
  double best = std::numeric_limits<double>::infinity();
  std::vector<char> col_used(cols, 0);
  std::function<void(int, double, int)> recurse = [&](int row, double sum, int matched) {
    if (row == rows) {
      best = std::min(best, sum + (cols - matched) * col_cost);
      return;
    }
    recurse(row + 1, sum + row_cost, matched);
    for (int c = 0; c < cols; ++c) {
      const double v = cost[row * cols + c];
      if (col_used[c] || !std::isfinite(v)) continue;
      col_used[c] = 1;
      recurse(row + 1, sum + v, matched + 1);
      col_used[c] = 0;
    }
  };
  recurse(0, 0.0, 0);
  return best;
}

TEST(Assignment, MatchesBruteForceOnRandomGatedProblems) {
  std::mt19937 random(5);
  std::uniform_real_distribution<double> uniform(0.0, 20.0);
  for (int trial = 0; trial < 300; ++trial) {
    const int rows = 1 + static_cast<int>(random() % 6), cols = 1 + static_cast<int>(random() % 6);
    std::vector<double> cost(static_cast<std::size_t>(rows) * cols);
    for (double& c : cost) c = (random() % 3 == 0) ? kForbidden : uniform(random);
    const double half_gate = 9.2;
    const auto assignment = solve_assignment(cost, rows, cols, half_gate, half_gate);
    double total = 0;
    int matched = 0;
    std::vector<char> col_used(cols, 0);
    for (int r = 0; r < rows; ++r) {
      if (assignment[r] < 0) {
        total += half_gate;
        continue;
      }
      ASSERT_LT(assignment[r], cols);
      ASSERT_FALSE(col_used[assignment[r]]) << "column used twice";
      col_used[assignment[r]] = 1;
      ASSERT_TRUE(std::isfinite(cost[r * cols + assignment[r]])) << "forbidden pair chosen";
      total += cost[r * cols + assignment[r]];
      ++matched;
    }
    total += (cols - matched) * half_gate;
    EXPECT_NEAR(total, brute_force(cost, rows, cols, half_gate, half_gate), 1e-9) << "trial " << trial;
  }
}

TEST(GatedAssignment, ClustersGiveTheSameTotalAsOneDenseProblem) {
  // Sparse gated pairs over many rows and columns: solving the clusters apart must cost exactly what
  // the whole dense problem costs, use each row and column at most once, and only gated pairs.
  std::mt19937 random(9);
  std::uniform_real_distribution<double> uniform(0.0, 12.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int rows = 1 + static_cast<int>(random() % 12), cols = 1 + static_cast<int>(random() % 12);
    std::vector<double> dense(static_cast<std::size_t>(rows * cols), kForbidden);
    std::vector<GatedPair> pairs;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c)
        if (random() % 5 == 0) {
          const double d2 = uniform(random);
          dense[static_cast<std::size_t>(r) * cols + c] = d2;
          pairs.push_back({static_cast<std::size_t>(r), static_cast<std::size_t>(c), d2});
        }
    const double half_gate = 5.0;
    const auto chosen = assign_gated(pairs, half_gate);
    std::vector<char> row_used(rows, 0), col_used(cols, 0);
    double total = 0;
    for (const auto& [r, c] : chosen) {
      ASSERT_FALSE(row_used[r]);
      ASSERT_FALSE(col_used[c]);
      row_used[r] = col_used[c] = 1;
      const double d2 = dense[r * static_cast<std::size_t>(cols) + c];
      ASSERT_TRUE(std::isfinite(d2)) << "a pair outside the gate was chosen";
      total += d2 - 2.0 * half_gate;
    }
    EXPECT_TRUE(std::is_sorted(chosen.begin(), chosen.end()));
    const auto reference = solve_assignment(dense, rows, cols, half_gate, half_gate);
    double reference_total = 0;
    for (int r = 0; r < rows; ++r)
      if (reference[r] >= 0)
        reference_total += dense[static_cast<std::size_t>(r) * cols + reference[r]] - 2.0 * half_gate;
    EXPECT_NEAR(total, reference_total, 1e-9) << "trial " << trial;
  }
}

TEST(GatedAssignment, AloneAPairIsTakenOnlyWhenCheaperThanLeavingBoth) {
  EXPECT_EQ(assign_gated({{3, 7, 1.0}}, 1.0).size(), 1U);
  EXPECT_TRUE(assign_gated({{3, 7, 2.5}}, 1.0).empty());
  EXPECT_TRUE(assign_gated({}, 1.0).empty());
}

TEST(GatedAssignment, TheGateRadiusHoldsEveryPointInsideTheGate) {
  Eigen::Matrix2d S;
  S << 4.0, 1.5, 1.5, 2.0;
  const Eigen::Matrix2d S_inverse = S.inverse();
  const double chi2 = 9.21;
  const double radius2 = gate_radius2(S, chi2);
  std::mt19937 random(2);
  std::uniform_real_distribution<double> uniform(-10.0, 10.0);
  for (int k = 0; k < 5000; ++k) {
    const Eigen::Vector2d r(uniform(random), uniform(random));
    if (inside_gate(r.dot(S_inverse * r), chi2)) {
      EXPECT_LE(r.squaredNorm(), radius2 * (1 + 1e-12));
    }
  }
  EXPECT_TRUE(inside_gate(9.2, chi2));
  EXPECT_FALSE(inside_gate(9.21, chi2));
}

TEST(Assignment, PrefersTheGloballyBestPairsOverGreedy) {
  // Greedy would take (0,0) = 1 and leave row 1 with nothing; optimal is (0,1) + (1,0) = 4.
  const std::vector<double> cost = {1.0, 2.0, 2.0, kForbidden};
  const auto assignment = solve_assignment(cost, 2, 2, 9.0, 9.0);
  EXPECT_EQ(assignment[0], 1);
  EXPECT_EQ(assignment[1], 0);
}

TEST(Assignment, RejectsAMismatchedMatrixAndHandlesEmptyOnes) {
  EXPECT_THROW(solve_assignment({1.0, 2.0}, 2, 2, 1, 1), std::invalid_argument);
  EXPECT_TRUE(solve_assignment({}, 0, 3, 1, 1).empty());
  EXPECT_EQ(solve_assignment({}, 2, 0, 1, 1), (std::vector<int>{-1, -1}));
}

TEST(BlobGrid, FindsEveryBlobWithinTheRadiusIncludingOutsideTheImage) {
  std::mt19937 random(9);
  std::uniform_real_distribution<double> x(-50.0, 1330.0), y(-50.0, 1074.0);
  std::vector<Eigen::Vector2d> points(500);
  for (auto& p : points) p = {x(random), y(random)};
  points.push_back({std::nan(""), 3.0});  // never returned by a distance test, never a crash
  const BlobGrid grid(points, 1280, 1024, 32.0);
  for (int q = 0; q < 200; ++q) {
    const Eigen::Vector2d center(x(random), y(random));
    const double radius = 5.0 + q;
    std::vector<std::size_t> found;
    grid.for_each_near(center, radius, [&](std::size_t i) {
      if ((points[i] - center).norm() <= radius) found.push_back(i);
    });
    std::vector<std::size_t> expected;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if ((points[i] - center).norm() <= radius) expected.push_back(i);
    }
    std::sort(found.begin(), found.end());
    EXPECT_EQ(found, expected);
  }
}

// Clustered points (the blobs of a few bodies), duplicates and a NaN, as a monitored frame has.
std::vector<Eigen::Vector2d> clustered_points(std::mt19937& random) {
  std::uniform_real_distribution<double> centre(0.0, 1280.0), offset(-30.0, 30.0);
  std::vector<Eigen::Vector2d> points;
  for (int cluster = 0; cluster < 6; ++cluster) {
    const Eigen::Vector2d c(centre(random), centre(random) * 0.8);
    for (int k = 0; k < 12; ++k) points.push_back(c + Eigen::Vector2d(offset(random), offset(random)));
  }
  points.push_back(points[5]);  // a duplicate: equal distances, the lower index first
  points.push_back({std::nan(""), 3.0});
  return points;
}

NearestTwo nearest_two_by_scan(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector2d& at,
                               double reach) {
  NearestTwo n;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double d = (points[i] - at).norm();
    if (!(d <= reach)) continue;
    if (d < n.d1) {
      n.d2 = n.d1;
      n.d1 = d;
      n.index = i;
    } else if (d < n.d2) {
      n.d2 = d;
    }
  }
  return n;
}

TEST(PointsByX, NearestTwoAnyWithinAndCrowdedMatchALinearScan) {
  std::mt19937 random(4);
  const std::vector<Eigen::Vector2d> points = clustered_points(random);
  const PointsByX by_x(points);
  std::uniform_real_distribution<double> x(-20.0, 1300.0), y(-20.0, 1044.0), jitter(-3.0, 3.0);
  for (int q = 0; q < 400; ++q) {
    // A third of the queries near a point (a track's prediction near its blob), a third a few
    // pixels off (the nearest beyond the first step's reach), a third anywhere.
    const double off = q % 3 == 0 ? 1.0 : 4.0;
    const Eigen::Vector2d at =
        q % 3 == 2 ? Eigen::Vector2d(x(random), y(random))
                   : Eigen::Vector2d(points[q % 72] + off * Eigen::Vector2d(jitter(random), jitter(random)));
    const double reach = 2.0 + 0.2 * q;
    const NearestTwo expected = nearest_two_by_scan(points, at, reach);
    const NearestTwo found = by_x.nearest_two(at, reach);
    EXPECT_EQ(found.d1, expected.d1) << "query " << q;
    EXPECT_EQ(found.d2, expected.d2) << "query " << q;
    if (std::isfinite(expected.d1)) EXPECT_EQ(found.index, expected.index) << "query " << q;
    bool any = false;
    for (const auto& p : points) any = any || (p - at).squaredNorm() <= reach * reach;
    EXPECT_EQ(by_x.any_within(at, reach), any) << "query " << q;
    // The two-step search decides as the wide one: the nearest within 25 px, and whether the next
    // is twice as far.
    const NearestTwo wide = nearest_two_by_scan(points, at, 50.0);
    const NearestTwo stepped = by_x.nearest_two(at, 4.0, 25.0, 2.0);
    const auto taken = [](const NearestTwo& n) { return n.d1 <= 25.0 && n.d2 >= 2.0 * n.d1; };
    EXPECT_EQ(taken(stepped), taken(wide)) << "query " << q;
    EXPECT_EQ(stepped.d1, wide.d1) << "query " << q;
    if (std::isfinite(wide.d1)) EXPECT_EQ(stepped.index, wide.index) << "query " << q;
  }
  for (const double radius : {0.5, 5.0, 25.0}) {
    const std::vector<char> crowded = by_x.crowded(radius);
    for (std::size_t i = 0; i < points.size(); ++i) {
      bool expected = false;
      for (std::size_t k = 0; k < points.size(); ++k)
        expected = expected || (k != i && (points[k] - points[i]).squaredNorm() <= radius * radius);
      EXPECT_EQ(crowded[i] != 0, expected) << "point " << i << " radius " << radius;
    }
  }
  // The duplicate pair is crowded at any radius; the NaN never is.
  EXPECT_TRUE(by_x.crowded(0.0)[5]);
  EXPECT_FALSE(by_x.crowded(1e9).back());
}

}  // namespace
}  // namespace panoptes::estimator
