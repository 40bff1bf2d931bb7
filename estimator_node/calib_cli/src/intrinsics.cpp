// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/intrinsics.h"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "panoptes/image_file_cv.h"

namespace panoptes::calib {
namespace {

// 8-bit grey for the corner detector; deeper images scaled from their significant bits.
cv::Mat grey8_mat(const Image& image) {
  cv::Mat mat = to_mat(image);
  if (image.bits > 8) mat.convertTo(mat, CV_8U, 255.0 / image.max_value());
  return mat;
}

}  // namespace

ChessboardResult calibrate_chessboard(const std::vector<std::filesystem::path>& images,
                                      const ChessboardOptions& options) {
  ChessboardResult result;
  if (options.cols < 2 || options.rows < 2 || !(options.square_m > 0)) {
    result.error = "--board needs at least 2x2 inner corners and --square a positive size";
    return result;
  }
  std::vector<cv::Point3f> board;
  for (int r = 0; r < options.rows; ++r)
    for (int c = 0; c < options.cols; ++c)
      board.emplace_back(static_cast<float>(c * options.square_m), static_cast<float>(r * options.square_m),
                         0.0f);
  std::vector<std::vector<cv::Point3f>> object_points;
  std::vector<std::vector<cv::Point2f>> image_points;
  cv::Size size;
  for (std::size_t i = 0; i < images.size(); ++i) {
    cv::Mat image;
    try {
      image = grey8_mat(read_grey_image(images[i]));
    } catch (const std::runtime_error& error) {
      result.error = std::string(error.what()) + " (cannot read the image)";
      return result;
    }
    if (size.width != 0 && image.size() != size) {
      // Another camera's picture caught by the glob: it cannot share one set of intrinsics.
      result.rejected.push_back(images[i]);
      if (options.progress)
        options.progress("image " + std::to_string(i + 1) + "/" + std::to_string(images.size()) + " " +
                         images[i].filename().string() +
                         ": skipped, size differs from the first board image's");
      continue;
    }
    std::vector<cv::Point2f> corners;
    const bool found = cv::findChessboardCorners(image, {options.cols, options.rows}, corners,
                                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
    if (!found) {
      result.rejected.push_back(images[i]);
      if (options.progress)
        options.progress("image " + std::to_string(i + 1) + "/" + std::to_string(images.size()) + " " +
                         images[i].filename().string() + ": no board");
      continue;
    }
    if (size.width == 0) size = image.size();
    cv::cornerSubPix(image, corners, {11, 11}, {-1, -1},
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 0.0001));
    object_points.push_back(board);
    image_points.push_back(corners);
    result.used.push_back(images[i]);
    if (options.progress)
      options.progress("image " + std::to_string(i + 1) + "/" + std::to_string(images.size()) + " " +
                       images[i].filename().string() + ": board found");
  }
  if (object_points.size() < 3) {
    result.error = "a " + std::to_string(options.cols) + "x" + std::to_string(options.rows) +
                   " board was found in " + std::to_string(object_points.size()) + " of " +
                   std::to_string(images.size()) +
                   " images; need at least 3 (is --board the count of inner corners?)";
    return result;
  }
  cv::Mat K, distortion;
  std::vector<cv::Mat> rvecs, tvecs;
  result.rms_px = cv::calibrateCamera(object_points, image_points, size, K, distortion, rvecs, tvecs, 0);
  for (std::size_t i = 0; i < object_points.size(); ++i) {
    std::vector<cv::Point2f> projected;
    cv::projectPoints(object_points[i], rvecs[i], tvecs[i], K, distortion, projected);
    double squared = 0;
    for (std::size_t k = 0; k < projected.size(); ++k) {
      const cv::Point2f d = projected[k] - image_points[i][k];
      squared += d.dot(d);
    }
    result.per_image_rms_px.push_back(std::sqrt(squared / static_cast<double>(projected.size())));
  }
  auto& k = result.intrinsics;
  k.width = size.width;
  k.height = size.height;
  k.fx = K.at<double>(0, 0);
  k.fy = K.at<double>(1, 1);
  k.cx = K.at<double>(0, 2);
  k.cy = K.at<double>(1, 2);
  for (int i = 0; i < 5 && i < static_cast<int>(distortion.total()); ++i)
    k.distortion[static_cast<std::size_t>(i)] = distortion.at<double>(i);
  return result;
}

}  // namespace panoptes::calib
