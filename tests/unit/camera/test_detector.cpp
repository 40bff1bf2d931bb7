// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "panoptes/camera/detector.h"
#include "panoptes/config.h"
#include "spot_renderer.h"

namespace panoptes::camera {
namespace {

using testing::random_spot_grid;
using testing::render_spots;
using testing::Spot;

Image image_from_rows(const std::vector<std::vector<int>>& rows, int bits = 8) {
  Image image(static_cast<int>(rows.front().size()), static_cast<int>(rows.size()), bits);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      if (bits > 8) {
        image.row16(y)[x] = static_cast<std::uint16_t>(rows[y][x]);
      } else {
        image.row8(y)[x] = static_cast<std::uint8_t>(rows[y][x]);
      }
    }
  }
  return image;
}

int pixel(const Image& image, int x, int y) {
  return image.bytes_per_pixel() == 1 ? image.row8(y)[x] : image.row16(y)[x];
}

DetectorConfig permissive(int threshold) {
  DetectorConfig config;
  config.threshold = threshold;
  config.min_area = 1;
  config.max_area = std::numeric_limits<int>::max();
  config.refine_margin = 0;  // exact moments of the pixels above threshold
  return config;
}

struct Accuracy {
  double bias_x = 0, bias_y = 0, rms = 0, max_error = 0;
  int truths = 0, detected = 0, false_blobs = 0;
};

