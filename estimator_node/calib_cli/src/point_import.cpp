// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/point_import.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace panoptes::calib {

namespace {

// Rows of numbers ("nan" accepted), blank lines skipped.
std::vector<std::vector<double>> read_rows(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot read");
  std::vector<std::vector<double>> rows;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream fields(line);
    std::vector<double> row;
    for (std::string field; fields >> field;) {
      try {
        std::size_t used = 0;
        row.push_back(std::stod(field, &used));
        if (used != field.size()) throw std::invalid_argument(field);
      } catch (const std::exception&) {
        throw std::runtime_error(path.string() + ": line " + std::to_string(number) + ": '" + field +
                                 "' is not a number");
      }
    }
    if (!row.empty()) rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace

PointTable read_multicam_points(const std::filesystem::path& path) {
  const auto rows = read_rows(path);
  if (rows.empty() || rows.size() % 3 != 0)
    throw std::runtime_error(path.string() + ": expected 3 rows per camera (x, y, 1), got " +
                             std::to_string(rows.size()) + " rows");
  PointTable table;
  table.frames = static_cast<int>(rows.front().size());
  for (std::size_t r = 0; r < rows.size(); ++r)
    if (rows[r].size() != rows.front().size())
      throw std::runtime_error(path.string() + ": row " + std::to_string(r + 1) + " has " +
                               std::to_string(rows[r].size()) + " columns, row 1 has " +
                               std::to_string(rows.front().size()));
  for (std::size_t c = 0; c < rows.size() / 3; ++c) {
    const auto& x = rows[3 * c];
    const auto& y = rows[3 * c + 1];
    auto& camera = table.cameras.emplace_back(static_cast<std::size_t>(table.frames));
    for (int f = 0; f < table.frames; ++f) {
      const auto i = static_cast<std::size_t>(f);
      if (std::isfinite(x[i]) && std::isfinite(y[i])) camera[i] = Eigen::Vector2d(x[i], y[i]);
    }
  }
  return table;
}

std::vector<std::pair<int, int>> read_multicam_resolutions(const std::filesystem::path& path) {
  std::vector<std::pair<int, int>> sizes;
  const auto rows = read_rows(path);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    if (rows[r].size() != 2 || !(rows[r][0] >= 1) || !(rows[r][1] >= 1))
      throw std::runtime_error(path.string() + ": row " + std::to_string(r + 1) +
                               ": expected 'width height' (positive)");
    sizes.emplace_back(static_cast<int>(rows[r][0]), static_cast<int>(rows[r][1]));
  }
  return sizes;
}

std::vector<FeatureFrame> point_feature_frames(const PointTable& table, const std::vector<std::string>& ids,
                                               double rate_hz, TimeNs start_ns) {
  if (ids.size() != table.cameras.size())
    throw std::invalid_argument("point_feature_frames: " + std::to_string(ids.size()) + " ids for " +
                                std::to_string(table.cameras.size()) + " cameras");
  const auto period = static_cast<TimeNs>(std::llround(1e9 / rate_hz));
  std::vector<FeatureFrame> frames;
  for (std::size_t c = 0; c < table.cameras.size(); ++c)
    for (int f = 0; f < table.frames; ++f) {
      FeatureFrame frame;
      frame.camera_id = ids[c];
      frame.frame = f;
      frame.stamp_ns = start_ns + period * f;
      if (const auto& pixel = table.cameras[c][static_cast<std::size_t>(f)]) {
        Blob blob;
        blob.x = pixel->x();
        blob.y = pixel->y();
        blob.area = 1;
        blob.x0 = static_cast<int>(std::floor(blob.x));
        blob.y0 = static_cast<int>(std::floor(blob.y));
        blob.x1 = blob.x0 + 1;
        blob.y1 = blob.y0 + 1;
        frame.blobs.push_back(blob);
      }
      frames.push_back(std::move(frame));
    }
  return frames;
}

CameraCalibration nominal_camera(const std::string& id, int width, int height, double focal_px) {
  CameraCalibration camera;
  camera.id = id;
  camera.intrinsics.width = width;
  camera.intrinsics.height = height;
  camera.intrinsics.fx = camera.intrinsics.fy = focal_px;
  camera.intrinsics.cx = (width - 1) / 2.0;
  camera.intrinsics.cy = (height - 1) / 2.0;
  camera.nominal_intrinsics = true;
  return camera;
}

}  // namespace panoptes::calib
