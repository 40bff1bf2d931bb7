// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/assignment.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace panoptes::estimator {

namespace {

// Square minimum-cost perfect matching (Kuhn–Munkres with row/column potentials and shortest
// augmenting paths). `a` is n x n, 1-based in the classic formulation; returns column of each row.
std::vector<int> hungarian_square(const std::vector<double>& a, int n) {
  constexpr double kInf = std::numeric_limits<double>::max() / 4;
  std::vector<double> u(n + 1, 0.0), v(n + 1, 0.0), min_to(n + 1);
  std::vector<int> p(n + 1, 0), way(n + 1, 0);  // p[j]: row matched to column j (0 = none)
  std::vector<char> used(n + 1);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::fill(min_to.begin(), min_to.end(), kInf);
    std::fill(used.begin(), used.end(), 0);
    do {
      used[j0] = 1;
      const int i0 = p[j0];
      double delta = kInf;
      int j1 = 0;
      for (int j = 1; j <= n; ++j) {
        if (used[j]) continue;
        const double current = a[(i0 - 1) * n + (j - 1)] - u[i0] - v[j];
        if (current < min_to[j]) {
          min_to[j] = current;
          way[j] = j0;
        }
        if (min_to[j] < delta) {
          delta = min_to[j];
          j1 = j;
        }
      }
      for (int j = 0; j <= n; ++j) {
        if (used[j]) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          min_to[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const int j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  std::vector<int> column_of_row(n, -1);
  for (int j = 1; j <= n; ++j) {
    if (p[j] != 0) column_of_row[p[j] - 1] = j - 1;
  }
  return column_of_row;
}

}  // namespace

std::vector<int> solve_assignment(const std::vector<double>& cost, int rows, int cols,
                                  double unassigned_row_cost, double unassigned_col_cost) {
  if (rows < 0 || cols < 0 || cost.size() != static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols))
    throw std::invalid_argument("solve_assignment: cost matrix size does not match rows x cols");
  std::vector<int> result(rows, -1);
  if (rows == 0 || cols == 0) return result;
  // Forbidden pairs become a finite price above any feasible alternative, so the square problem
  // always has a perfect matching; such pairs are discarded afterwards.
  const double leave_both = unassigned_row_cost + unassigned_col_cost;
  double big = 1.0 + std::abs(leave_both);
  for (double c : cost) {
    if (std::isfinite(c)) big += std::abs(c);
  }
  big *= 2.0;
  // Layout: [rows x cols real | rows x rows row-dummies]
  //         [cols x cols col-dummies | cols x rows zeros]
  const int n = rows + cols;
  std::vector<double> square(static_cast<std::size_t>(n) * n, big);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      const double c = cost[static_cast<std::size_t>(i) * cols + j];
      if (std::isfinite(c) && c < leave_both) square[static_cast<std::size_t>(i) * n + j] = c;
    }
    square[static_cast<std::size_t>(i) * n + cols + i] = unassigned_row_cost;
  }
  for (int k = 0; k < cols; ++k) {
    square[static_cast<std::size_t>(rows + k) * n + k] = unassigned_col_cost;
    for (int i = 0; i < rows; ++i) square[static_cast<std::size_t>(rows + k) * n + cols + i] = 0.0;
  }
  const auto matching = hungarian_square(square, n);
  for (int i = 0; i < rows; ++i) {
    const int j = matching[i];
    if (j >= 0 && j < cols && square[static_cast<std::size_t>(i) * n + j] < big) result[i] = j;
  }
  return result;
}

}  // namespace panoptes::estimator
