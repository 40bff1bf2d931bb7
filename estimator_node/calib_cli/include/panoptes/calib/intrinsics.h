// SPDX-License-Identifier: Apache-2.0
// Intrinsics of one camera from chessboard images (OpenCV's detector and calibrateCamera).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "panoptes/camera_model.h"

namespace panoptes::calib {

struct ChessboardOptions {
  int cols = 9;  // inner corners per row
  int rows = 6;  // inner corners per column
  double square_m = 0.025;
  std::function<void(const std::string&)> progress;
};

struct ChessboardResult {
  CameraIntrinsics intrinsics;
  double rms_px = 0;                                  // OpenCV's RMS reprojection error (2D norm)
  std::vector<std::filesystem::path> used, rejected;  // images with and without a board found
  std::vector<double> per_image_rms_px;               // for `used`
  std::string error;                                  // "" on success
};

// Never throws: problems go to `error` (naming the file where one is at fault).
ChessboardResult calibrate_chessboard(const std::vector<std::filesystem::path>& images,
                                      const ChessboardOptions& options);

}  // namespace panoptes::calib
