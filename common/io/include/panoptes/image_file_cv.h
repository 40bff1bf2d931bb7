// SPDX-License-Identifier: Apache-2.0
// panoptes/image_file.h for code that draws with OpenCV: a cv::Mat as pixels to write, a decoded
// Picture or Image as a cv::Mat. Header only: panoptes_io itself does not link OpenCV; includers do
// (opencv_core).
#pragma once

#include <cstring>

#include <opencv2/core.hpp>

#include "panoptes/image_file.h"

namespace panoptes {

// The pixels of an 8-bit grey, BGR or BGRA or a 16-bit grey matrix, for encode_png / write_png.
inline PixelsView view_of(const cv::Mat& mat) {
  return {mat.cols, mat.rows, mat.channels(), mat.depth() == CV_16U ? 16 : 8, mat.data, mat.step[0]};
}

// A copy of the picture as CV_8UC1/CV_8UC3/CV_16UC1/CV_16UC3 (B, G, R).
inline cv::Mat to_mat(const Picture& picture) {
  cv::Mat mat(picture.height, picture.width,
              CV_MAKETYPE(picture.bits == 16 ? CV_16U : CV_8U, picture.channels));
  for (int y = 0; y < picture.height; ++y)
    std::memcpy(mat.ptr(y), picture.data.data() + y * picture.stride(), picture.stride());
  return mat;
}

// A copy of the image as CV_8UC1, or CV_16UC1 for more than 8 bits.
inline cv::Mat to_mat(const Image& image) {
  cv::Mat mat(image.height, image.width, image.bits > 8 ? CV_16UC1 : CV_8UC1);
  for (int y = 0; y < image.height; ++y) std::memcpy(mat.ptr(y), image.row8(y), image.stride());
  return mat;
}

}  // namespace panoptes