// Each truth matched to its nearest blob within 2 px; blobs matching no truth are false.
void score(const std::vector<Spot>& truths, const std::vector<Blob>& blobs, Accuracy& accuracy,
           double* sum_squares) {
  std::vector<bool> used(blobs.size(), false);
  for (const Spot& truth : truths) {
    ++accuracy.truths;
    int best = -1;
    double best_distance = 2.0;
    for (std::size_t i = 0; i < blobs.size(); ++i) {
      const double distance = std::hypot(blobs[i].x - truth.x, blobs[i].y - truth.y);
      if (distance < best_distance) {
        best_distance = distance;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) continue;
    used[best] = true;
    ++accuracy.detected;
    accuracy.bias_x += blobs[best].x - truth.x;
    accuracy.bias_y += blobs[best].y - truth.y;
    *sum_squares += best_distance * best_distance;
    accuracy.max_error = std::max(accuracy.max_error, best_distance);
  }
  for (bool u : used) accuracy.false_blobs += u ? 0 : 1;
}

struct Scenario {
  CentroidWeighting weighting = CentroidWeighting::kIntensitySquared;
  double noise_dn = 0;
  int frames = 4;
  std::uint64_t seed = 11;
  int refine_margin = DetectorConfig{}.refine_margin;
  int bits = 8;  // 12 and 16 render the same picture times 16 in 16-bit words
};

// Spots of sigma 0.8-3 px at random sub-pixel positions, peaks 120-400 DN on a 10 DN background,
// so about half of them saturate at 255.
Accuracy measure(const Scenario& scenario) {
  std::mt19937_64 rng(scenario.seed);
  DetectorConfig config;
  config.weighting = scenario.weighting;
  config.refine_margin = scenario.refine_margin;
  if (scenario.bits == 16) config.threshold = 64 * 16;  // the 16-bit default would be 16384
  Detector detector(config);
  Accuracy accuracy;
  double sum_squares = 0;
  const double gain = scenario.bits > 8 ? 16.0 : 1.0;
  for (int frame = 0; frame < scenario.frames; ++frame) {
    const std::vector<Spot> spots = random_spot_grid(640, 480, 32, 0.8, 3.0, rng, 120, 400);
    const Image image = render_spots(640, 480, spots, 10, scenario.noise_dn, &rng, gain, scenario.bits);
    score(spots, detector.detect(image), accuracy, &sum_squares);
  }
  if (accuracy.detected > 0) {
    accuracy.bias_x /= accuracy.detected;
    accuracy.bias_y /= accuracy.detected;
    accuracy.rms = std::sqrt(sum_squares / accuracy.detected);
  }
  return accuracy;
}

void print(const char* label, const Accuracy& a) {
  std::printf(
      "[ accuracy ] %-40s rms %.4f px  max %.4f px  bias (%+.4f, %+.4f) px  detected %d/%d  false %d\n",
      label, a.rms, a.max_error, a.bias_x, a.bias_y, a.detected, a.truths, a.false_blobs);
}

void expect_noise_free_target(const Accuracy& accuracy) {
  EXPECT_EQ(accuracy.detected, accuracy.truths);
  EXPECT_EQ(accuracy.false_blobs, 0);
  EXPECT_LT(std::abs(accuracy.bias_x), 0.01);
  EXPECT_LT(std::abs(accuracy.bias_y), 0.01);
  EXPECT_LT(accuracy.rms, 0.02);
}

// Issue 3 target: noise-free bias < 0.01 px and RMS < 0.02 px, saturated spots included. The
// pixels above threshold alone (seed 004 eq. 1-2 as written) leave the threshold's cut in the
// centroid; the refinement over the grown box removes it.
TEST(Detector, NoiseFreeCentroidsMeetTheAccuracyTarget) {
  const Accuracy refined = measure({});
  const Accuracy cut_only = measure({.refine_margin = 0});
  const Accuracy linear = measure({.weighting = CentroidWeighting::kIntensity});
  print("I^2 refined (default), noise-free", refined);
  print("I^2 above threshold only, noise-free", cut_only);
  print("I refined, noise-free", linear);
  expect_noise_free_target(refined);
  expect_noise_free_target(linear);
  EXPECT_LT(refined.rms, 0.5 * cut_only.rms);
}

TEST(Detector, SixteenBitInputMeetsTheSameTarget) {
  const Accuracy twelve = measure({.bits = 12});
  const Accuracy sixteen = measure({.bits = 16});
  print("I^2 refined, noise-free, 12-bit", twelve);
  print("I^2 refined, noise-free, 16-bit", sixteen);
  expect_noise_free_target(twelve);
  expect_noise_free_target(sixteen);
  const Accuracy noisy = measure({.noise_dn = 2.0, .frames = 10, .seed = 12, .bits = 12});
  print("I^2 refined, noise 2 DN (x16), 12-bit", noisy);
  EXPECT_LT(noisy.rms, 0.04);
}

// Issue 3 target with additive noise of 2 DN: RMS < 0.04 px, detection >= 99%, < 0.1 false
// blobs per frame.
TEST(Detector, NoisyCentroidsMeetTheAccuracyTarget) {
  const int frames = 10;
  const Accuracy accuracy = measure({.noise_dn = 2.0, .frames = frames, .seed = 12});
  print("I^2 refined, noise 2 DN, sigma 0.8-3 px", accuracy);
  EXPECT_GE(accuracy.detected, 0.99 * accuracy.truths);
  EXPECT_LT(accuracy.false_blobs, 0.1 * frames);
  EXPECT_LT(accuracy.rms, 0.04);
}

// Frame-to-frame jitter of a static spot under sensor noise: the property seed 004 §2.2.1 chose
// I^2 weighting for (dim border pixels flicker across the threshold).
double jitter(CentroidWeighting weighting, const std::vector<Spot>& spots, int frames, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  DetectorConfig config;
  config.weighting = weighting;
  Detector detector(config);
  std::vector<double> sum_x(spots.size(), 0), sum_y(spots.size(), 0), sum_xx(spots.size(), 0),
      sum_yy(spots.size(), 0);
  std::vector<int> count(spots.size(), 0);
  const testing::SpotField field = testing::render_field(640, 480, spots, 10);
  for (int frame = 0; frame < frames; ++frame) {
    const Image image = testing::to_image(field, 2.0, &rng);
    for (const Blob& blob : detector.detect(image)) {
      for (std::size_t i = 0; i < spots.size(); ++i) {
        if (std::hypot(blob.x - spots[i].x, blob.y - spots[i].y) < 2.0) {
          sum_x[i] += blob.x;
          sum_y[i] += blob.y;
          sum_xx[i] += blob.x * blob.x;
          sum_yy[i] += blob.y * blob.y;
          ++count[i];
        }
      }
    }
  }
  double variance = 0;
  for (std::size_t i = 0; i < spots.size(); ++i) {
    EXPECT_EQ(count[i], frames) << "spot " << i;
    const double n = count[i];
    const double mean_x = sum_x[i] / n, mean_y = sum_y[i] / n;
    variance += sum_xx[i] / n - mean_x * mean_x + sum_yy[i] / n - mean_y * mean_y;
  }
  return std::sqrt(variance / static_cast<double>(spots.size()));
}

TEST(Detector, IntensitySquaredJittersLessThanIntensityUnderNoise) {
  std::mt19937_64 layout_rng(21);
  const std::vector<Spot> spots = random_spot_grid(640, 480, 32, 0.8, 3.0, layout_rng);
  const double jitter_i2 = jitter(CentroidWeighting::kIntensitySquared, spots, 40, 22);
  const double jitter_i = jitter(CentroidWeighting::kIntensity, spots, 40, 22);
  const double jitter_above = jitter(CentroidWeighting::kAboveThreshold, spots, 40, 22);
  std::printf("[ jitter   ] noise 2 DN, %zu spots x 40 frames: I^2 %.4f px, I %.4f px, I-T %.4f px\n",
              spots.size(), jitter_i2, jitter_i, jitter_above);
  // Seed 004 §2.2.1 reports the reduction qualitatively ("similar to a low-pass filter"); here
  // it is about a third (0.0118 vs 0.0178 px when measured).
  EXPECT_LT(jitter_i2, 0.8 * jitter_i);
}

TEST(Detector, SixteenBitImagesGiveTheSameCentroids) {
  std::mt19937_64 rng(31);
  const std::vector<Spot> spots = random_spot_grid(320, 240, 32, 0.8, 3.0, rng);
  std::mt19937_64 noise_8(32), noise_12(32), noise_16(32);
  const Image image_8 = render_spots(320, 240, spots, 10, 2.0, &noise_8);
  const Image image_12 = render_spots(320, 240, spots, 10, 2.0, &noise_12, 16.0, 12);
  const Image image_16 = render_spots(320, 240, spots, 10, 2.0, &noise_16, 16.0, 16);
  ASSERT_EQ(image_12.bytes_per_pixel(), 2);

  for (const CentroidWeighting weighting :
       {CentroidWeighting::kIntensitySquared, CentroidWeighting::kIntensity,
        CentroidWeighting::kAboveThreshold}) {
    DetectorConfig config;
    config.weighting = weighting;
    Detector detector_default(config);  // 12-bit default threshold is 64 * 16
    config.threshold = 64 * 16;
    Detector detector_explicit(config);  // a 16-bit default (16384) would be above these spots
    const std::vector<Blob> blobs_8 = detector_default.detect(image_8);
    const std::vector<Blob> blobs_12 = detector_default.detect(image_12);
    const std::vector<Blob> blobs_16 = detector_explicit.detect(image_16);
    ASSERT_EQ(blobs_8.size(), spots.size());
    ASSERT_EQ(blobs_12.size(), blobs_8.size());
    ASSERT_EQ(blobs_16.size(), blobs_8.size());
    for (std::size_t i = 0; i < blobs_8.size(); ++i) {
      EXPECT_NEAR(blobs_12[i].x, blobs_8[i].x, 1e-9);
      EXPECT_NEAR(blobs_12[i].y, blobs_8[i].y, 1e-9);
      EXPECT_NEAR(blobs_16[i].x, blobs_8[i].x, 1e-9);
      EXPECT_NEAR(blobs_16[i].y, blobs_8[i].y, 1e-9);
      EXPECT_EQ(blobs_12[i].area, blobs_8[i].area);
      EXPECT_EQ(blobs_12[i].peak, blobs_8[i].peak * 16);
      EXPECT_DOUBLE_EQ(blobs_12[i].sum, blobs_8[i].sum * 16);
    }
  }
}

TEST(Detector, DefaultThresholdScalesWithBitDepth) {
  const DetectorConfig config;
  EXPECT_EQ(config.threshold_for_bits(8), 64);
  EXPECT_EQ(config.threshold_for_bits(10), 256);
  EXPECT_EQ(config.threshold_for_bits(12), 1024);
  EXPECT_EQ(config.threshold_for_bits(16), 16384);
  DetectorConfig explicit_threshold;
  explicit_threshold.threshold = 40;
  EXPECT_EQ(explicit_threshold.threshold_for_bits(12), 40);
}

TEST(Detector, HandMadeBlobHasExactAreaPeakSumAndMoments) {
  // Threshold 50: the blob is the five pixels > 50; 50 itself is not above.
  const Image image = image_from_rows({
      {0, 0, 0, 0, 0},
      {0, 60, 100, 0, 0},
      {0, 0, 200, 80, 50},
      {0, 0, 0, 0, 0},
  });
  for (const CentroidWeighting weighting :
       {CentroidWeighting::kIntensitySquared, CentroidWeighting::kIntensity,
        CentroidWeighting::kAboveThreshold}) {
    DetectorConfig config = permissive(50);
    config.weighting = weighting;
    Detector detector(config);
    const std::vector<Blob> blobs = detector.detect(image);
    ASSERT_EQ(blobs.size(), 1u);
    const Blob& blob = blobs[0];
    EXPECT_EQ(blob.area, 4);
    EXPECT_EQ(blob.peak, 200);
    EXPECT_EQ(blob.sum, 60 + 100 + 200 + 80);

    struct P {
      int x, y, i;
    };
    const P pixels[] = {{1, 1, 60}, {2, 1, 100}, {2, 2, 200}, {3, 2, 80}};
    double w = 0, wx = 0, wy = 0;
    for (const P& p : pixels) {
      const double weight = weighting == CentroidWeighting::kIntensitySquared ? double(p.i) * p.i
                            : weighting == CentroidWeighting::kIntensity      ? p.i
                                                                              : p.i - 50;
      w += weight;
      wx += weight * p.x;
      wy += weight * p.y;
    }
    const double cx = wx / w, cy = wy / w;
    double m20 = 0, m11 = 0, m02 = 0;
    for (const P& p : pixels) {
      const double weight = weighting == CentroidWeighting::kIntensitySquared ? double(p.i) * p.i
                            : weighting == CentroidWeighting::kIntensity      ? p.i
                                                                              : p.i - 50;
      m20 += weight * (p.x - cx) * (p.x - cx) / w;
      m11 += weight * (p.x - cx) * (p.y - cy) / w;
      m02 += weight * (p.y - cy) * (p.y - cy) / w;
    }
    EXPECT_NEAR(blob.x, cx, 1e-12);
    EXPECT_NEAR(blob.y, cy, 1e-12);
    EXPECT_NEAR(blob.m20, m20, 1e-12);
    EXPECT_NEAR(blob.m11, m11, 1e-12);
    EXPECT_NEAR(blob.m02, m02, 1e-12);
  }
}

TEST(Detector, SinglePixelCentroidIsItsIndex) {
  Image image(7, 5, 8);
  image.row8(3)[4] = 200;
  Detector detector(permissive(64));
  const std::vector<Blob> blobs = detector.detect(image);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_EQ(blobs[0].x, 4.0);
  EXPECT_EQ(blobs[0].y, 3.0);
}

TEST(Detector, DiagonalNeighboursAreOneBlob) {
  Detector detector(permissive(64));
  EXPECT_EQ(detector.detect(image_from_rows({{200, 0, 0}, {0, 200, 0}, {0, 0, 0}})).size(), 1u);
  EXPECT_EQ(detector.detect(image_from_rows({{0, 0, 200}, {0, 200, 0}, {0, 0, 0}})).size(), 1u);
  // A one-pixel gap separates blobs, in a row and between rows.
  EXPECT_EQ(detector.detect(image_from_rows({{200, 0, 200}, {0, 0, 0}, {200, 0, 200}})).size(), 4u);
  EXPECT_EQ(detector.detect(image_from_rows({{200, 200, 0, 0}, {0, 0, 200, 0}})).size(), 1u);
  EXPECT_EQ(detector.detect(image_from_rows({{200, 200, 0, 0, 0}, {0, 0, 0, 200, 0}})).size(), 2u);
}

TEST(Detector, TouchingSpotsMergeIntoOneComponent) {
  std::mt19937_64 rng(41);
  const Image image =
      render_spots(64, 48, {Spot{20.3, 20.1, 2.0, 200}, Spot{25.6, 22.4, 2.0, 200}}, 10, 0.0, &rng);
  Detector detector;
  const std::vector<Blob> blobs = detector.detect(image);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_GT(blobs[0].x, 20.3);
  EXPECT_LT(blobs[0].x, 25.6);
}

TEST(Detector, ShapesWhoseRunsMergeLateAreOneComponent) {
  Detector detector(permissive(64));
  // U: two arms that are separate runs until the bottom row joins them.
  const std::vector<Blob> u = detector.detect(image_from_rows({
      {0, 200, 0, 0, 0, 200, 0},
      {0, 200, 0, 0, 0, 200, 0},
      {0, 200, 0, 0, 0, 200, 0},
      {0, 200, 200, 200, 200, 200, 0},
  }));
  ASSERT_EQ(u.size(), 1u);
  EXPECT_EQ(u[0].area, 11);
  EXPECT_NEAR(u[0].x, 3.0, 1e-12);

  // Comb: four arms joined only at the bottom, and a separate blob to the right that starts first
  // in raster order but merges with nothing.
  const std::vector<Blob> comb = detector.detect(image_from_rows({
      {0, 0, 0, 0, 0, 0, 0, 0, 0, 200},
      {200, 0, 200, 0, 200, 0, 200, 0, 0, 0},
      {200, 0, 200, 0, 200, 0, 200, 0, 0, 0},
      {0, 200, 0, 200, 0, 200, 0, 0, 0, 0},
  }));
  ASSERT_EQ(comb.size(), 2u);
  EXPECT_EQ(comb[0].area, 1);  // ordered by first pixel
  EXPECT_EQ(comb[0].x, 9.0);
  EXPECT_EQ(comb[1].area, 11);

  // Spiral: the arm that closes it is reached last.
  const std::vector<Blob> spiral = detector.detect(image_from_rows({
      {200, 200, 200, 200, 200, 200, 200},
      {200, 0, 0, 0, 0, 0, 200},
      {200, 0, 200, 200, 200, 0, 200},
      {200, 0, 200, 0, 200, 0, 200},
      {200, 0, 0, 0, 200, 0, 200},
      {200, 200, 200, 200, 200, 0, 200},
  }));
  ASSERT_EQ(spiral.size(), 1u);
  EXPECT_EQ(spiral[0].area, 27);
}

// Brute-force 8-connected flood fill: the reference for random images.
std::vector<Blob> reference_blobs(const Image& image, int threshold) {
  std::vector<int> label(static_cast<std::size_t>(image.width) * image.height, -1);
  std::vector<Blob> blobs;
  for (int y0 = 0; y0 < image.height; ++y0) {
    for (int x0 = 0; x0 < image.width; ++x0) {
      if (pixel(image, x0, y0) <= threshold || label[y0 * image.width + x0] >= 0) continue;
      const int id = static_cast<int>(blobs.size());
      std::deque<std::pair<int, int>> queue{{x0, y0}};
      label[y0 * image.width + x0] = id;
      double w = 0, wx = 0, wy = 0, wxx = 0, wxy = 0, wyy = 0;
      Blob blob;
      while (!queue.empty()) {
        const auto [x, y] = queue.front();
        queue.pop_front();
        const double i = pixel(image, x, y);
        w += i * i;
        wx += i * i * x;
        wy += i * i * y;
        wxx += i * i * x * x;
        wxy += i * i * x * y;
        wyy += i * i * y * y;
        blob.area += 1;
        blob.sum += i;
        blob.peak = std::max(blob.peak, static_cast<int>(i));
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= image.width || ny >= image.height) continue;
            if (pixel(image, nx, ny) <= threshold || label[ny * image.width + nx] >= 0) continue;
            label[ny * image.width + nx] = id;
            queue.emplace_back(nx, ny);
          }
        }
      }
      blob.x = wx / w;
      blob.y = wy / w;
      blob.m20 = wxx / w - blob.x * blob.x;
      blob.m11 = wxy / w - blob.x * blob.y;
      blob.m02 = wyy / w - blob.y * blob.y;
      blobs.push_back(blob);
    }
  }
  return blobs;
}

