// SPDX-License-Identifier: Apache-2.0
// ClockSync against simulated NTP-style exchanges whose truth is known: a local clock off by an
// offset and drifting, legs with a floor delay plus random (independent, so asymmetric) jitter,
// heavy tails, corrupt replies and a clock step.
#include <cmath>
#include <cstdint>
#include <random>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "panoptes/clock_sync.h"

namespace panoptes {
namespace {

constexpr TimeNs kUs = 1000;
constexpr TimeNs kMs = kNsPerMillisecond;
constexpr TimeNs kS = kNsPerSecond;
constexpr TimeNs kServerStart = 1'700'000'000 * kS;  // absolute wall-clock values, as in real use

// The local clock: local(t) = t + offset + drift · (t − kServerStart), t on the server's clock,
// plus `step_ns` from `step_at` on.
struct LocalClock {
  TimeNs offset_ns = 0;
  double drift_ppm = 0;
  TimeNs step_at_ns = 0;  // 0: never
  TimeNs step_ns = 0;

  TimeNs at(TimeNs server_ns) const {
    TimeNs local =
        server_ns + offset_ns +
        static_cast<TimeNs>(std::llround(drift_ppm * 1e-6 * static_cast<double>(server_ns - kServerStart)));
    if (step_at_ns != 0 && server_ns >= step_at_ns) local += step_ns;
    return local;
  }
  // True local − server at server time t.
  TimeNs offset_at(TimeNs server_ns) const { return at(server_ns) - server_ns; }
};

struct Network {
  TimeNs request_floor_ns = 80 * kUs;  // per leg
  TimeNs reply_floor_ns = 80 * kUs;
  double jitter_mean_ns = 150'000;  // exponential, drawn independently per leg
  double tail_probability = 0;      // a leg delayed by tail_ns on top (scheduler, busy network)
  TimeNs tail_ns = 20 * kMs;
  TimeNs turnaround_ns = 30 * kUs;  // server, between t2 and t3
  double corrupt_probability = 0;   // reply with t2/t3 off by ±corrupt_ns but a short round trip
  TimeNs corrupt_ns = 3 * kMs;
};

// Runs the DDS client's schedule (20 Hz for 2 s and while the estimate wants more exchanges,
// then 2 Hz) up to `until` seconds and calls `probe(server_time)` every 100 ms of server time.
class Simulation {
 public:
  Simulation(LocalClock clock, Network network, std::uint64_t seed, ClockSyncOptions options = {})
      : clock_(clock), network_(network), rng_(seed), sync_(options) {}

  template <class Probe>
  void run(double until_s, Probe&& probe) {
    const TimeNs end = kServerStart + static_cast<TimeNs>(until_s * 1e9);
    TimeNs next_probe = kServerStart;
    while (send_time_ < end) {
      while (next_probe <= send_time_) {
        probe(next_probe);
        next_probe += 100 * kMs;
      }
      exchange_at(send_time_);
      const bool fast = send_time_ - kServerStart < 2 * kS || sync_.wants_more_exchanges();
      send_time_ += fast ? 50 * kMs : 500 * kMs;
    }
  }

  // Error of the estimate at server time t: estimated − true offset, ns.
  double error_at(TimeNs server_ns) const {
    const TimeNs local = clock_.at(server_ns);
    return static_cast<double>(sync_.estimate().offset_at(local) - clock_.offset_at(server_ns));
  }

  ClockSync& sync() { return sync_; }
  const std::vector<ClockSync::Verdict>& verdicts() const { return verdicts_; }

 private:
  TimeNs leg(TimeNs floor) {
    std::exponential_distribution<double> jitter(1.0 / network_.jitter_mean_ns);
    TimeNs delay = floor + static_cast<TimeNs>(jitter(rng_));
    if (uniform_(rng_) < network_.tail_probability) delay += network_.tail_ns;
    return delay;
  }

