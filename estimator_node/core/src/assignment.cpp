// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/assignment.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include <Eigen/LU>

#include "panoptes/union_find.h"

namespace panoptes::estimator {

namespace {

// Minimum-cost matching of every one of n rows to distinct columns of an n x m matrix, n <= m
// (Kuhn–Munkres with row/column potentials and shortest augmenting paths, O(n^2 m)). `a` is
// row-major; returns the column of each row.
std::vector<int> hungarian(const std::vector<double>& a, int n, int m) {
  constexpr double kInf = std::numeric_limits<double>::max() / 4;
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0), min_to(m + 1);
  std::vector<int> p(m + 1, 0), way(m + 1, 0);  // p[j]: row matched to column j (0 = none)
  std::vector<char> used(m + 1);
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
      const double* row = &a[static_cast<std::size_t>(i0 - 1) * m];
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double current = row[j - 1] - u[i0] - v[j];
        if (current < min_to[j]) {
          min_to[j] = current;
          way[j] = j0;
        }
        if (min_to[j] < delta) {
          delta = min_to[j];
          j1 = j;
        }
      }
      for (int j = 0; j <= m; ++j) {
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
  for (int j = 1; j <= m; ++j) {
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
  // Total = sum over pairs of (c - row_cost - col_cost) + rows * row_cost + cols * col_cost, so a
  // pair is worth taking when its reduced cost is negative. Each row also gets a private "stay
  // unassigned" column of reduced cost 0; the problem is then rows x (cols + rows), solved in
  // O(rows^2 (cols + rows)). Forbidden or unprofitable pairs get a price above any alternative.
  const double leave_both = unassigned_row_cost + unassigned_col_cost;
  const double big = 1.0;  // reduced costs of usable pairs are < 0, the private columns 0
  const int m = cols + rows;
  std::vector<double> reduced(static_cast<std::size_t>(rows) * m, big);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      const double c = cost[static_cast<std::size_t>(i) * cols + j];
      if (std::isfinite(c) && c < leave_both) reduced[static_cast<std::size_t>(i) * m + j] = c - leave_both;
    }
    reduced[static_cast<std::size_t>(i) * m + cols + i] = 0.0;
  }
  const auto matching = hungarian(reduced, rows, m);
  for (int i = 0; i < rows; ++i) {
    const int j = matching[i];
    if (j >= 0 && j < cols && reduced[static_cast<std::size_t>(i) * m + j] < 0.0) result[i] = j;
  }
  return result;
}

double gate_radius2(const Eigen::Matrix2d& S, double gate_chi2) {
  const double half_trace = 0.5 * S.trace();
  const double largest = half_trace + std::sqrt(std::max(0.0, half_trace * half_trace - S.determinant()));
  return gate_chi2 * largest;
}

namespace {

// Sorted distinct values of `values`, and the index of a value in them.
std::vector<std::size_t> distinct(std::vector<std::size_t> values) {
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
  return values;
}

std::size_t index_of(const std::vector<std::size_t>& sorted, std::size_t value) {
  return static_cast<std::size_t>(std::lower_bound(sorted.begin(), sorted.end(), value) - sorted.begin());
}

// Optimal assignment within one cluster (pair indices `members`), appended to `chosen`.
void solve_cluster(const std::vector<GatedPair>& pairs, const std::vector<std::size_t>& members,
                   double unassigned_cost, std::vector<std::pair<std::size_t, std::size_t>>& chosen) {
  if (members.size() == 1) {
    const GatedPair& only = pairs[members[0]];
    if (only.cost < 2.0 * unassigned_cost) chosen.emplace_back(only.row, only.col);
    return;
  }
  std::vector<std::size_t> rows, cols;
  for (std::size_t k : members) {
    rows.push_back(pairs[k].row);
    cols.push_back(pairs[k].col);
  }
  rows = distinct(std::move(rows));
  cols = distinct(std::move(cols));
  std::vector<double> cost(rows.size() * cols.size(), kForbidden);
  for (std::size_t k : members) {
    double& c = cost[index_of(rows, pairs[k].row) * cols.size() + index_of(cols, pairs[k].col)];
    c = std::min(c, pairs[k].cost);
  }
  const auto solution = solve_assignment(cost, static_cast<int>(rows.size()), static_cast<int>(cols.size()),
                                         unassigned_cost, unassigned_cost);
  for (std::size_t r = 0; r < rows.size(); ++r)
    if (solution[r] >= 0) chosen.emplace_back(rows[r], cols[static_cast<std::size_t>(solution[r])]);
}

}  // namespace

std::vector<std::pair<std::size_t, std::size_t>> assign_gated(const std::vector<GatedPair>& pairs,
                                                              double unassigned_cost) {
  std::vector<std::pair<std::size_t, std::size_t>> chosen;
  if (pairs.empty()) return chosen;
  std::vector<std::size_t> rows, cols;
  for (const auto& pair : pairs) {
    rows.push_back(pair.row);
    cols.push_back(pair.col);
  }
  rows = distinct(std::move(rows));
  cols = distinct(std::move(cols));
  // Union-find over row nodes 0..rows-1 and column nodes rows..rows+cols-1.
  UnionFind clusters(rows.size() + cols.size());
  for (const auto& pair : pairs)
    clusters.unite(index_of(rows, pair.row), rows.size() + index_of(cols, pair.col));
  std::map<std::size_t, std::vector<std::size_t>> members_of_root;
  for (std::size_t k = 0; k < pairs.size(); ++k)
    members_of_root[clusters.find(index_of(rows, pairs[k].row))].push_back(k);
  for (const auto& [root, members] : members_of_root) solve_cluster(pairs, members, unassigned_cost, chosen);
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

}  // namespace panoptes::estimator
