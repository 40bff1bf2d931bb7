// SPDX-License-Identifier: Apache-2.0
// The zero-lag Butterworth low-pass of marker trajectories (panoptes/labelling/lowpass.h): a slow
// sine passes without lag, a fast one is cut, gaps split runs and stay gaps, bad cutoffs throw.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "panoptes/labelling/lowpass.h"

namespace panoptes::labelling {
namespace {

// One marker, x = sine of `hz` (amplitude 1), y = 0.5, z = a ramp, at 100 Hz for 4 s.
MarkerSamples sine(double hz) {
  MarkerSamples s;
  s.source = "sine";
  s.rate_hz = 100.0;
  s.names = {"m"};
  for (int f = 0; f < 400; ++f) {
    const double t = f / s.rate_hz;
    s.positions.emplace_back(std::sin(2.0 * std::numbers::pi * hz * t), 0.5, 0.1 * t);
    s.valid.push_back(1);
  }
  return s;
}

double rms_x_error(const MarkerSamples& a, const MarkerSamples& b, std::size_t from, std::size_t to) {
  double sum = 0.0;
  for (std::size_t f = from; f < to; ++f) sum += std::pow(a.position(f, 0).x() - b.position(f, 0).x(), 2);
  return std::sqrt(sum / static_cast<double>(to - from));
}

TEST(Lowpass, ASlowSinePassesWithoutLagAndAFastOneIsCut) {
  const MarkerSamples slow = sine(1.0);
  MarkerSamples filtered = slow;
  lowpass_filter(filtered, 6.0);
  // 1 Hz through a 6 Hz second-order Butterworth twice: gain 0.9992, no phase.
  EXPECT_LT(rms_x_error(filtered, slow, 0, 400), 0.01);
  EXPECT_LT(rms_x_error(filtered, slow, 50, 350), 0.002);
  for (std::size_t f = 0; f < 400; ++f) {
    EXPECT_NEAR(filtered.position(f, 0).y(), 0.5, 1e-9);              // a constant stays
    EXPECT_NEAR(filtered.position(f, 0).z(), 0.1 * f / 100.0, 1e-6);  // a ramp stays (reflection pads)
  }
  MarkerSamples fast = sine(20.0);
  lowpass_filter(fast, 6.0);
  double peak = 0.0;
  for (std::size_t f = 50; f < 350; ++f) peak = std::max(peak, std::abs(fast.position(f, 0).x()));
  EXPECT_LT(peak, 0.02);  // (6/20)^4 = 0.008
}

TEST(Lowpass, GapsSplitRunsAndStayGaps) {
  MarkerSamples s = sine(1.0);
  for (std::size_t f = 100; f < 110; ++f) {
    s.valid[f] = 0;
    s.positions[f] = Eigen::Vector3d(99.0, 99.0, 99.0);
  }
  s.valid[300] = 0;
  for (std::size_t f = 302; f < 400; ++f) s.valid[f] = 0;  // leaves a run of one sample (301)
  const MarkerSamples before = s;
  lowpass_filter(s, 6.0);
  for (std::size_t f = 100; f < 110; ++f) {
    EXPECT_EQ(s.valid[f], 0);
    EXPECT_EQ(s.positions[f], before.positions[f]);  // untouched
  }
  EXPECT_EQ(s.positions[301], before.positions[301]);  // too short to filter
  EXPECT_LT(rms_x_error(s, before, 0, 100), 0.01);     // the run before the gap, no pull to 99
  EXPECT_LT(rms_x_error(s, before, 110, 300), 0.01);
}

TEST(Lowpass, ACutoffOutsideTheBandThrowsNamingTheSource) {
  MarkerSamples s = sine(1.0);
  for (const double bad : {0.0, -1.0, 50.0, 80.0, std::nan("")}) {
    try {
      lowpass_filter(s, bad);
      ADD_FAILURE() << bad;
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find("sine"), std::string::npos) << error.what();
    }
  }
}

}  // namespace
}  // namespace panoptes::labelling
