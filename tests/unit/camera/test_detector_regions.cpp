// SPDX-License-Identifier: Apache-2.0
// Background subtraction, blind regions, run-time threshold changes and prediction-guided search.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "panoptes/camera/detector.h"
#include "panoptes/config.h"
#include "spot_renderer.h"

namespace panoptes::camera {
namespace {

using testing::render_field;
using testing::Spot;
using testing::SpotField;

// A "monitor": a rectangle showing separate bright 5x5 squares (each marker-sized), whose
// content moves with `phase`.
void add_monitor(SpotField& field, int x0, int y0, int x1, int y1, int phase) {
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      const bool lit = (x + phase) % 10 < 5 && (y + phase) % 10 < 5;
      field.values[static_cast<std::size_t>(y) * field.width + x] = lit ? 230 : 40;
    }
  }
}

const std::vector<Spot> kMarkers = {
    {100.3, 80.6, 1.5, 220}, {300.7, 200.2, 2.0, 220}, {500.1, 400.9, 1.2, 220}};

int count_near(const std::vector<Blob>& blobs, const std::vector<Spot>& spots, double tolerance) {
  int found = 0;
  for (const Spot& spot : spots) {
    for (const Blob& blob : blobs) {
      if (std::hypot(blob.x - spot.x, blob.y - spot.y) < tolerance) {
        ++found;
        break;
      }
    }
  }
  return found;
}

Image frame_with_monitor(int phase, bool markers, std::mt19937_64* rng) {
  SpotField field = render_field(640, 480, markers ? kMarkers : std::vector<Spot>{}, 10);
  add_monitor(field, 380, 40, 600, 180, phase);
  return testing::to_image(field, 2.0, rng);
}

// Seed 003 §2.2.2: a static bright region is removed by the per-pixel threshold
// max(B + T_r, T_a) once a background is captured, markers elsewhere are still found.
TEST(DetectorBackground, CapturedBackgroundRemovesAStaticBrightRegion) {
  std::mt19937_64 rng(3);
  Detector detector;
  const std::vector<Blob> before = detector.detect(frame_with_monitor(0, true, &rng));
  EXPECT_GT(before.size(), kMarkers.size()) << "the monitor should show up as blobs without a background";

  detector.capture_background(1);
  EXPECT_TRUE(detector.capturing_background());
  detector.detect(frame_with_monitor(0, false, &rng));  // folded into the background
  EXPECT_TRUE(detector.has_background());
  for (int frame = 0; frame < 5; ++frame) {
    const std::vector<Blob> after = detector.detect(frame_with_monitor(0, true, &rng));
    EXPECT_EQ(after.size(), kMarkers.size()) << "frame " << frame;
    EXPECT_EQ(count_near(after, kMarkers, 0.05), static_cast<int>(kMarkers.size()));
  }
  detector.clear_background();
  EXPECT_GT(detector.detect(frame_with_monitor(0, true, &rng)).size(), kMarkers.size());
}

// A changing picture defeats the background (seed 003: "this scheme doesn't work when there are
// computer monitors"); a blind region does not care.
TEST(DetectorBackground, BlindRegionsHandleChangingContent) {
  std::mt19937_64 rng(4);
  for (const MaskRegion& mask :
       {MaskRegion::rectangle(370, 30, 240, 160), MaskRegion::parse("poly 370 30 620 30 620 190 370 190"),
        MaskRegion::parse("rect 370 30 240 160")}) {
    Detector detector;
    detector.add_mask(mask);
    for (int phase = 0; phase < 14; phase += 3) {
      const std::vector<Blob> blobs = detector.detect(frame_with_monitor(phase, true, &rng));
      EXPECT_EQ(blobs.size(), kMarkers.size()) << mask.to_string() << " phase " << phase;
      EXPECT_EQ(count_near(blobs, kMarkers, 0.05), static_cast<int>(kMarkers.size()));
    }
    detector.clear_masks();
    EXPECT_GT(detector.detect(frame_with_monitor(0, true, &rng)).size(), kMarkers.size());
  }
}

TEST(DetectorBackground, TriangularMaskHidesOnlyItsInside) {
  Image image(40, 40, 8);
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 40; ++x) image.row8(y)[x] = 200;
  }
  Detector detector;
  detector.set_masks({MaskRegion::parse("poly 0 0 40 0 0 40")});  // upper-left half, x + y < 40
  const std::vector<Blob> blobs = detector.detect(image);
  ASSERT_EQ(blobs.size(), 1u);
  // Pixels whose centre lies on the hypotenuse count as inside: 859 of 1600 are blind.
  EXPECT_EQ(blobs[0].area, 1600 - 859);
  EXPECT_GT(blobs[0].x + blobs[0].y, 40);
}

TEST(DetectorBackground, ThresholdChangesTakeEffectOnTheNextFrame) {
  std::mt19937_64 rng(5);
  const Image image =
      testing::render_spots(200, 100, {{50.2, 50.4, 1.5, 100}, {150.6, 40.1, 1.5, 220}}, 10, 0, &rng);
  Detector detector;
  EXPECT_EQ(detector.detect(image).size(), 2u);
  detector.set_threshold(150);
  EXPECT_EQ(detector.detect(image).size(), 1u);
  detector.set_threshold(0);  // back to the default
  EXPECT_EQ(detector.detect(image).size(), 2u);
}

TEST(DetectorBackground, BackgroundOfAnotherSizeIsIgnored) {
  std::mt19937_64 rng(6);
  Detector detector;
  detector.set_background(Image(320, 240, 8));
  EXPECT_EQ(detector.detect(frame_with_monitor(0, true, &rng)).size() > kMarkers.size(), true);
}

