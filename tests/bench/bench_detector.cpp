// SPDX-License-Identifier: Apache-2.0
// Detector::detect against OpenCV's threshold + findContours + moments and against a memcpy of
// the same frame (the floor any per-frame pass pays), on a 2048x2048 8-bit frame with 40 spots.
#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <vector>

#include "panoptes/camera/detector.h"

namespace {

constexpr int kSize = 2048;
constexpr int kSpots = 40;

const panoptes::Image& frame() {
  static const panoptes::Image image = [] {
    std::mt19937_64 rng(2048);
    std::uniform_real_distribution<double> position(20.0, kSize - 20.0);
    std::uniform_real_distribution<double> sigma(0.8, 3.0);
    std::normal_distribution<double> noise(0.0, 2.0);
    std::vector<double> values(static_cast<std::size_t>(kSize) * kSize, 10.0);
    for (int s = 0; s < kSpots; ++s) {
      const double cx = position(rng), cy = position(rng), sd = sigma(rng);
      const double scale = 1.0 / (std::sqrt(2.0) * sd);
      const double gain = 200.0 * 2.0 * std::numbers::pi * sd * sd;
      const auto mass = [scale](int i, double c) {
        return 0.5 * (std::erf((i + 0.5 - c) * scale) - std::erf((i - 0.5 - c) * scale));
      };
      for (int y = static_cast<int>(cy) - 12; y <= static_cast<int>(cy) + 12; ++y) {
        for (int x = static_cast<int>(cx) - 12; x <= static_cast<int>(cx) + 12; ++x) {
          values[static_cast<std::size_t>(y) * kSize + x] += gain * mass(x, cx) * mass(y, cy);
        }
      }
    }
    panoptes::Image result(kSize, kSize, 8);
    for (std::size_t i = 0; i < values.size(); ++i) {
      result.data[i] = static_cast<std::uint8_t>(std::clamp(std::round(values[i] + noise(rng)), 0.0, 255.0));
    }
    return result;
  }();
  return image;
}

void BM_Detector(benchmark::State& state) {
  const panoptes::Image& image = frame();
  panoptes::camera::Detector detector;
  std::size_t blobs = 0;
  for (auto _ : state) {
    const auto found = detector.detect(image);
    blobs = found.size();
    benchmark::DoNotOptimize(found.data());
  }
  state.counters["blobs"] = static_cast<double>(blobs);
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(image.data.size()));
}
BENCHMARK(BM_Detector)->Unit(benchmark::kMicrosecond);

void BM_OpenCvContoursMoments(benchmark::State& state) {
  const panoptes::Image& image = frame();
  const cv::Mat input(kSize, kSize, CV_8UC1, const_cast<std::uint8_t*>(image.data.data()));
  cv::Mat binary;
  std::vector<std::vector<cv::Point>> contours;
  std::size_t blobs = 0;
  for (auto _ : state) {
    cv::threshold(input, binary, 64, 255, cv::THRESH_BINARY);
    cv::findContours(binary, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    double checksum = 0;
    for (const auto& contour : contours) {
      // Intensity moments over each blob's bounding box, the nearest OpenCV equivalent of a
      // weighted centroid.
      const cv::Rect box = cv::boundingRect(contour);
      const cv::Moments m = cv::moments(input(box), false);
      if (m.m00 > 0) checksum += m.m10 / m.m00 + box.x;
    }
    blobs = contours.size();
    benchmark::DoNotOptimize(checksum);
  }
  state.counters["blobs"] = static_cast<double>(blobs);
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(image.data.size()));
}
BENCHMARK(BM_OpenCvContoursMoments)->Unit(benchmark::kMicrosecond);

void BM_Memcpy(benchmark::State& state) {
  const panoptes::Image& image = frame();
  std::vector<std::uint8_t> copy(image.data.size());
  for (auto _ : state) {
    std::memcpy(copy.data(), image.data.data(), image.data.size());
    benchmark::DoNotOptimize(copy.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(image.data.size()));
}
BENCHMARK(BM_Memcpy)->Unit(benchmark::kMicrosecond);

}  // namespace
