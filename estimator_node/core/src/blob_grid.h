// SPDX-License-Identifier: Apache-2.0
// Uniform grid over one image's blobs, so that finding the blobs near a predicted track costs
// what is near it and not the whole frame (association stays linear in tracks + blobs).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace panoptes::estimator {

class BlobGrid {
 public:
  // Blobs outside the image are kept in the border cells.
  BlobGrid(const std::vector<Eigen::Vector2d>& points, int width, int height, double cell_px)
      : cell_(std::max(cell_px, 1.0)),
        nx_(std::max(1, static_cast<int>(std::ceil(std::max(width, 1) / cell_)))),
        ny_(std::max(1, static_cast<int>(std::ceil(std::max(height, 1) / cell_)))),
        start_(static_cast<std::size_t>(nx_) * ny_ + 1, 0),
        items_(points.size()) {
    std::vector<std::uint32_t> cell_of(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      cell_of[i] = static_cast<std::uint32_t>(cell_index(points[i]));
      ++start_[cell_of[i] + 1];
    }
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < points.size(); ++i)
      items_[fill[cell_of[i]]++] = static_cast<std::uint32_t>(i);
  }

  // Calls f(index) for every blob in the cells that overlap the square of half-size `radius`
  // around `center` (a superset of the blobs within `radius`).
  template <class F>
  void for_each_near(const Eigen::Vector2d& center, double radius, F&& f) const {
    const int x0 = clamp_x(std::floor((center.x() - radius) / cell_));
    const int x1 = clamp_x(std::floor((center.x() + radius) / cell_));
    const int y0 = clamp_y(std::floor((center.y() - radius) / cell_));
    const int y1 = clamp_y(std::floor((center.y() + radius) / cell_));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const std::size_t c = static_cast<std::size_t>(y) * nx_ + x;
        for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k) f(static_cast<std::size_t>(items_[k]));
      }
    }
  }

 private:
  int clamp_x(double v) const { return static_cast<int>(std::clamp(v, 0.0, static_cast<double>(nx_ - 1))); }
  int clamp_y(double v) const { return static_cast<int>(std::clamp(v, 0.0, static_cast<double>(ny_ - 1))); }
  std::size_t cell_index(const Eigen::Vector2d& p) const {
    const double fx = std::isfinite(p.x()) ? p.x() / cell_ : 0.0;
    const double fy = std::isfinite(p.y()) ? p.y() / cell_ : 0.0;
    return static_cast<std::size_t>(clamp_y(std::floor(fy))) * nx_ + clamp_x(std::floor(fx));
  }

  double cell_;
  int nx_, ny_;
  std::vector<std::uint32_t> start_;  // CSR: blobs of cell c are items_[start_[c] .. start_[c+1])
  std::vector<std::uint32_t> items_;
};

}  // namespace panoptes::estimator