TEST(Detector, MatchesFloodFillOnRandomImages) {
  std::mt19937_64 rng(51);
  // Widths that are not multiples of the skip block exercise the row tails.
  const int sizes[][2] = {{97, 61}, {200, 50}, {64, 64}, {1, 40}, {130, 1}};
  for (const int bits : {8, 12}) {
    for (const auto& size : sizes) {
      for (const double density : {0.05, 0.3, 0.45, 0.6}) {
        Image image(size[0], size[1], bits);
        const int threshold = bits == 8 ? 100 : 1600;
        std::uniform_int_distribution<int> below(0, threshold);
        std::uniform_int_distribution<int> above(threshold + 1, image.max_value());
        std::bernoulli_distribution on(density);
        for (int y = 0; y < image.height; ++y) {
          for (int x = 0; x < image.width; ++x) {
            const int value = on(rng) ? above(rng) : below(rng);
            if (bits == 8) {
              image.row8(y)[x] = static_cast<std::uint8_t>(value);
            } else {
              image.row16(y)[x] = static_cast<std::uint16_t>(value);
            }
          }
        }
        Detector detector(permissive(threshold));
        const std::vector<Blob> expected = reference_blobs(image, threshold);
        const std::vector<Blob> actual = detector.detect(image);
        SCOPED_TRACE("bits " + std::to_string(bits) + " size " + std::to_string(size[0]) + "x" +
                     std::to_string(size[1]) + " density " + std::to_string(density));
        ASSERT_EQ(actual.size(), expected.size());
        for (std::size_t i = 0; i < actual.size(); ++i) {
          EXPECT_EQ(actual[i].area, expected[i].area);
          EXPECT_EQ(actual[i].sum, expected[i].sum);
          EXPECT_EQ(actual[i].peak, expected[i].peak);
          EXPECT_NEAR(actual[i].x, expected[i].x, 1e-9);
          EXPECT_NEAR(actual[i].y, expected[i].y, 1e-9);
          EXPECT_NEAR(actual[i].m20, expected[i].m20, 1e-6);
          EXPECT_NEAR(actual[i].m11, expected[i].m11, 1e-6);
          EXPECT_NEAR(actual[i].m02, expected[i].m02, 1e-6);
        }
      }
    }
  }
}

