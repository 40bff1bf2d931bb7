// SPDX-License-Identifier: Apache-2.0
// Where in a camera's image blobs have been seen, on an 8x8 grid: the coverage figure a wand
// capture shows per camera (`estimator_node calibrate capture`, the console's calibration page;
// docs/calibration.md, step 2). Before the image size is known, the grid spans the blobs seen.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <string>

namespace panoptes {

class ImageCoverage {
 public:
  static constexpr int kCells = 8;
  static constexpr std::size_t kCellCount = 64;  // kCells x kCells

  void set_size(int width, int height) {
    width_ = width;
    height_ = height;
  }
  void add(double x, double y) {
    const double w = width_ > 0 ? width_ : std::max(max_x_, x + 1);
    const double h = height_ > 0 ? height_ : std::max(max_y_, y + 1);
    max_x_ = std::max(max_x_, x + 1);
    max_y_ = std::max(max_y_, y + 1);
    const int column = std::clamp(static_cast<int>(x * kCells / w), 0, kCells - 1);
    const int row = std::clamp(static_cast<int>(y * kCells / h), 0, kCells - 1);
    cells_[static_cast<std::size_t>(row) * kCells + static_cast<std::size_t>(column)] = true;
  }
  int percent() const { return static_cast<int>(covered() * 100 / static_cast<long>(kCellCount)); }
  double fraction() const { return static_cast<double>(covered()) / static_cast<double>(kCellCount); }
  // Row by row from the top left, '1' where a blob was seen.
  std::string cells() const {
    std::string out;
    for (const bool cell : cells_) out += cell ? '1' : '0';
    return out;
  }

 private:
  long covered() const { return static_cast<long>(std::count(cells_.begin(), cells_.end(), true)); }

  int width_ = 0;
  int height_ = 0;
  double max_x_ = 1;
  double max_y_ = 1;
  std::array<bool, kCellCount> cells_{};
};

}  // namespace panoptes
