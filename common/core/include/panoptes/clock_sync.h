// SPDX-License-Identifier: Apache-2.0
// Clock synchronisation maths (architecture.md "Time"; seed 003 §2.2.4.2, the "time daemon"):
// estimates the offset and drift of this host's clock against the common time base (the
// estimator's clock) from NTP-style request/reply exchanges. Pure arithmetic, no DDS and no
// threads: panoptes/dds/time_sync.h carries the exchanges and feeds a ClockSync.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

#include "panoptes/time.h"

namespace panoptes {

// One request/reply exchange. t1 and t4 are read on the local clock (request sent, reply
// received), t2 and t3 on the server's (request received, reply sent).
struct ClockExchange {
  TimeNs t1_ns = 0;
  TimeNs t2_ns = 0;
  TimeNs t3_ns = 0;
  TimeNs t4_ns = 0;

  // Time the exchange spent in transit (both legs, without the server's own turnaround).
  TimeNs round_trip_ns() const { return (t4_ns - t1_ns) - (t3_ns - t2_ns); }
  // Local minus server clock if both legs took equally long. Whatever the split, the true offset
  // lies within round_trip / 2 of it: that bound is why short round trips are the good samples.
  TimeNs offset_ns() const { return ((t1_ns - t2_ns) + (t4_ns - t3_ns)) / 2; }
  // Local time the offset refers to: the middle of the exchange.
  TimeNs local_mid_ns() const { return t1_ns + (t4_ns - t1_ns) / 2; }
};

struct ClockSyncOptions {
  // Exchanges are grouped by local time into intervals; each interval keeps only the ones with
  // the smallest round trip. At 20 Hz that keeps the best 4 of 20 a second; at 2 Hz all of them
  // (the weights below still favour the short round trips).
  TimeNs interval_ns = kNsPerSecond;
  std::size_t keep_per_interval = 4;
  std::size_t max_intervals = 120;  // history fitted: 2 minutes
  // Synchronised once this many exchanges are kept.
  std::size_t min_samples = 4;
  // Exchanges slower than this carry nothing useful (offset known only to ±half of it).
  TimeNs max_round_trip_ns = 100 * kNsPerMillisecond;
  // Standard deviation of a sample with the smallest round trip r_min: its error is bounded by
  // r_min / 2 (and uniform within that, σ would be r_min / 3.5), so σ_min = max(min_sigma_ns,
  // sigma_per_round_trip · r_min). A sample with a longer round trip r gets σ_min + (r − r_min) / 2,
  // its possible extra asymmetry. On loopback DDS (r_min ≈ 0.2–0.3 ms) the best samples disagree
  // by tens of µs: a smaller σ_min would let a single one dominate the fit.
  TimeNs min_sigma_ns = 10'000;
  double sigma_per_round_trip = 0.25;
  // Newest samples weigh most: a sample's weight halves every `age_half_life_ns`, so the fit
  // follows a drift that changes with temperature.
  TimeNs age_half_life_ns = 60 * kNsPerSecond;
  // Prior on the drift, N(0, drift_prior_ppm²): with one or two samples, or samples close in
  // time, the slope is mostly noise; the prior keeps it near 0 until the data outweigh it (within
  // a second at 20 Hz). Crystals stay within ±100 ppm; 200 leaves room for worse ones.
  double drift_prior_ppm = 200;
  double max_drift_ppm = 1000;  // a fitted drift beyond this is clamped (crystals: ~±100 ppm)
  // Samples whose normalised residual exceeds this many robust standard deviations are left out
  // of the fit (refitted until none is).
  double outlier_sigmas = 4;
  // A sample whose whole uncertainty interval (offset ± round_trip/2) misses the current fit by
  // more than this is not fitted: after `step_confirm` of them in a row (and none in between
  // agreeing) the clock was stepped (chrony, an operator) and the estimate restarts from them.
  TimeNs step_threshold_ns = 5 * kNsPerMillisecond;
  std::size_t step_confirm = 3;
  // Until the offset's standard error is below this, more exchanges are wanted (the client keeps
  // its fast rate): a jittery network needs more of them to find short round trips.
  TimeNs target_sigma_ns = 50'000;
};

// The fitted line: offset(local) = local − server = offset_ns + drift · (local − reference_ns).
struct ClockEstimate {
  bool synchronised = false;
  TimeNs reference_ns = 0;  // local time of the newest sample fitted
  double offset_ns = 0;     // local minus server clock at reference_ns
  double drift = 0;         // d(local − server) / d(local); ppm = drift · 1e6

  std::size_t samples = 0;       // samples in the fit
  std::size_t outliers = 0;      // kept samples left out of the fit as outliers
  TimeNs span_ns = 0;            // local time from the oldest to the newest sample fitted
  double residual_rms_ns = 0;    // weighted RMS of the fitted samples about the line
  double offset_sigma_ns = 0;    // standard error of the fitted offset at reference_ns
  double drift_sigma_ppm = 0;    // standard error of the drift
  TimeNs min_round_trip_ns = 0;  // shortest round trip fitted; half of it bounds a constant bias

  double drift_ppm() const { return drift * 1e6; }
  // Local minus server clock at local time `local_ns` (0 before synchronisation).
  TimeNs offset_at(TimeNs local_ns) const;
  // The common (server) time of a local time stamp.
  TimeNs to_server(TimeNs local_ns) const { return local_ns - offset_at(local_ns); }
  // The local time of a server time stamp (inverse of to_server).
  TimeNs to_local(TimeNs server_ns) const;
};

class ClockSync {
 public:
  enum class Verdict {
    kKept,           // kept in its interval (fitted unless it turns out an outlier)
    kNotKept,        // its interval already holds shorter round trips
    kInvalid,        // stamps out of order (t4 < t1, t3 < t2, negative round trip)
    kTooSlow,        // round trip above max_round_trip_ns
    kStepSuspected,  // disagrees with the fit beyond its uncertainty: held until confirmed
    kStepped,        // the last of step_confirm disagreeing samples: the estimate restarted
  };

  explicit ClockSync(const ClockSyncOptions& options = {});

  // Adds an exchange and refits.
  Verdict add(const ClockExchange& exchange);
  const ClockEstimate& estimate() const { return estimate_; }
  const ClockSyncOptions& options() const { return options_; }

  // True while not synchronised or the offset's standard error is above target_sigma_ns.
  bool wants_more_exchanges() const;

  void reset();
  std::size_t resets() const { return resets_; }  // restarts after confirmed steps
  std::size_t kept() const;                       // samples in the store

 private:
  struct Sample {
    TimeNs local_ns = 0;   // middle of the exchange, local clock
    TimeNs offset_ns = 0;  // local minus server
    TimeNs round_trip_ns = 0;
  };
  struct Interval {
    std::int64_t index = 0;
    std::vector<Sample> samples;
  };

  static Sample to_sample(const ClockExchange& exchange);
  bool store(const Sample& sample);  // false if the interval keeps better ones
  bool contradicts_fit(const Sample& sample) const;
  void fit();

  ClockSyncOptions options_;
  std::deque<Interval> intervals_;  // oldest first
  std::vector<Sample> step_suspects_;
  ClockEstimate estimate_;
  std::size_t resets_ = 0;
};

}  // namespace panoptes
