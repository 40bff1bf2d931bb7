// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

#include "device_clock.h"

namespace panoptes::camera {
namespace {

// A camera whose clock runs at (1 + drift) of the host's, frames every `period`, each arriving
// after a latency floor plus an exponential tail, with an occasional very late frame.
struct ClockScenario {
  TimeNs device_start_ns = 5 * kNsPerSecond;     // cameras count from their power-up
  TimeNs offset_ns = 1'700'000'000'000'000'000;  // wall clock minus device clock at the start
  double drift_ppm = 0;
  TimeNs period_ns = 10 * kNsPerMillisecond;  // 100 Hz
  TimeNs floor_ns = 200'000;                  // fixed part of the transfer latency
  double tail_mean_ns = 1e6;                  // exponential part
  double late_fraction = 0;                   // frames additionally delayed by 20..100 ms
  std::uint64_t seed = 7;
};

class ClockSimulation {
 public:
  explicit ClockSimulation(const ClockScenario& scenario) : scenario_(scenario), rng_(scenario.seed) {}

  // Device stamp of frame k, and the host time it would have were latency only the floor: what
  // the mapper should return for it.
  TimeNs device_ns(std::int64_t k) const { return scenario_.device_start_ns + k * scenario_.period_ns; }
  TimeNs ideal_host_ns(std::int64_t k) const {
    const double elapsed = static_cast<double>(k * scenario_.period_ns);
    return device_ns(k) + scenario_.offset_ns +
           static_cast<TimeNs>(std::llround(elapsed * scenario_.drift_ppm * 1e-6)) + scenario_.floor_ns;
  }
  TimeNs arrival_ns(std::int64_t k) {
    std::exponential_distribution<double> tail(1.0 / scenario_.tail_mean_ns);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    double delay = tail(rng_);
    if (unit(rng_) < scenario_.late_fraction) delay += 20e6 + 80e6 * unit(rng_);
    return ideal_host_ns(k) + static_cast<TimeNs>(delay);
  }

 private:
  ClockScenario scenario_;
  std::mt19937_64 rng_;
};

constexpr TimeNs kTolerance = 100'000;  // 0.1 ms; the tail's mean is 1 ms

// Feeds `frames` frames and returns the largest |mapped - ideal| after `warmup` frames.
TimeNs worst_error(DeviceClockMapper& mapper, ClockSimulation& simulation, std::int64_t frames,
                   std::int64_t warmup, std::int64_t first = 0) {
  TimeNs worst = 0;
  for (std::int64_t k = first; k < first + frames; ++k) {
    const TimeNs mapped = mapper.add(simulation.device_ns(k), simulation.arrival_ns(k));
    if (k - first >= warmup) worst = std::max(worst, std::abs(mapped - simulation.ideal_host_ns(k)));
  }
  return worst;
}

TEST(DeviceClock, FirstFrameMapsToItsArrival) {
  DeviceClockMapper mapper;
  EXPECT_FALSE(mapper.map(123).has_value());
  EXPECT_EQ(mapper.add(1000, 5000), 5000);
  EXPECT_EQ(*mapper.map(2000), 6000);
}

TEST(DeviceClock, RecoversConstantOffsetUnderLatencyJitter) {
  ClockScenario scenario;
  ClockSimulation simulation(scenario);
  DeviceClockMapper mapper;
  const TimeNs worst = worst_error(mapper, simulation, 6000, 500);
  EXPECT_LT(worst, kTolerance) << "worst error " << worst << " ns";
  EXPECT_NEAR(mapper.drift_ppm(), 0.0, 5.0);
  EXPECT_EQ(mapper.resets(), 0u);
}

TEST(DeviceClock, TracksPositiveAndNegativeDrift) {
  for (const double drift_ppm : {200.0, -200.0}) {
    ClockScenario scenario;
    scenario.drift_ppm = drift_ppm;
    ClockSimulation simulation(scenario);
    DeviceClockMapper mapper;
    // 60 s at 200 ppm accumulates 12 ms: a constant-offset mapper would be far out.
    const TimeNs worst = worst_error(mapper, simulation, 6000, 1000);
    EXPECT_LT(worst, kTolerance) << "drift " << drift_ppm << " ppm: worst error " << worst << " ns";
    EXPECT_NEAR(mapper.drift_ppm(), drift_ppm, 5.0);
  }
}

TEST(DeviceClock, LateFramesDoNotPullTheEnvelope) {
  ClockScenario scenario;
  scenario.drift_ppm = 150;
  scenario.late_fraction = 0.1;
  ClockSimulation simulation(scenario);
  DeviceClockMapper mapper;
  const TimeNs worst = worst_error(mapper, simulation, 6000, 1000);
  EXPECT_LT(worst, kTolerance) << "worst error " << worst << " ns";
  EXPECT_EQ(mapper.resets(), 0u);
}

TEST(DeviceClock, AFewVeryLateFramesAreNotAJump) {
  ClockScenario scenario;
  ClockSimulation simulation(scenario);
  DeviceClockMapper mapper;
  worst_error(mapper, simulation, 1000, 0);
  for (std::int64_t k = 1000; k < 1003; ++k) {
    const TimeNs mapped =
        mapper.add(simulation.device_ns(k), simulation.arrival_ns(k) + 400 * kNsPerMillisecond);
    EXPECT_LT(std::abs(mapped - simulation.ideal_host_ns(k)), kTolerance);
  }
  EXPECT_LT(worst_error(mapper, simulation, 1000, 0, 1003), kTolerance);
  EXPECT_EQ(mapper.resets(), 0u);
}

TEST(DeviceClock, ResetsWhenTheDeviceClockRestarts) {
  ClockScenario before;
  ClockSimulation first(before);
  DeviceClockMapper mapper;
  worst_error(mapper, first, 2000, 0);
  // The camera rebooted: its counter starts again near zero while wall time goes on.
  ClockScenario after = before;
  after.device_start_ns = 0;
  after.offset_ns = first.ideal_host_ns(2100) - before.floor_ns;
  after.seed = 8;
  ClockSimulation second(after);
  EXPECT_LT(worst_error(mapper, second, 3000, 500), kTolerance);
  EXPECT_EQ(mapper.resets(), 1u);
}

TEST(DeviceClock, ResetsWhenTheHostClockSteps) {
  for (const TimeNs step : {2 * kNsPerSecond, -1 * kNsPerSecond}) {
    ClockScenario scenario;
    ClockSimulation simulation(scenario);
    DeviceClockMapper mapper;
    worst_error(mapper, simulation, 2000, 0);
    ClockScenario stepped = scenario;
    stepped.offset_ns += step;
    stepped.seed = 9;
    ClockSimulation after(stepped);
    EXPECT_LT(worst_error(mapper, after, 3000, 500, 2000), kTolerance) << "step " << step;
    EXPECT_EQ(mapper.resets(), 1u) << "step " << step;
  }
}

TEST(DeviceClock, ExplicitResetStartsOver) {
  DeviceClockMapper mapper;
  mapper.add(1000, 5000);
  mapper.add(2000, 6000);
  mapper.reset();
  EXPECT_FALSE(mapper.map(3000).has_value());
  EXPECT_EQ(mapper.add(10, 90), 90);
  EXPECT_EQ(mapper.resets(), 0u);
}

}  // namespace
}  // namespace panoptes::camera
