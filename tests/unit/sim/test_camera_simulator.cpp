// SPDX-License-Identifier: Apache-2.0
// CameraSimulator: frame timing, determinism, agreement between rendered spots and ideal features,
// noise statistics, dropout and visibility.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/simulator.h"

namespace panoptes {
namespace {

// One camera at the origin looking along +y (image x = world x, image y = -world z), so world
// points map to pixels predictably.
std::string camera_scene(const std::string& camera_keys, const std::string& rest) {
  return R"(
seed: 1234
cameras:
  - id: cam0
    width: 640
    height: 480
    K: [600, 600, 319.5, 239.5]
    T_world_cam: {q: [-0.7071067811865476, 0, 0, 0.7071067811865476], t: [0, 0, 0]}
)" + camera_keys +
         rest;
}

const std::string kGridOfMarkers = R"(
markers:
  - {name: a, path: {type: static, position: [0.0, 3.0, 0.0]}}
  - {name: b, path: {type: static, position: [-0.8, 3.0, 0.5]}}
  - {name: c, path: {type: static, position: [0.9, 3.0, -0.6]}}
  - {name: d, path: {type: circle, center: [0.3, 3.0, 0.2], radius: 0.4, frequency: 0.7, axis: [0, 1, 0]}}
  - {name: near, radius: 0.02, path: {type: static, position: [-0.3, 1.0, -0.2]}}
)";

double pixel(const Image& image, int x, int y) {
  return image.bytes_per_pixel() == 1 ? image.row8(y)[x] : image.row16(y)[x];
}

