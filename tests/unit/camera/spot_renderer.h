// SPDX-License-Identifier: Apache-2.0
// Test-side renderer of Gaussian spots, independent of the simulator so the detector is checked
// against an image model it did not help write.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "panoptes/image.h"

namespace panoptes::camera::testing {

struct Spot {
  double x = 0, y = 0;     // centre in pixels; (0, 0) is the centre of the top-left pixel
  double sigma = 1;        // pixels
  double amplitude = 200;  // DN at the peak of the continuous profile
};

// Fraction of a unit-area 1-D Gaussian that falls in pixel `index`, whose extent is
// [index - 0.5, index + 0.5].
inline double pixel_mass(int index, double centre, double sigma) {
  const double scale = 1.0 / (std::sqrt(2.0) * sigma);
  return 0.5 * (std::erf((index + 0.5 - centre) * scale) - std::erf((index - 0.5 - centre) * scale));
}

// amplitude * exp(-r^2 / 2 sigma^2) integrated over each pixel, on `background`: the noise-free
// picture, kept in double so many noisy frames can share one (costly) rendering.
struct SpotField {
  int width = 0, height = 0;
  std::vector<double> values;
};

inline SpotField render_field(int width, int height, const std::vector<Spot>& spots, double background) {
  SpotField field{width, height, std::vector<double>(static_cast<std::size_t>(width) * height, background)};
  for (const Spot& spot : spots) {
    const double peak_scale = spot.amplitude * 2.0 * std::numbers::pi * spot.sigma * spot.sigma;
    const int reach = static_cast<int>(std::ceil(6 * spot.sigma)) + 1;
    const int x_begin = std::max(0, static_cast<int>(spot.x) - reach);
    const int x_end = std::min(width, static_cast<int>(spot.x) + reach + 1);
    const int y_begin = std::max(0, static_cast<int>(spot.y) - reach);
    const int y_end = std::min(height, static_cast<int>(spot.y) + reach + 1);
    for (int y = y_begin; y < y_end; ++y) {
      const double mass_y = pixel_mass(y, spot.y, spot.sigma);
      for (int x = x_begin; x < x_end; ++x) {
        field.values[static_cast<std::size_t>(y) * width + x] +=
            peak_scale * mass_y * pixel_mass(x, spot.x, spot.sigma);
      }
    }
  }
  return field;
}

// The field plus Gaussian noise of `noise_dn`, rounded to 8-bit DN, then times `gain` in an image
// of `bits`: noise and rounding happen at the 8-bit level so a gain-scaled image is the same
// picture.
inline Image to_image(const SpotField& field, double noise_dn, std::mt19937_64* rng, double gain = 1.0,
                      int bits = 8) {
  Image image(field.width, field.height, bits);
  std::normal_distribution<double> noise(0.0, noise_dn > 0 ? noise_dn : 1.0);
  const double max_value = image.max_value();
  for (int y = 0; y < field.height; ++y) {
    for (int x = 0; x < field.width; ++x) {
      double value = field.values[static_cast<std::size_t>(y) * field.width + x];
      if (noise_dn > 0) value += noise(*rng);
      value = std::min(std::clamp(std::round(value), 0.0, 255.0) * gain, max_value);
      if (image.bytes_per_pixel() == 1) {
        image.row8(y)[x] = static_cast<std::uint8_t>(value);
      } else {
        image.row16(y)[x] = static_cast<std::uint16_t>(value);
      }
    }
  }
  return image;
}

inline Image render_spots(int width, int height, const std::vector<Spot>& spots, double background,
                          double noise_dn, std::mt19937_64* rng, double gain = 1.0, int bits = 8) {
  return to_image(render_field(width, height, spots, background), noise_dn, rng, gain, bits);
}

// Spots on a grid of `cell` pixels, each with a random sub-pixel offset and a random sigma, far
// enough apart never to touch. With `amplitude_max` > `amplitude` the peak is drawn from
// [amplitude, amplitude_max]; peaks above 255 saturate in the 8-bit picture.
inline std::vector<Spot> random_spot_grid(int width, int height, int cell, double sigma_min, double sigma_max,
                                          std::mt19937_64& rng, double amplitude = 200,
                                          double amplitude_max = 0) {
  std::uniform_real_distribution<double> offset(-0.5, 0.5);
  std::uniform_real_distribution<double> sigma(sigma_min, sigma_max);
  std::uniform_real_distribution<double> peak(amplitude, std::max(amplitude, amplitude_max));
  std::vector<Spot> spots;
  for (int cy = cell / 2; cy + cell / 2 <= height; cy += cell) {
    for (int cx = cell / 2; cx + cell / 2 <= width; cx += cell) {
      Spot spot{cx + offset(rng), cy + offset(rng), sigma(rng), amplitude};
      if (amplitude_max > amplitude) spot.amplitude = peak(rng);
      spots.push_back(spot);
    }
  }
  return spots;
}

}  // namespace panoptes::camera::testing
