// SPDX-License-Identifier: Apache-2.0
// Blob detector: threshold, connected components by union-find over runs, sub-pixel centroids
// weighted by I^2 (seed 004 §2.2.1, eq. 1-2), area, peak, sum, second moments.
#pragma once

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

struct DetectorConfig {
  // Absolute threshold T_a in DN of the image's bit depth; 0 selects a default that scales with
  // the bit depth (64 for 8-bit, i.e. 25% of full scale).
  int threshold = 0;
  int min_area = 2;           // pixels
  int max_area = 5000;        // pixels
  int min_peak = 0;           // DN; 0 disables
  double max_elongation = 0;  // ratio of ellipse axes; 0 disables
  CentroidWeighting weighting = CentroidWeighting::kIntensitySquared;

  // Effective threshold for an image of `bits` significant bits.
  int threshold_for_bits(int bits) const;
  // Reads the `detector:` section keys (threshold, min_area, max_area, min_peak, max_elongation,
  // weighting: "i2" | "i" | "above_threshold"); unknown values throw ConfigError.
  static DetectorConfig from_yaml(const YamlReader& reader);
};

class Detector {
 public:
  explicit Detector(DetectorConfig config = {});
  const DetectorConfig& config() const { return config_; }
  void set_threshold(int threshold) { config_.threshold = threshold; }

  // Finds blobs in an 8-bit or 16-bit image. Blobs are ordered by their first pixel (raster).
  std::vector<Blob> detect(const Image& image);

 private:
  DetectorConfig config_;
  // Scratch buffers reused across frames (no allocation in steady state).
  struct Run {
    int y, x0, x1;  // [x0, x1)
    int parent;
  };
  std::vector<Run> runs_;
  std::vector<int> row_start_;
  // Per-component moment sums, relative to the component's first pixel to keep the central
  // moments free of cancellation on large images.
  struct Moments {
    int origin_x, origin_y;
    double weight, weight_x, weight_y, weight_xx, weight_xy, weight_yy;
    double sum;
    int area;
    int peak;
  };
  std::vector<Moments> moments_;

  template <class Pixel>
  void find_runs(const Image& image, int threshold);
  void label_components();
  template <class Pixel, CentroidWeighting kWeighting>
  void accumulate_moments(const Image& image, int threshold);
  void emit_blobs(std::vector<Blob>& blobs) const;
};

}  // namespace panoptes::camera