TEST(Detector, AreaFiltersDropSmallAndLargeBlobs) {
  // Areas 1, 4 and 9.
  const Image image = image_from_rows({
      {200, 0, 200, 200, 0, 200, 200, 200},
      {0, 0, 200, 200, 0, 200, 200, 200},
      {0, 0, 0, 0, 0, 200, 200, 200},
  });
  DetectorConfig config = permissive(64);
  config.min_area = 2;
  config.max_area = 8;
  const std::vector<Blob> blobs = Detector(config).detect(image);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_EQ(blobs[0].area, 4);
  config.min_area = 4;
  config.max_area = 9;
  EXPECT_EQ(Detector(config).detect(image).size(), 2u);
}

TEST(Detector, PeakAndElongationFilters) {
  const Image image = image_from_rows({
      {100, 100, 100, 100, 100, 100, 100, 100, 0, 0, 0},
      {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
      {0, 0, 0, 0, 0, 0, 0, 0, 200, 200, 0},
      {0, 0, 0, 0, 0, 0, 0, 0, 200, 200, 0},
  });
  DetectorConfig config = permissive(64);
  EXPECT_EQ(Detector(config).detect(image).size(), 2u);
  config.min_peak = 150;
  EXPECT_EQ(Detector(config).detect(image).size(), 1u);
  config.min_peak = 0;
  config.max_elongation = 2.0;  // drops the 8x1 line, keeps the 2x2 square
  const std::vector<Blob> blobs = Detector(config).detect(image);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_EQ(blobs[0].area, 4);
}

TEST(Detector, EmptyAndDarkImagesHaveNoBlobs) {
  Detector detector;
  EXPECT_TRUE(detector.detect(Image(0, 0, 8)).empty());
  EXPECT_TRUE(detector.detect(Image(640, 480, 8)).empty());
  Image dark(640, 480, 8);
  std::fill(dark.data.begin(), dark.data.end(), 64);  // at, not above, the default threshold
  EXPECT_TRUE(detector.detect(dark).empty());
  EXPECT_TRUE(detector.detect(Image(640, 480, 16)).empty());
}

TEST(Detector, BlobsTouchingTheBorderAreWhole) {
  const int width = 100, height = 30;  // 100 is not a multiple of the skip block
  Image image(width, height, 8);
  const auto fill = [&image](int x0, int y0, int x1, int y1) {
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) image.row8(y)[x] = 200;
    }
  };
  fill(0, 0, 3, 2);                  // top-left corner
  fill(width - 2, 10, width, 13);    // right edge, in the row tail
  fill(62, height - 1, 67, height);  // bottom edge, across a block boundary
  fill(0, 20, 1, 24);                // left edge column
  Detector detector(permissive(64));
  const std::vector<Blob> blobs = detector.detect(image);
  ASSERT_EQ(blobs.size(), 4u);
  EXPECT_EQ(blobs[0].area, 6);
  EXPECT_NEAR(blobs[0].x, 1.0, 1e-12);
  EXPECT_NEAR(blobs[0].y, 0.5, 1e-12);
  EXPECT_EQ(blobs[1].area, 6);
  EXPECT_NEAR(blobs[1].x, width - 1.5, 1e-12);
  EXPECT_NEAR(blobs[1].y, 11.0, 1e-12);
  EXPECT_EQ(blobs[2].area, 4);
  EXPECT_NEAR(blobs[2].x, 0.0, 1e-12);
  EXPECT_NEAR(blobs[2].y, 21.5, 1e-12);
  EXPECT_EQ(blobs[3].area, 5);
  EXPECT_NEAR(blobs[3].x, 64.0, 1e-12);
  EXPECT_NEAR(blobs[3].y, height - 1.0, 1e-12);
}

