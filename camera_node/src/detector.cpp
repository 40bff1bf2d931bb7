// SPDX-License-Identifier: Apache-2.0
// Blob detector v1: threshold, run-length rows, union-find over runs, one moment pass
// (seed 004 §2.2.1).
#include "panoptes/camera/detector.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include "panoptes/config.h"

namespace panoptes::camera {

int DetectorConfig::threshold_for_bits(int bits) const {
  if (threshold > 0) return threshold;
  // 25% of full scale keeps the default meaningful whatever the sensor's bit depth.
  const long long full_scale = 1LL << std::clamp(bits, 1, 30);
  return static_cast<int>(full_scale / 4);
}

DetectorConfig DetectorConfig::from_yaml(const YamlReader& reader) {
  DetectorConfig config;
  const auto read_int = [&reader](const std::string& key, int fallback, long long minimum) {
    const long long value = reader.get_int(key, fallback);
    if (value < minimum || value > std::numeric_limits<int>::max()) {
      reader.fail(key, "must be an integer >= " + std::to_string(minimum));
    }
    return static_cast<int>(value);
  };
  config.threshold = read_int("threshold", config.threshold, 0);
  config.min_area = read_int("min_area", config.min_area, 1);
  config.max_area = read_int("max_area", config.max_area, 1);
  if (config.max_area < config.min_area) {
    reader.fail("max_area", "must not be smaller than min_area (" + std::to_string(config.min_area) + ")");
  }
  config.min_peak = read_int("min_peak", config.min_peak, 0);
  config.max_elongation = reader.get_double("max_elongation", config.max_elongation);
  if (!(config.max_elongation == 0 || config.max_elongation >= 1)) {
    reader.fail("max_elongation", "must be 0 (disabled) or >= 1");
  }
  if (reader.has("weighting")) {
    const std::string weighting = reader.get_string("weighting");
    if (weighting == "i2") {
      config.weighting = CentroidWeighting::kIntensitySquared;
    } else if (weighting == "i") {
      config.weighting = CentroidWeighting::kIntensity;
    } else if (weighting == "above_threshold") {
      config.weighting = CentroidWeighting::kAboveThreshold;
    } else {
      reader.fail("weighting", "unknown weighting '" + weighting + "' (expected i2, i or above_threshold)");
    }
  }
  return config;
}

Detector::Detector(DetectorConfig config) : config_(config) {}

namespace {

// Background pixels are the vast majority; testing a whole cache line per step with a max
// reduction (no branch per pixel) lets the compiler use vector instructions for the skip.
template <class Pixel>
constexpr int kSkipBlock = 64 / static_cast<int>(sizeof(Pixel));

template <class Pixel>
inline bool block_has_above(const Pixel* pixels, Pixel threshold) {
  Pixel brightest = 0;
  for (int i = 0; i < kSkipBlock<Pixel>; ++i) brightest = std::max(brightest, pixels[i]);
  return brightest > threshold;
}

template <class Pixel>
const Pixel* row_of(const Image& image, int y) {
  if constexpr (sizeof(Pixel) == 1) {
    return image.row8(y);
  } else {
    return image.row16(y);
  }
}

template <CentroidWeighting kWeighting>
inline double weight_of(int intensity, int threshold) {
  if constexpr (kWeighting == CentroidWeighting::kIntensitySquared) {
    // Seed 004 §2.2.1 eq. 2: squaring suppresses the flickering dim border pixels. Done in double
    // because 16-bit I^2 sums overflow 32 bits.
    const double value = intensity;
    return value * value;
  } else if constexpr (kWeighting == CentroidWeighting::kIntensity) {
    return intensity;
  } else {
    return intensity - threshold;
  }
}

}  // namespace

template <class Pixel>
void Detector::find_runs(const Image& image, int threshold) {
  runs_.clear();
  row_start_.assign(static_cast<std::size_t>(image.height) + 1, 0);
  if (threshold >= std::numeric_limits<Pixel>::max()) return;  // nothing can exceed it
  const Pixel pixel_threshold = static_cast<Pixel>(threshold);
  const int width = image.width;
  for (int y = 0; y < image.height; ++y) {
    row_start_[y] = static_cast<int>(runs_.size());
    const Pixel* row = row_of<Pixel>(image, y);
    int x = 0;
    while (true) {
      while (x + kSkipBlock<Pixel> <= width && !block_has_above(row + x, pixel_threshold)) {
        x += kSkipBlock<Pixel>;
      }
      while (x < width && row[x] <= pixel_threshold) ++x;
      if (x >= width) break;
      const int x0 = x;
      while (x < width && row[x] > pixel_threshold) ++x;
      const int index = static_cast<int>(runs_.size());
      runs_.push_back(Run{y, x0, x, index});
    }
  }
  row_start_[image.height] = static_cast<int>(runs_.size());
}

void Detector::label_components() {
  // Union by smaller index keeps every parent index below its child's, so each root is its
  // component's first run in raster order and one forward pass can resolve all labels.
  const auto find = [this](int i) {
    while (runs_[i].parent != i) {
      runs_[i].parent = runs_[runs_[i].parent].parent;
      i = runs_[i].parent;
    }
    return i;
  };
  const auto unite = [this, &find](int a, int b) {
    a = find(a);
    b = find(b);
    if (a < b) {
      runs_[b].parent = a;
    } else if (b < a) {
      runs_[a].parent = b;
    }
  };

  const int rows = static_cast<int>(row_start_.size()) - 1;
  for (int y = 1; y < rows; ++y) {
    int above = row_start_[y - 1];
    const int above_end = row_start_[y];
    int current = row_start_[y];
    const int current_end = row_start_[y + 1];
    while (above < above_end && current < current_end) {
      const Run& a = runs_[above];
      const Run& c = runs_[current];
      // 8-connectivity: runs [x0, x1) touch if they overlap or meet diagonally.
      if (a.x0 <= c.x1 && c.x0 <= a.x1) unite(above, current);
      // The run that ends first cannot touch anything further right in the other row, because
      // runs within a row are separated by at least one background pixel.
      if (a.x1 < c.x1) {
        ++above;
      } else {
        ++current;
      }
    }
  }

  // Labels are stored in `parent` as -(label + 1) so that unresolved entries (indices >= 0)
  // and resolved ones can be told apart during the single pass.
  moments_.clear();
  for (int i = 0; i < static_cast<int>(runs_.size()); ++i) {
    Run& run = runs_[i];
    if (run.parent == i) {
      run.parent = -static_cast<int>(moments_.size()) - 1;
      moments_.push_back(Moments{run.x0, run.y, 0, 0, 0, 0, 0, 0, 0, 0, 0});
    } else {
      run.parent = runs_[run.parent].parent;
    }
  }
  for (Run& run : runs_) run.parent = -run.parent - 1;
}

template <class Pixel, CentroidWeighting kWeighting>
void Detector::accumulate_moments(const Image& image, int threshold) {
  for (const Run& run : runs_) {
    Moments& m = moments_[run.parent];
    const Pixel* row = row_of<Pixel>(image, run.y);
    // y is constant along a run, so only the x sums need a per-pixel loop.
    double weight = 0, weight_x = 0, weight_xx = 0, sum = 0;
    int peak = 0;
    for (int x = run.x0; x < run.x1; ++x) {
      const int intensity = row[x];
      const double w = weight_of<kWeighting>(intensity, threshold);
      const double dx = x - m.origin_x;
      weight += w;
      weight_x += w * dx;
      weight_xx += w * dx * dx;
      sum += intensity;
      peak = std::max(peak, intensity);
    }
    const double dy = run.y - m.origin_y;
    m.weight += weight;
    m.weight_x += weight_x;
    m.weight_y += weight * dy;
    m.weight_xx += weight_xx;
    m.weight_xy += weight_x * dy;
    m.weight_yy += weight * dy * dy;
    m.sum += sum;
    m.area += run.x1 - run.x0;
    m.peak = std::max(m.peak, peak);
  }
}

void Detector::emit_blobs(std::vector<Blob>& blobs) const {
  for (const Moments& m : moments_) {
    if (m.area < config_.min_area || m.area > config_.max_area) continue;
    if (config_.min_peak > 0 && m.peak < config_.min_peak) continue;
    if (!(m.weight > 0)) continue;  // only possible with an all-zero blob
    const double mean_x = m.weight_x / m.weight;
    const double mean_y = m.weight_y / m.weight;
    Blob blob;
    blob.x = m.origin_x + mean_x;
    blob.y = m.origin_y + mean_y;
    blob.area = m.area;
    blob.sum = m.sum;
    blob.peak = m.peak;
    blob.m20 = std::max(0.0, m.weight_xx / m.weight - mean_x * mean_x);
    blob.m11 = m.weight_xy / m.weight - mean_x * mean_y;
    blob.m02 = std::max(0.0, m.weight_yy / m.weight - mean_y * mean_y);
    if (config_.max_elongation > 0) {
      // Each pixel is a unit square, not a point: adding its own variance (1/12) keeps one- and
      // two-pixel blobs from looking infinitely elongated.
      const double a = blob.m20 + 1.0 / 12.0;
      const double c = blob.m02 + 1.0 / 12.0;
      const double half_trace = 0.5 * (a + c);
      const double radius = std::hypot(0.5 * (a - c), blob.m11);
      const double major = half_trace + radius;
      const double minor = half_trace - radius;
      if (!(minor > 0) || std::sqrt(major / minor) > config_.max_elongation) continue;
    }
    blobs.push_back(blob);
  }
}

std::vector<Blob> Detector::detect(const Image& image) {
  if (image.width < 0 || image.height < 0 ||
      image.data.size() < static_cast<std::size_t>(image.height) * image.stride()) {
    throw std::invalid_argument("Detector::detect: image buffer smaller than " + std::to_string(image.width) +
                                "x" + std::to_string(image.height));
  }
  const int threshold = config_.threshold_for_bits(image.bits);
  const bool wide = image.bytes_per_pixel() == 2;
  if (wide) {
    find_runs<std::uint16_t>(image, threshold);
  } else {
    find_runs<std::uint8_t>(image, threshold);
  }
  label_components();

  // The weighting is a template parameter so the per-pixel loop carries no branch on it.
  const auto accumulate = [&]<class Pixel>() {
    switch (config_.weighting) {
      case CentroidWeighting::kIntensitySquared:
        accumulate_moments<Pixel, CentroidWeighting::kIntensitySquared>(image, threshold);
        break;
      case CentroidWeighting::kIntensity:
        accumulate_moments<Pixel, CentroidWeighting::kIntensity>(image, threshold);
        break;
      case CentroidWeighting::kAboveThreshold:
        accumulate_moments<Pixel, CentroidWeighting::kAboveThreshold>(image, threshold);
        break;
    }
  };
  if (wide) {
    accumulate.template operator()<std::uint16_t>();
  } else {
    accumulate.template operator()<std::uint8_t>();
  }

  std::vector<Blob> blobs;
  blobs.reserve(moments_.size());
  emit_blobs(blobs);
  return blobs;
}

}  // namespace panoptes::camera