TEST(MaskRegion, ParseRejectsMalformedText) {
  EXPECT_THROW(MaskRegion::parse("rect 1 2 3"), std::invalid_argument);
  EXPECT_THROW(MaskRegion::parse("rect 1 2 -3 4"), std::invalid_argument);
  EXPECT_THROW(MaskRegion::parse("poly 1 2 3 4"), std::invalid_argument);
  EXPECT_THROW(MaskRegion::parse("circle 1 2 3"), std::invalid_argument);
  EXPECT_THROW(MaskRegion::parse("rect 1 2 x 4"), std::invalid_argument);
  const MaskRegion rect = MaskRegion::parse("rect 10 20 30 40");
  EXPECT_EQ(rect.x1, 40);
  EXPECT_EQ(rect.y1, 60);
  EXPECT_EQ(MaskRegion::parse(rect.to_string()).to_string(), rect.to_string());
}

TEST(DetectorConfigYaml, MasksAndUnknownKeys) {
  const DetectorConfig config = DetectorConfig::from_yaml(YamlReader(
      "cam.yaml", YAML::Load("masks:\n  - [10, 20, 30, 40]\n  - polygon: [[0, 0], [5, 0], [0, 5]]\n")));
  ASSERT_EQ(config.masks.size(), 2u);
  EXPECT_FALSE(config.masks[0].is_polygon());
  EXPECT_TRUE(config.masks[1].is_polygon());
  try {
    DetectorConfig::from_yaml(YamlReader("cam.yaml", YAML::Load("treshold: 40\n"), "detector"));
    FAIL() << "a misspelt key must be rejected";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("detector.treshold"), std::string::npos) << error.what();
  }
  EXPECT_THROW(DetectorConfig::from_yaml(YamlReader("cam.yaml", YAML::Load("masks: [[1, 2, 3]]"))),
               ConfigError);
  EXPECT_THROW(DetectorConfig::from_yaml(YamlReader("cam.yaml", YAML::Load("masks: [{polygon: [[1, 2]]}]"))),
               ConfigError);
  EXPECT_THROW(DetectorConfig::from_yaml(YamlReader("cam.yaml", YAML::Load("grid_step: 0"))), ConfigError);
}

// Guided search finds exactly the full-frame blobs that touch a window or span the grid, with
// the same centroids, while scanning a fraction of the rows.
TEST(DetectorGuided, FindsTheSameBlobsAsAFullFrameSearch) {
  std::mt19937_64 rng(7);
  const std::vector<Spot> spots = testing::random_spot_grid(1280, 1024, 64, 0.8, 3.0, rng, 120, 400);
  const Image image = testing::render_spots(1280, 1024, spots, 10, 2.0, &rng);
  Detector full_detector;
  const std::vector<Blob> full = full_detector.detect(image);
  ASSERT_EQ(full.size(), spots.size());

  std::vector<SearchWindow> windows;
  for (std::size_t i = 0; i < spots.size(); i += 2)
    windows.push_back({spots[i].x + 1.0, spots[i].y - 1.0, 8, 8});
  DetectorConfig config;
  config.grid_step = 4;
  Detector guided_detector(config);
  const std::vector<Blob> guided = guided_detector.detect(image, windows);
  EXPECT_TRUE(guided_detector.last_stats().guided);
  EXPECT_LT(guided_detector.last_stats().pixels_scanned, full_detector.last_stats().pixels_scanned / 3);

  int expected = 0;
  for (std::size_t i = 0; i < full.size(); ++i) {
    const Blob& blob = full[i];
    const bool in_window = std::any_of(windows.begin(), windows.end(), [&](const SearchWindow& w) {
      return std::abs(blob.x - w.x) <= w.half_width + 3 && std::abs(blob.y - w.y) <= w.half_height + 3;
    });
    const bool spans_grid = blob.y1 - blob.y0 >= config.grid_step;
    if (!in_window && !spans_grid) continue;
    ++expected;
    const auto match = std::find_if(guided.begin(), guided.end(), [&](const Blob& g) {
      return g.x0 == blob.x0 && g.y0 == blob.y0 && g.x1 == blob.x1 && g.y1 == blob.y1;
    });
    ASSERT_NE(match, guided.end()) << "blob at " << blob.x << ", " << blob.y << " missed";
    EXPECT_DOUBLE_EQ(match->x, blob.x);
    EXPECT_DOUBLE_EQ(match->y, blob.y);
    EXPECT_EQ(match->area, blob.area);
  }
  EXPECT_GE(static_cast<int>(guided.size()), expected);
  EXPECT_LE(guided.size(), full.size());
  EXPECT_GT(expected, static_cast<int>(full.size() * 9 / 10));

  // An empty window list is a full-frame search; a second call reuses the scratch state cleanly.
  EXPECT_EQ(guided_detector.detect(image, {}).size(), full.size());
  EXPECT_FALSE(guided_detector.last_stats().guided);
  EXPECT_EQ(guided_detector.detect(image, windows).size(), guided.size());
}

TEST(DetectorGuided, WindowsOutsideTheImageAndNonFiniteAreHarmless) {
  std::mt19937_64 rng(8);
  const Image image = testing::render_spots(200, 100, {{50.2, 50.4, 1.5, 200}}, 10, 0, &rng);
  Detector detector;
  const std::vector<SearchWindow> windows = {
      {-100, -100, 10, 10}, {1e9, 1e9, 5, 5}, {NAN, 3, 4, 4}, {50, 50, -1, 3}, {50, 50, 1e6, 1e6}};
  const std::vector<Blob> blobs = detector.detect(image, windows);
  ASSERT_EQ(blobs.size(), 1u);
  EXPECT_NEAR(blobs[0].x, 50.2, 0.02);
}

}  // namespace
}  // namespace panoptes::camera