TEST(Detector, ScratchReuseAcrossFramesOfDifferentSizes) {
  std::mt19937_64 rng(61);
  const std::vector<Spot> big_spots = random_spot_grid(640, 480, 32, 0.8, 3.0, rng);
  const Image big = render_spots(640, 480, big_spots, 10, 2.0, &rng);
  const Image small = render_spots(64, 32, {Spot{30.2, 15.7, 1.5, 200}}, 10, 2.0, &rng);
  Detector detector;
  const std::vector<Blob> first = detector.detect(big);
  ASSERT_EQ(detector.detect(small).size(), 1u);
  const std::vector<Blob> again = detector.detect(big);
  ASSERT_EQ(again.size(), first.size());
  for (std::size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(again[i].x, first[i].x);
    EXPECT_EQ(again[i].y, first[i].y);
  }
}

TEST(Detector, RejectsAnImageWhoseBufferIsTooSmall) {
  Image image(10, 10, 16);
  image.data.resize(150);
  Detector detector;
  EXPECT_THROW(detector.detect(image), std::invalid_argument);
}

TEST(DetectorConfig, ReadsYaml) {
  const YAML::Node node = YAML::Load(
      "threshold: 90\nmin_area: 3\nmax_area: 400\nmin_peak: 120\nmax_elongation: 3.5\nweighting: i\n");
  const DetectorConfig config = DetectorConfig::from_yaml(YamlReader("detector.yaml", node));
  EXPECT_EQ(config.threshold, 90);
  EXPECT_EQ(config.min_area, 3);
  EXPECT_EQ(config.max_area, 400);
  EXPECT_EQ(config.min_peak, 120);
  EXPECT_EQ(config.max_elongation, 3.5);
  EXPECT_EQ(config.weighting, CentroidWeighting::kIntensity);

  const DetectorConfig defaults = DetectorConfig::from_yaml(YamlReader("empty.yaml", YAML::Load("{}")));
  EXPECT_EQ(defaults.threshold, 0);
  EXPECT_EQ(defaults.weighting, CentroidWeighting::kIntensitySquared);
  EXPECT_EQ(
      DetectorConfig::from_yaml(YamlReader("a.yaml", YAML::Load("weighting: above_threshold"))).weighting,
      CentroidWeighting::kAboveThreshold);
}

TEST(DetectorConfig, BadValuesNameTheKey) {
  const auto error_of = [](const std::string& yaml) -> std::string {
    try {
      DetectorConfig::from_yaml(YamlReader("detector.yaml", YAML::Load(yaml)));
    } catch (const ConfigError& error) {
      return error.what();
    }
    return "no error";
  };
  EXPECT_NE(error_of("weighting: squared").find("weighting"), std::string::npos);
  EXPECT_NE(error_of("weighting: squared").find("detector.yaml"), std::string::npos);
  EXPECT_NE(error_of("min_area: -1").find("min_area"), std::string::npos);
  EXPECT_NE(error_of("min_area: 10\nmax_area: 5").find("max_area"), std::string::npos);
  EXPECT_NE(error_of("max_elongation: 0.5").find("max_elongation"), std::string::npos);
}

}  // namespace
}  // namespace panoptes::camera
