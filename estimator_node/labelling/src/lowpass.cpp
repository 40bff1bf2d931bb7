// SPDX-License-Identifier: Apache-2.0
#include "panoptes/labelling/lowpass.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace panoptes::labelling {

namespace {

struct Biquad {
  double b0 = 0, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
};

Biquad butterworth(double cutoff_hz, double rate_hz) {
  const double k = std::tan(std::numbers::pi * cutoff_hz / rate_hz);
  const double norm = 1.0 / (1.0 + std::numbers::sqrt2 * k + k * k);
  Biquad f;
  f.b0 = k * k * norm;
  f.b1 = 2.0 * f.b0;
  f.b2 = f.b0;
  f.a1 = 2.0 * (k * k - 1.0) * norm;
  f.a2 = (1.0 - std::numbers::sqrt2 * k + k * k) * norm;
  return f;
}

// One pass over x in place, started in the steady state of its first value (unit DC gain).
void run(const Biquad& f, std::vector<double>& x) {
  double x1 = x.front(), x2 = x.front(), y1 = x.front(), y2 = x.front();
  for (double& v : x) {
    const double y = f.b0 * v + f.b1 * x1 + f.b2 * x2 - f.a1 * y1 - f.a2 * y2;
    x2 = x1;
    x1 = v;
    y2 = y1;
    y1 = y;
    v = y;
  }
}

// Forwards and backwards over one run of one coordinate, padded by point reflection.
void filtfilt(const Biquad& f, std::vector<double>& x, std::size_t pad) {
  pad = std::min(pad, x.size() - 1);
  std::vector<double> padded;
  padded.reserve(x.size() + 2 * pad);
  for (std::size_t k = pad; k >= 1; --k) padded.push_back(2.0 * x.front() - x[k]);
  padded.insert(padded.end(), x.begin(), x.end());
  for (std::size_t k = 1; k <= pad; ++k) padded.push_back(2.0 * x.back() - x[x.size() - 1 - k]);
  run(f, padded);
  std::reverse(padded.begin(), padded.end());
  run(f, padded);
  std::reverse(padded.begin(), padded.end());
  std::copy(padded.begin() + static_cast<std::ptrdiff_t>(pad),
            padded.begin() + static_cast<std::ptrdiff_t>(pad + x.size()), x.begin());
}

}  // namespace

void lowpass_filter(MarkerSamples& samples, double cutoff_hz) {
  if (!(cutoff_hz > 0.0) || !(cutoff_hz < 0.5 * samples.rate_hz))
    throw std::invalid_argument("low-pass cutoff " + std::to_string(cutoff_hz) +
                                " Hz: expected above 0 and below half the sample rate (" +
                                std::to_string(samples.rate_hz) + " Hz) of " + samples.source);
  const Biquad f = butterworth(cutoff_hz, samples.rate_hz);
  const auto pad = static_cast<std::size_t>(std::ceil(3.0 * samples.rate_hz / cutoff_hz));
  const std::size_t frames = samples.frame_count();
  const std::size_t markers = samples.point_count();
  std::vector<double> coordinate;
  for (std::size_t m = 0; m < markers; ++m) {
    for (std::size_t first = 0; first < frames;) {
      if (!samples.is_valid(first, m)) {
        ++first;
        continue;
      }
      std::size_t last = first;
      while (last < frames && samples.is_valid(last, m)) ++last;
      if (last - first >= 4) {
        for (int axis = 0; axis < 3; ++axis) {
          coordinate.clear();
          for (std::size_t t = first; t < last; ++t) coordinate.push_back(samples.position(t, m)[axis]);
          filtfilt(f, coordinate, pad);
          for (std::size_t t = first; t < last; ++t)
            samples.positions[t * markers + m][axis] = coordinate[t - first];
        }
      }
      first = last;
    }
  }
}

}  // namespace panoptes::labelling
