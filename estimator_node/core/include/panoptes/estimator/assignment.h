// SPDX-License-Identifier: Apache-2.0
// Minimum-cost assignment between rows (tracks) and columns (blobs) where a row or a column may
// also stay unassigned at a price: the global nearest-neighbour step of data association
// (seed 003 §2.2.3.2 matches each point to its closest dot; we solve all points jointly).
#pragma once

#include <limits>
#include <vector>

namespace panoptes::estimator {

// Pairs that may not be assigned (outside the gate) carry this cost.
inline constexpr double kForbidden = std::numeric_limits<double>::infinity();

// `cost` is rows x cols, row-major. Leaving a row unassigned costs `unassigned_row_cost`, a column
// `unassigned_col_cost`; a pair is chosen only when it is cheaper than leaving both unassigned.
// Returns, for each row, its column or -1. Hungarian method with potentials on the
// (rows + cols)-square problem that adds one "unassigned" slot per row and per column: O((r+c)^3).
std::vector<int> solve_assignment(const std::vector<double>& cost, int rows, int cols,
                                  double unassigned_row_cost, double unassigned_col_cost);

}  // namespace panoptes::estimator