  void exchange_at(TimeNs send_server) {
    const TimeNs receive_server = send_server + leg(network_.request_floor_ns);
    const TimeNs reply_server = receive_server + network_.turnaround_ns;
    const TimeNs back_server = reply_server + leg(network_.reply_floor_ns);
    ClockExchange exchange{clock_.at(send_server), receive_server, reply_server, clock_.at(back_server)};
    if (uniform_(rng_) < network_.corrupt_probability) {
      const TimeNs shift = uniform_(rng_) < 0.5 ? -network_.corrupt_ns : network_.corrupt_ns;
      exchange.t2_ns += shift;
      exchange.t3_ns += shift;
    }
    verdicts_.push_back(sync_.add(exchange));
  }

  LocalClock clock_;
  Network network_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  ClockSync sync_;
  TimeNs send_time_ = kServerStart;
  std::vector<ClockSync::Verdict> verdicts_;
};

struct Residuals {
  double max_abs_after_5s_ns = 0;
  double first_within_200us_s = -1;  // server time since start when the error last entered ±0.2 ms
};

template <class Sim>
Residuals run_and_measure(Sim& sim, double until_s) {
  Residuals result;
  bool inside = false;
  sim.run(until_s, [&](TimeNs t) {
    if (!sim.sync().estimate().synchronised) return;
    const double error = std::abs(sim.error_at(t));
    const double since_start = static_cast<double>(t - kServerStart) * 1e-9;
    if (since_start >= 5.0) result.max_abs_after_5s_ns = std::max(result.max_abs_after_5s_ns, error);
    if (error < 200'000 && !inside) result.first_within_200us_s = since_start;
    inside = error < 200'000;
  });
  return result;
}

TEST(ClockExchange, OffsetAndRoundTripFromTheFourStamps) {
  // Local clock 10 ms ahead; request takes 300 µs, server turns around in 50 µs, reply 100 µs.
  const TimeNs local_ahead = 10 * kMs;
  const TimeNs t_send = kServerStart;
  const ClockExchange exchange{t_send + local_ahead, t_send + 300 * kUs, t_send + 350 * kUs,
                               t_send + 450 * kUs + local_ahead};
  EXPECT_EQ(exchange.round_trip_ns(), 400 * kUs);
  // Asymmetric legs: the estimate is off by (300 − 100) / 2 µs, within round_trip / 2.
  EXPECT_EQ(exchange.offset_ns(), local_ahead - 100 * kUs);
  EXPECT_EQ(exchange.local_mid_ns(), t_send + local_ahead + 225 * kUs);
}

TEST(ClockSync, RejectsInvalidAndSlowExchanges) {
  ClockSync sync;
  const TimeNs t = kServerStart;
  EXPECT_EQ(sync.add({t, t, t + 10, t - 1}), ClockSync::Verdict::kInvalid);     // t4 < t1
  EXPECT_EQ(sync.add({t, t + 10, t, t + 100}), ClockSync::Verdict::kInvalid);   // t3 < t2
  EXPECT_EQ(sync.add({t, t, t + 200, t + 100}), ClockSync::Verdict::kInvalid);  // negative round trip
  EXPECT_EQ(sync.add({t, t, t, t + 150 * kMs}), ClockSync::Verdict::kTooSlow);  // > 100 ms
  EXPECT_EQ(sync.kept(), 0u);
  EXPECT_FALSE(sync.estimate().synchronised);
  EXPECT_EQ(sync.estimate().offset_at(t), 0);
}

TEST(ClockSync, SynchronisedAfterMinSamplesAndMapsBothWays) {
  ClockSync sync;
  const TimeNs ahead = 42 * kMs;
  for (int i = 0; i < 4; ++i) {
    EXPECT_FALSE(sync.estimate().synchronised) << i;
    const TimeNs t = kServerStart + static_cast<TimeNs>(i) * 50 * kMs;
    EXPECT_EQ(sync.add({t + ahead, t + 100 * kUs, t + 120 * kUs, t + 220 * kUs + ahead}),
              ClockSync::Verdict::kKept);
  }
  const ClockEstimate& estimate = sync.estimate();
  ASSERT_TRUE(estimate.synchronised);
  EXPECT_EQ(estimate.samples, 4u);
  EXPECT_EQ(estimate.min_round_trip_ns, 200 * kUs);
  EXPECT_NEAR(estimate.drift_ppm(), 0.0, 1e-6);
  const TimeNs local = kServerStart + 10 * kS + ahead;
  EXPECT_EQ(estimate.offset_at(local), ahead);
  EXPECT_EQ(estimate.to_server(local), kServerStart + 10 * kS);
  EXPECT_EQ(estimate.to_local(estimate.to_server(local)), local);
}

TEST(ClockSync, InverseMappingWithDrift) {
  ClockEstimate estimate;
  estimate.samples = 10;
  estimate.synchronised = true;
  estimate.reference_ns = kServerStart;
  estimate.offset_ns = -37'123'456.0;
  estimate.drift = -180e-6;
  for (TimeNs dt : {-100 * kS, -1 * kS, 0 * kS, 3 * kS, 3600 * kS}) {
    const TimeNs local = kServerStart + dt;
    EXPECT_NEAR(static_cast<double>(estimate.to_local(estimate.to_server(local)) - local), 0.0, 1.0) << dt;
  }
}

TEST(ClockSync, EachIntervalKeepsItsShortestRoundTrips) {
  ClockSync sync;  // 1 s intervals, 4 kept
  const TimeNs base = kServerStart + 100 * kMs;
  // Ten exchanges in one interval, round trips 1000, 900, ..., 100 µs.
  for (int i = 0; i < 10; ++i) {
    const TimeNs rtt = (1000 - 100 * i) * kUs;
    const TimeNs t = base + static_cast<TimeNs>(i) * 50 * kMs;
    sync.add({t, t + rtt / 2, t + rtt / 2, t + rtt});
  }
  EXPECT_EQ(sync.kept(), 4u);
  EXPECT_EQ(sync.estimate().min_round_trip_ns, 100 * kUs);
  // A slower exchange in the full interval is not kept.
  EXPECT_EQ(sync.add({base + 600 * kMs, base + 600 * kMs + 300 * kUs, base + 600 * kMs + 300 * kUs,
                      base + 600 * kMs + 600 * kUs}),
            ClockSync::Verdict::kNotKept);
  // History is bounded: 200 s later only the last 120 intervals remain.
  for (int i = 0; i < 200; ++i) {
    const TimeNs t = base + (i + 1) * kS;
    sync.add({t, t + 50 * kUs, t + 50 * kUs, t + 100 * kUs});
  }
  EXPECT_EQ(sync.kept(), 120u);
}

// The acceptance case of issue 4: offsets up to ±50 ms, drifts up to ±200 ppm, jittery legs
// drawn independently (so every exchange is asymmetric): after 5 s the residual is < 0.2 ms.
class ClockSyncConvergence : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(ClockSyncConvergence, ResidualBelow100usAfter5s) {
  const auto [offset_ms, drift_ppm] = GetParam();
  LocalClock clock{static_cast<TimeNs>(offset_ms * 1e6), drift_ppm};
  Simulation sim(clock, Network{}, 7);
  const Residuals residuals = run_and_measure(sim, 20.0);
  const ClockEstimate& estimate = sim.sync().estimate();
  ASSERT_TRUE(estimate.synchronised);
  // Jitter of 150 µs mean per leg makes single samples wrong by ~100 µs; the short round trips
  // bring the residual to half the 200 µs target (the worst over 13 seeds × 6 such networks,
  // tails and corrupt replies included, was 66 µs).
  EXPECT_LT(residuals.max_abs_after_5s_ns, 100'000) << "offset " << offset_ms << " ms, drift " << drift_ppm;
  EXPECT_GE(residuals.first_within_200us_s, 0.0);
  EXPECT_LT(residuals.first_within_200us_s, 1.0);
  EXPECT_NEAR(estimate.drift_ppm(), drift_ppm, 5.0);
  // The statistical standard error is honest: the actual error is within 4 of them.
  EXPECT_LT(std::abs(sim.error_at(kServerStart + 20 * kS)), 4 * estimate.offset_sigma_ns + 5'000);
}

INSTANTIATE_TEST_SUITE_P(OffsetsAndDrifts, ClockSyncConvergence,
                         ::testing::Values(std::make_tuple(50.0, 200.0), std::make_tuple(-50.0, -200.0),
                                           std::make_tuple(20.0, -150.0), std::make_tuple(-35.0, 120.0),
                                           std::make_tuple(50.0, -200.0), std::make_tuple(0.0, 0.0)));

TEST(ClockSync, ConstantAsymmetryIsABiasOfHalfTheDifference) {
  // The one thing no two-way exchange can see: legs with different floors. The estimate is off
  // by (request − reply) / 2, and never by more than half the shortest round trip.
  Network network;
  network.request_floor_ns = 400 * kUs;
  network.reply_floor_ns = 100 * kUs;
  network.jitter_mean_ns = 20'000;
  Simulation sim(LocalClock{-20 * kMs, 80}, network, 11);
  sim.run(10.0, [](TimeNs) {});
  const double error = sim.error_at(kServerStart + 10 * kS);
  EXPECT_NEAR(error, -150'000, 15'000);
  EXPECT_LE(std::abs(error), static_cast<double>(sim.sync().estimate().min_round_trip_ns) / 2 + 5'000);
}

TEST(ClockSync, HeavyTailsAreFilteredByTheShortestRoundTrips) {
  // 30% of legs delayed by 20 ms (a loaded host): one leg late makes the naive offset wrong by
  // 10 ms, yet the residual stays at the level of the clean case.
  Network network;
  network.tail_probability = 0.3;
  Simulation sim(LocalClock{35 * kMs, -170}, network, 3);
  const Residuals residuals = run_and_measure(sim, 30.0);
  EXPECT_LT(residuals.max_abs_after_5s_ns, 100'000);
  EXPECT_NEAR(sim.sync().estimate().drift_ppm(), -170.0, 8.0);
}

TEST(ClockSync, CorruptRepliesAreLeftOut) {
  // 10% of replies with server stamps off by ±8 ms but a normal round trip: physically
  // impossible samples that the interval filter cannot recognise. Early on (before
  // synchronisation) they are fitted and rejected as outliers; later they contradict the fit
  // beyond the step threshold and are held out as step suspects that never agree.
  Network network;
  network.corrupt_probability = 0.1;
  network.corrupt_ns = 8 * kMs;
  Simulation sim(LocalClock{-45 * kMs, 190}, network, 5);
  const Residuals residuals = run_and_measure(sim, 30.0);
  EXPECT_LT(residuals.max_abs_after_5s_ns, 100'000);
  std::size_t suspected = 0;
  for (const auto verdict : sim.verdicts())
    suspected += verdict == ClockSync::Verdict::kStepSuspected ? 1 : 0;
  EXPECT_GT(suspected, 0u);
  EXPECT_EQ(sim.sync().resets(), 0u) << "scattered corrupt replies must never restart the estimate";
}

TEST(ClockSync, CorruptRepliesFromTheStartAreOutliers) {
  // Corrupt replies only 1 ms off (below the step threshold) go into the fit: the robust
  // rejection must leave them out.
  Network network;
  network.corrupt_probability = 0.15;
  network.corrupt_ns = 1 * kMs;
  Simulation sim(LocalClock{10 * kMs, 50}, network, 9);
  const Residuals residuals = run_and_measure(sim, 20.0);
  EXPECT_LT(residuals.max_abs_after_5s_ns, 100'000);
  EXPECT_GT(sim.sync().estimate().outliers, 0u);
}

TEST(ClockSync, ClockStepRestartsTheEstimate) {
  // At 15 s the local clock is stepped by +80 ms (chrony, an operator): three agreeing replies
  // confirm it and the estimate restarts from them.
  LocalClock clock{25 * kMs, 100, kServerStart + 15 * kS, 80 * kMs};
  Simulation sim(clock, Network{}, 13);
  double worst_late = 0;
  sim.run(30.0, [&](TimeNs t) {
    if (t >= kServerStart + 20 * kS) worst_late = std::max(worst_late, std::abs(sim.error_at(t)));
  });
  EXPECT_EQ(sim.sync().resets(), 1u);
  EXPECT_LT(worst_late, 100'000);  // drift known only from the 10 s since the step, 2 Hz
}

TEST(ClockSync, ExtremeDriftIsClamped) {
  ClockSyncOptions options;
  options.max_drift_ppm = 300;
  Simulation sim(LocalClock{0, 900}, Network{}, 17, options);
  sim.run(10.0, [](TimeNs) {});
  EXPECT_NEAR(sim.sync().estimate().drift_ppm(), 300.0, 1e-6);
}

}  // namespace
}  // namespace panoptes
