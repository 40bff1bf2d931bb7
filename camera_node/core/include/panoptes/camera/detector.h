// SPDX-License-Identifier: Apache-2.0
// Blob detector (docs/camera_node.md):
//  - per-pixel threshold I > max(B + T_r, T_a) with a captured background B and blind regions
//    (seed 003 §2.2.2, "Setting the per-pixel threshold", Fig. 2.3);
//  - connected components by union-find over runs; area, peak, sum, second moments, bounding box;
//    filters on area, elongation and peak;
//  - centroids weighted by I^2 (seed 004 §2.2.1 eq. 1-2; or I, or I - T), refined over the blob's
//    neighbourhood after subtracting the local background, which removes the bias the threshold
//    cut leaves (measured in tests/unit/camera/test_detector.cpp);
//  - prediction-guided search: windows around predicted positions first, then a coarse grid over
//    the rest of the frame (seed 003 §2.2.2, "Latency"), or the full frame.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "panoptes/image.h"
#include "panoptes/records.h"

namespace panoptes {
class YamlReader;
}

namespace panoptes::camera {

enum class CentroidWeighting {
  kIntensity,         // m_pq = sum x^p y^q I
  kIntensitySquared,  // m_pq = sum x^p y^q I^2 (seed 004 eq. 2), the default
  kAboveThreshold,    // m_pq = sum x^p y^q (I - threshold)
};

// A blind region: pixels inside never count as bright. Either a rectangle [x0, x1) x [y0, y1) or
// a polygon (vertices in pixel coordinates; a pixel is inside if its centre is).
struct MaskRegion {
  std::vector<std::array<double, 2>> polygon;  // used when it has >= 3 vertices
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;

  static MaskRegion rectangle(int x, int y, int width, int height) {
    return {{}, x, y, x + width, y + height};
  }
  bool is_polygon() const { return polygon.size() >= 3; }
  // Parses "rect x y w h" or "poly x1 y1 x2 y2 x3 y3 ..." (the camera_command argument form);
  // throws std::invalid_argument naming what is wrong.
  static MaskRegion parse(const std::string& text);
  std::string to_string() const;
};

struct DetectorConfig {
  // Absolute threshold T_a in DN of the image's bit depth; 0 selects 25% of full scale (64 for
  // 8-bit, 1024 for 12-bit, 16384 for 16-bit), so a first run needs no tuning.
  int threshold = 0;
  // Relative threshold T_r over the captured background; 0 selects 8% of full scale (20 DN at
  // 8 bits, seed 003 Fig. 2.3). Used only once a background has been captured.
  int relative_threshold = 0;
  int min_area = 2;           // pixels
  int max_area = 5000;        // pixels
  int min_peak = 0;           // DN; 0 disables
  double max_elongation = 0;  // ratio of ellipse axes; 0 disables
  CentroidWeighting weighting = CentroidWeighting::kIntensitySquared;
  // Centroid over the blob's bounding box grown by this many pixels, with the local background
  // (median of the grown box's border) subtracted; 0 = only the pixels above threshold (seed 004).
  int refine_margin = 2;
  // Guided search: rows scanned in the coarse grid outside the windows (every grid_step-th row);
  // a blob shorter than this many rows can be missed outside the windows.
  int grid_step = 4;
  std::vector<MaskRegion> masks;

  int threshold_for_bits(int bits) const;
  int relative_threshold_for_bits(int bits) const;
  // Reads the `detector:` section (keys as above; weighting: "i2" | "i" | "above_threshold";
  // masks: list of [x, y, w, h] rectangles or {polygon: [[x, y], ...]}). Unknown keys and
  // out-of-range values throw ConfigError naming the file and key.
  static DetectorConfig from_yaml(const YamlReader& reader);
};

// A predicted blob position (from rt/panoptes/predictions) to search first.
struct SearchWindow {
  double x = 0, y = 0;                     // centre, px
  double half_width = 0, half_height = 0;  // px
};

struct DetectionStats {
  bool guided = false;              // windows + coarse grid instead of the full frame
  std::int64_t pixels_scanned = 0;  // pixels compared with the threshold in the scan
  int components = 0;               // connected components before filtering
  int rejected = 0;                 // components removed by the area/peak/elongation filters
};

class Detector {
 public:
  explicit Detector(DetectorConfig config = {});
  const DetectorConfig& config() const { return config_; }

  void set_threshold(int threshold);
  void set_relative_threshold(int threshold);
  // The next `frames` frames seen by detect() are folded (per-pixel maximum) into a new
  // background, which replaces the old one once complete; frames = 1 makes it effective for the
  // frame after the next.
  void capture_background(int frames = 1);
  void set_background(const Image& background);
  void clear_background();
  bool has_background() const { return !background_.data.empty(); }
  bool capturing_background() const { return background_frames_left_ > 0; }
  void set_masks(std::vector<MaskRegion> masks);
  void add_mask(const MaskRegion& mask);
  void clear_masks();

  // Full-frame detection in an 8-bit or 16-bit image. Blobs are ordered by their first pixel.
  std::vector<Blob> detect(const Image& image);
  // Guided detection: the windows first, then every grid_step-th row of the rest; an empty list
  // of windows means a full-frame search. Finds the same blobs as detect() for blobs that touch a
  // window or span grid_step rows.
  std::vector<Blob> detect(const Image& image, std::span<const SearchWindow> windows);
  const DetectionStats& last_stats() const { return stats_; }

 private:
  struct Run {
    int y, x0, x1;  // [x0, x1)
    int parent;
  };
  // Per-component moment sums, relative to the component's first pixel to keep the central
  // moments free of cancellation on large images.
  struct Moments {
    int origin_x, origin_y;
    double weight, weight_x, weight_y, weight_xx, weight_xy, weight_yy;
    double sum;
    int area;
    int peak;
    int x0, y0, x1, y1;
  };

  void prepare(const Image& image);
  void rebuild_threshold_map(const Image& image);
  template <class Pixel>
  void find_runs(const Image& image);
  template <class Pixel>
  void find_runs_guided(const Image& image, std::span<const SearchWindow> windows);
  template <class Pixel>
  void flood_component(const Image& image, int seed_x, int seed_y);
  void label_components();
  template <class Pixel, CentroidWeighting kWeighting>
  void accumulate_moments(const Image& image, int threshold);
  template <class Pixel>
  void refine_centroid(const Image& image, Blob& blob, std::size_t component) const;
  void emit_blobs(const Image& image, std::vector<Blob>& blobs);
  std::vector<Blob> finish(const Image& image);

  DetectorConfig config_;
  DetectionStats stats_;
  // Scratch buffers reused across frames (no allocation in steady state).
  std::vector<Run> runs_;
  std::vector<int> row_start_;  // full-frame mode: first run of each row (runs are in raster order)
  std::vector<Moments> moments_;
  std::vector<std::uint8_t> visited_;  // guided mode: pixels already taken by a component
  std::vector<int> stack_;             // guided mode: runs still to grow from

  // Per-pixel threshold map (same bit depth as the frames) once a background or mask exists;
  // empty means the scalar absolute threshold applies everywhere.
  Image threshold_map_;
  bool threshold_map_dirty_ = true;
  Image background_;
  Image pending_background_;  // being folded while capture_background() frames remain
  int background_frames_left_ = 0;
  int threshold_ = 0;  // effective T_a for the current frame's bit depth
};

}  // namespace panoptes::camera