TEST(CameraSimulator, FrameTimesUseExactIntegerArithmetic) {
  const Scene scene = Scene::from_yaml_string(
      camera_scene("    rate: 90\n    phase: 0.0023\n    clock_offset: -0.0015\n", kGridOfMarkers));
  const CameraSimulator camera(scene, "cam0");
  EXPECT_EQ(camera.frame_time_ns(0), 2'300'000);
  EXPECT_EQ(camera.frame_time_ns(1), 2'300'000 + 11'111'111);
  EXPECT_EQ(camera.frame_time_ns(2), 2'300'000 + 22'222'222);
  EXPECT_EQ(camera.frame_time_ns(5), 2'300'000 + 55'555'556);  // rounded to nearest
  EXPECT_EQ(camera.frame_time_ns(9000), 2'300'000 + 100 * kNsPerSecond);
  // A year of frames later there is still no drift.
  const std::int64_t year = 90LL * 86400 * 365;
  EXPECT_EQ(camera.frame_time_ns(year), 2'300'000 + 86400LL * 365 * kNsPerSecond);
  EXPECT_EQ(camera.frame_time_ns(-1), 2'300'000 - 11'111'111);
  EXPECT_EQ(camera.frame_stamp_ns(7), camera.frame_time_ns(7) - 1'500'000);

  const FeatureFrame frame = camera.features(7);
  EXPECT_EQ(frame.camera_id, "cam0");
  EXPECT_EQ(frame.frame, 7);
  EXPECT_EQ(frame.stamp_ns, camera.frame_stamp_ns(7));

  // A rate that is not a whole number of millihertz still rounds to the nearest nanosecond.
  const Scene ntsc = Scene::from_yaml_string(camera_scene("    rate: 59.94005994005994\n", kGridOfMarkers));
  const CameraSimulator ntsc_camera(ntsc, "cam0");
  EXPECT_NEAR(static_cast<double>(ntsc_camera.frame_time_ns(600'000)), 600'000 * 1001.0 / 60.0 * 1e6, 1.0);

  EXPECT_THROW(CameraSimulator(scene, "cam7"), std::invalid_argument);
}

TEST(CameraSimulator, FeaturesAreTheProjectionsPlusSeededJitter) {
  const Scene exact = Scene::from_yaml_string(camera_scene("    centroid_noise: 0\n", kGridOfMarkers));
  const CameraSimulator camera(exact, "cam0");
  const FeatureFrame frame = camera.features(3);
  ASSERT_EQ(frame.blobs.size(), 5u);
  const CameraModel model = camera.config().calibration.model();
  const auto markers = exact.markers_at(camera.frame_time_ns(3));
  for (std::size_t i = 0; i < markers.size(); ++i) {
    const Eigen::Vector2d expected = *model.project(markers[i].p);
    EXPECT_NEAR(frame.blobs[i].x, expected.x(), 1e-9);
    EXPECT_NEAR(frame.blobs[i].y, expected.y(), 1e-9);
  }
  EXPECT_NEAR(frame.blobs[0].x, 319.5, 1e-9);  // straight ahead
  EXPECT_NEAR(frame.blobs[0].y, 239.5, 1e-9);
  // Far markers render at the minimum size; the near, large one is bigger and carries more flux.
  EXPECT_NEAR(frame.blobs[0].area, 4.0 * M_PI, 1e-9);
  const double near_sigma = 0.5 * 600 * 0.02 / 1.0;
  EXPECT_NEAR(frame.blobs[4].area, 4.0 * M_PI * near_sigma * near_sigma, 1e-6);
  EXPECT_GT(frame.blobs[4].sum, 10 * frame.blobs[0].sum);
  EXPECT_LE(frame.blobs[0].peak, 8 + 220);
  EXPECT_GT(frame.blobs[0].peak, 8 + 150);

  // With jitter, offsets are N(0, sigma): check the spread over many frames.
  const Scene noisy = Scene::from_yaml_string(camera_scene("    centroid_noise: 0.5\n", kGridOfMarkers));
  const CameraSimulator jittery(noisy, "cam0");
  double sum = 0.0, sum2 = 0.0;
  int count = 0;
  for (std::int64_t k = 0; k < 400; ++k) {
    const FeatureFrame f = jittery.features(k);
    ASSERT_EQ(f.blobs.size(), 5u);
    for (const std::size_t i : {0, 1, 2, 4}) {  // the static markers
      const FeatureFrame reference = camera.features(k);
      for (const double d : {f.blobs[i].x - reference.blobs[i].x, f.blobs[i].y - reference.blobs[i].y}) {
        sum += d;
        sum2 += d * d;
        ++count;
      }
    }
  }
  const double mean = sum / count;
  const double sigma = std::sqrt(sum2 / count - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.05);
  EXPECT_NEAR(sigma, 0.5, 0.04);
}

TEST(CameraSimulator, RenderAndFeaturesArePureFunctionsOfSeedCameraAndFrame) {
  const std::string text = camera_scene("    centroid_noise: 0.2\n    pixel_noise: 2\n", kGridOfMarkers);
  const Scene scene = Scene::from_yaml_string(text);
  const Scene same_scene = Scene::from_yaml_string(text);
  const CameraSimulator first(scene, "cam0");
  const CameraSimulator second(same_scene, "cam0");

  const Image image = first.render(11);
  EXPECT_EQ(image.width, 640);
  EXPECT_EQ(image.height, 480);
  EXPECT_EQ(image.bits, 8);
  // Out of order and from another instance: identical.
  first.render(3);
  EXPECT_EQ(first.render(11).data, image.data);
  EXPECT_EQ(second.render(11).data, image.data);
  EXPECT_NE(first.render(12).data, image.data);
  EXPECT_EQ(first.features(11).blobs.front().x, second.features(11).blobs.front().x);
  EXPECT_NE(first.features(11).blobs.front().x, first.features(12).blobs.front().x);

  std::string reseeded = text;
  reseeded.replace(reseeded.find("seed: 1234"), 10, "seed: 1235");
  const Scene other_seed = Scene::from_yaml_string(reseeded);
  EXPECT_NE(CameraSimulator(other_seed, "cam0").render(11).data, image.data);
}

// The I^2-weighted centroid of seed 004 (section on centroiding), over the spot's window,
// background removed; computed here independently of the simulator's code.
Eigen::Vector2d squared_intensity_centroid(const Image& image, double x, double y, int half,
                                           double background) {
  double sx = 0, sy = 0, sw = 0;
  const int cx = static_cast<int>(std::lround(x));
  const int cy = static_cast<int>(std::lround(y));
  for (int v = cy - half; v <= cy + half; ++v) {
    for (int u = cx - half; u <= cx + half; ++u) {
      const double signal = std::max(0.0, pixel(image, u, v) - background);
      sx += signal * signal * u;
      sy += signal * signal * v;
      sw += signal * signal;
    }
  }
  return {sx / sw, sy / sw};
}

TEST(CameraSimulator, RenderedSpotCentroidsMatchTheFeatures) {
  const Scene scene =
      Scene::from_yaml_string(camera_scene("    pixel_noise: 0\n    centroid_noise: 0.35\n", kGridOfMarkers));
  const CameraSimulator camera(scene, "cam0");
  double worst = 0.0;
  for (std::int64_t k = 0; k < 20; ++k) {
    const Image image = camera.render(k);
    const FeatureFrame frame = camera.features(k);
    ASSERT_EQ(frame.blobs.size(), 5u);
    for (const Blob& blob : frame.blobs) {
      const int half = static_cast<int>(std::ceil(2.5 * std::sqrt(blob.area / (4 * M_PI))));
      const Eigen::Vector2d centroid = squared_intensity_centroid(image, blob.x, blob.y, half, 8.0);
      EXPECT_NEAR(centroid.x(), blob.x, 0.05) << "frame " << k;
      EXPECT_NEAR(centroid.y(), blob.y, 0.05) << "frame " << k;
      worst = std::max({worst, std::abs(centroid.x() - blob.x), std::abs(centroid.y() - blob.y)});
      EXPECT_EQ(pixel(image, static_cast<int>(std::lround(blob.x)), static_cast<int>(std::lround(blob.y))),
                blob.peak);
    }
  }
  std::printf("[ sim      ] worst I^2 centroid error over 100 spots: %.4f px\n", worst);

  // Away from spots the noiseless image is exactly the background.
  const Image image = camera.render(0);
  EXPECT_EQ(pixel(image, 5, 5), 8);
  EXPECT_EQ(pixel(image, 600, 400), 8);
}

TEST(CameraSimulator, SpotFluxMatchesTheFeaturesAndDropoutAgrees) {
  const Scene scene = Scene::from_yaml_string(camera_scene(
      "    pixel_noise: 0\n    background: 0\n    dropout: 0.4\n    bits: 16\n    blob_peak: 20000\n",
      kGridOfMarkers));
  const CameraSimulator camera(scene, "cam0");
  int shown = 0;
  const int frames = 300;
  for (std::int64_t k = 0; k < frames; ++k) {
    const FeatureFrame frame = camera.features(k);
    shown += static_cast<int>(frame.blobs.size());
    if (k >= 30) continue;
    const Image image = camera.render(k);
    EXPECT_EQ(image.bits, 16);
    EXPECT_EQ(image.max_value(), 65535);
    double flux = 0.0;
    for (int y = 0; y < image.height; ++y) {
      for (int x = 0; x < image.width; ++x) flux += pixel(image, x, y);
    }
    double expected = 0.0;
    for (const Blob& blob : frame.blobs) expected += blob.sum;
    // Every spot reported is drawn, and nothing else is (4-sigma truncation loses < 0.01 %).
    EXPECT_NEAR(flux, expected, 1e-3 * expected + 1.0) << "frame " << k;
  }
  EXPECT_NEAR(shown / (5.0 * frames), 0.6, 0.05);
}

TEST(CameraSimulator, PixelNoiseHasTheConfiguredSpreadAndSpotsSaturate) {
  const Scene scene = Scene::from_yaml_string(
      camera_scene("    pixel_noise: 3\n    background: 40\n    blob_peak: 900\n", kGridOfMarkers));
  const CameraSimulator camera(scene, "cam0");
  const Image image = camera.render(2);
  double sum = 0, sum2 = 0;
  int count = 0;
  for (int y = 0; y < 100; ++y) {  // above every spot
    for (int x = 0; x < 640; ++x) {
      const double value = pixel(image, x, y);
      sum += value;
      sum2 += value * value;
      ++count;
    }
  }
  const double mean = sum / count;
  EXPECT_NEAR(mean, 40.0, 0.05);
  // Rounding to whole DN adds 1/12 DN^2.
  EXPECT_NEAR(std::sqrt(sum2 / count - mean * mean), std::sqrt(9.0 + 1.0 / 12.0), 0.05);
  const FeatureFrame frame = camera.features(2);
  const Blob& centre = frame.blobs.front();
  EXPECT_EQ(centre.peak, 255);
  EXPECT_EQ(pixel(image, 320, 240), 255);
}

TEST(CameraSimulator, MinimumSizeSpotOnAPixelCentrePeaksAtBlobPeak) {
  // (0.0025, 3, -0.0025) projects to pixel (320, 240) exactly.
  const Scene scene =
      Scene::from_yaml_string(camera_scene("    pixel_noise: 0\n    background: 8\n    blob_peak: 200\n", R"(
markers:
  - {name: centred, path: {type: static, position: [0.0025, 3.0, -0.0025]}}
  - {name: large, radius: 0.03, path: {type: static, position: [-0.2, 1.0, 0.0]}}
)"));
  const CameraSimulator camera(scene, "cam0");
  const FeatureFrame frame = camera.features(0);
  ASSERT_EQ(frame.blobs.size(), 2u);
  EXPECT_NEAR(frame.blobs[0].x, 320.0, 1e-9);
  EXPECT_NEAR(frame.blobs[0].y, 240.0, 1e-9);
  EXPECT_EQ(frame.blobs[0].peak, 208);
  const Image image = camera.render(0);
  EXPECT_EQ(pixel(image, 320, 240), 208);
  // Same surface brightness: a large spot's brightest pixel approaches the peak density,
  // blob_peak / (2 pi erf(0.5 / sqrt(2))^2) = 1.086 blob_peak.
  EXPECT_NEAR(frame.blobs[1].peak, 8 + 1.086 * 200, 2.0);
}

TEST(CameraSimulator, MarkersBehindOrOutsideTheCameraAreNotSeen) {
  const Scene scene = Scene::from_yaml_string(camera_scene("", R"(
markers:
  - {name: behind, path: {type: static, position: [0, -3, 0]}}
  - {name: beside, path: {type: static, position: [3, 0.5, 0]}}
  - {name: off_the_edge, path: {type: static, position: [2.0, 3, 0]}}
  - {name: visible, path: {type: static, position: [0.5, 3, 0.2]}}
  - {name: on_the_plane, path: {type: static, position: [1, 0, 0]}}
)"));
  const CameraSimulator camera(scene, "cam0");
  const FeatureFrame frame = camera.features(0);
  ASSERT_EQ(frame.blobs.size(), 1u);
  EXPECT_NEAR(frame.blobs[0].x, 319.5 + 600 * 0.5 / 3, 0.5);
  EXPECT_NEAR(frame.blobs[0].y, 239.5 - 600 * 0.2 / 3, 0.5);
  // The rendered image holds exactly one spot.
  const Image image = camera.render(0);
  int bright = 0;
  for (std::uint8_t value : image.data) bright += value > 100;
  EXPECT_GT(bright, 0);
  EXPECT_LT(bright, 12);
}

}  // namespace
}  // namespace panoptes
