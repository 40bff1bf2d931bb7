// SPDX-License-Identifier: Apache-2.0
// Whether a 3 × 3 covariance's largest eigenvalue is within a bound, without an eigen-decomposition.
#pragma once

#include <Eigen/Core>

namespace panoptes {

// True when the largest eigenvalue of the symmetric matrix P is at most `bound` (bound ≥ 0), that
// is when bound·I − P is positive semidefinite: all its principal minors (three diagonal entries,
// three 2 × 2 minors and the determinant) are ≥ 0 (Sylvester's criterion for semidefinite
// matrices; the leading minors alone would not do). P need not be semidefinite itself. About
// thirty flops instead of a 3 × 3 eigen-solve: the tracker asks this of every track record (it
// publishes a position only while it is determined). On the boundary rounding may answer either way.
inline bool largest_eigenvalue_at_most(const Eigen::Matrix3d& P, double bound) {
  const double a = bound - P(0, 0), b = bound - P(1, 1), c = bound - P(2, 2);
  const double ab = -P(0, 1), ac = -P(0, 2), bc = -P(1, 2);
  if (a < 0 || b < 0 || c < 0) return false;
  if (a * b - ab * ab < 0 || a * c - ac * ac < 0 || b * c - bc * bc < 0) return false;
  const double determinant = a * (b * c - bc * bc) - ab * (ab * c - bc * ac) + ac * (ab * bc - b * ac);
  return determinant >= 0;
}

}  // namespace panoptes
