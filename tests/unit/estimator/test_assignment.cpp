// SPDX-License-Identifier: Apache-2.0
// The assignment solver against brute force, and the blob grid against a linear scan.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <random>

#include "../../../estimator_node/core/src/blob_grid.h"
#include "panoptes/estimator/assignment.h"

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
    std::vector<double> cost(rows * cols);
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

}  // namespace
}  // namespace panoptes::estimator
