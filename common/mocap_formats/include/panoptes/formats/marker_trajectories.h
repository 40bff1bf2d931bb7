// SPDX-License-Identifier: Apache-2.0
// Labelled marker trajectories sampled at a fixed rate: what C3D, TRC and the marker CSV hold.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace panoptes {

// Positions are in metres whatever the file's units; axes stay as in the file. Per-sample arrays
// are frame-major: [frame * marker_count() + marker].
struct MarkerTrajectories {
  double data_rate_hz = 0.0;
  std::string units;  // as written in (or to be written to) the file: "mm", "cm" or "m"
  std::vector<std::string> marker_names;
  std::vector<double> times_s;             // one entry per frame, strictly increasing
  std::vector<Eigen::Vector3d> positions;  // metres
  std::vector<std::uint8_t> valid;         // 0 where the file has no data for the marker
  // Optional (C3D): empty, or one entry per sample. residual_m: the measurement residual in
  // metres, 0 for a point that was computed (interpolated, predicted) rather than measured;
  // camera_mask: bit i set when camera i + 1 contributed (7 cameras at most, C3D's limit).
  std::vector<float> residuals_m;
  std::vector<std::uint8_t> camera_masks;

  std::size_t frame_count() const { return times_s.size(); }
  std::size_t marker_count() const { return marker_names.size(); }
  const Eigen::Vector3d& position(std::size_t frame, std::size_t marker) const {
    return positions[frame * marker_count() + marker];
  }
  bool is_valid(std::size_t frame, std::size_t marker) const {
    return valid[frame * marker_count() + marker] != 0;
  }
};

// Metres per unit for "mm", "cm" and "m"; 0 for anything else.
double metres_per_unit(const std::string& units);

}  // namespace panoptes
