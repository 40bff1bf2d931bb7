// SPDX-License-Identifier: Apache-2.0
// Image points sorted by x: the points near a pixel are a short run of the sorted list. Building
// costs a sort of the points, not a table of the image's cells, and a query scans the points in a
// band of x, so it suits a few tens of points per image and small radii (the continuous
// calibration's residuals and resections: issue 36's cost, docs/continuous_calibration.md).
// Association's gating, with radii up to hundreds of pixels, uses BlobGrid.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace panoptes::estimator {

// The point nearest a pixel and the distances of the nearest two (infinite when absent).
struct NearestTwo {
  std::size_t index = 0;
  double d1 = std::numeric_limits<double>::infinity();
  double d2 = std::numeric_limits<double>::infinity();
};

class PointsByX {
 public:
  // Keeps a reference to `points`, which must outlive it. Points that are not finite are left out.
  explicit PointsByX(const std::vector<Eigen::Vector2d>& points) : points_(&points) {
    sorted_.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
      if (points[i].allFinite()) sorted_.emplace_back(points[i].x(), i);
    std::sort(sorted_.begin(), sorted_.end());
  }

  // Looks only within `reach` of `at`: exact for every distance up to `reach`, infinite beyond.
  // Ties go to the lower index.
  NearestTwo nearest_two(const Eigen::Vector2d& at, double reach) const {
    NearestTwo n;
    const double reach2 = reach * reach;
    double d1 = std::numeric_limits<double>::infinity();  // squared until the end
    double d2 = d1;
    for (auto it = first_from(at.x() - reach); it != sorted_.end() && it->first <= at.x() + reach; ++it) {
      const double d = ((*points_)[it->second] - at).squaredNorm();
      if (d > reach2) continue;
      if (d < d1 || (d == d1 && it->second < n.index)) {
        d2 = d1;
        d1 = d;
        n.index = it->second;
      } else if (d < d2) {
        d2 = d;
      }
    }
    n.d1 = std::sqrt(d1);
    n.d2 = std::sqrt(d2);
    return n;
  }

  // nearest_two(at, ratio x radius) where it matters: a nearest point within `radius` and whether
  // the next is `ratio` times farther. Looks within ratio x `near` first (the nearest is usually
  // that near) and searches the whole reach only when that finds nothing within `near`.
  NearestTwo nearest_two(const Eigen::Vector2d& at, double near, double radius, double ratio) const {
    if (near < radius) {
      const NearestTwo close = nearest_two(at, ratio * near);
      if (close.d1 <= near) return close;  // a nearer point, or a second one, would be within reach
    }
    return nearest_two(at, ratio * radius);
  }

  bool any_within(const Eigen::Vector2d& at, double radius) const {
    const double radius2 = radius * radius;
    for (auto it = first_from(at.x() - radius); it != sorted_.end() && it->first <= at.x() + radius; ++it)
      if (((*points_)[it->second] - at).squaredNorm() <= radius2) return true;
    return false;
  }

  // By point: whether another point lies within `radius` of it.
  std::vector<char> crowded(double radius) const {
    std::vector<char> crowded(points_->size(), 0);
    const double radius2 = radius * radius;
    for (std::size_t a = 0; a < sorted_.size(); ++a) {
      for (std::size_t b = a + 1; b < sorted_.size() && sorted_[b].first - sorted_[a].first <= radius; ++b) {
        if (((*points_)[sorted_[b].second] - (*points_)[sorted_[a].second]).squaredNorm() > radius2) continue;
        crowded[sorted_[a].second] = 1;
        crowded[sorted_[b].second] = 1;
      }
    }
    return crowded;
  }

 private:
  using Entry = std::pair<double, std::size_t>;  // (x, index)
  std::vector<Entry>::const_iterator first_from(double x) const {
    return std::lower_bound(sorted_.begin(), sorted_.end(), x,
                            [](const Entry& entry, double value) { return entry.first < value; });
  }

  const std::vector<Eigen::Vector2d>* points_;
  std::vector<Entry> sorted_;
};

}  // namespace panoptes::estimator
