// SPDX-License-Identifier: Apache-2.0
// Gated assignment: the one data-association module of points (tracker) and bodies (markers).
// Rows (tracks, body markers) and columns (blobs) are paired when a measurement passes the
// row's chi-square gate; the gated pairs form a sparse cost list (d², the squared Mahalanobis
// distance), which splits into independent clusters (rows and columns linked by gated pairs),
// each solved as a minimum-cost assignment where a row or a column may also stay unassigned at a
// price: the global nearest-neighbour step of data association (seed 003 §2.2.3.2 matches each
// point to its closest dot; we solve all points jointly).
#pragma once

#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace panoptes::estimator {

// Pairs that may not be assigned (outside the gate) carry this cost.
inline constexpr double kForbidden = std::numeric_limits<double>::infinity();

// `cost` is rows x cols, row-major. Leaving a row unassigned costs `unassigned_row_cost`, a column
// `unassigned_col_cost`; a pair is chosen only when it is cheaper than leaving both unassigned.
// Returns, for each row, its column or -1. Hungarian method with potentials on the
// (rows + cols)-square problem that adds one "unassigned" slot per row and per column: O((r+c)^3).
std::vector<int> solve_assignment(const std::vector<double>& cost, int rows, int cols,
                                  double unassigned_row_cost, double unassigned_col_cost);

// The chi-square gate: a measurement with squared Mahalanobis distance d² belongs to a row's
// verify region when d² < chi2 (seed 003 §2.2.3.2).
inline bool inside_gate(double d2, double gate_chi2) {
  return d2 < gate_chi2;
}

// Radius² (px²) of the circle that holds the gate d² < chi2 of innovation covariance S: chi2 times
// S's largest eigenvalue (2 x 2, closed form). Blobs outside it need no Mahalanobis test.
double gate_radius2(const Eigen::Matrix2d& S, double gate_chi2);

// One pair that passed the gate, with its cost (usually d²).
struct GatedPair {
  std::size_t row = 0;
  std::size_t col = 0;
  double cost = 0.0;
};

// The best assignment among `pairs` (at most one pair per row and per column): leaving a row and a
// column both unassigned costs `unassigned_cost` each, so any pair cheaper than 2 · unassigned_cost
// is preferred to none. The pairs split into clusters by union-find over rows and columns; a
// cluster of one pair is taken as is, larger ones are solved with solve_assignment (Hungarian), so
// the cost follows the clusters, not the whole frame. Returns the chosen (row, col) by row.
std::vector<std::pair<std::size_t, std::size_t>> assign_gated(const std::vector<GatedPair>& pairs,
                                                              double unassigned_cost);

}  // namespace panoptes::estimator
