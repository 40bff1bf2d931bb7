// SPDX-License-Identifier: Apache-2.0
// FrameClock: the output clock of fixed-rate frames (docs/frames.md). Instants lie on a grid of
// `rate_hz` periods aligned to whole seconds of the capture clock (period k of second s starts at
// s * 1e9 + floor(k * 1e9 / rate_hz) ns), so every estimator agrees on them and a timecode follows
// from the instant alone. Frame numbers count periods since the first frame, from 1: a frame that
// was not published (the estimator fell behind) leaves a gap, it is never sent late.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/frame_grid.h"
#include "panoptes/records.h"

namespace panoptes::session {

struct FrameTick {
  std::uint64_t frame_number = 0;  // 1 for the first frame, + 1 per period
  TimeNs instant_ns = 0;           // on the grid
};

class FrameClock {
 public:
  static constexpr int kMaxRateHz = FrameGrid::kMaxRateHz;
  // Throws std::invalid_argument (naming the rate) unless 1 <= rate_hz <= kMaxRateHz.
  explicit FrameClock(int rate_hz);

  int rate_hz() const { return grid_.rate_hz(); }
  // The nominal period (exact periods alternate between floor and ceil of it).
  double period_ns() const { return 1e9 / grid_.rate_hz(); }

  // Grid instants (panoptes/frame_grid.h): the index of the newest instant at or before `t_ns`,
  // and the instant of an index.
  std::int64_t index_at(TimeNs t_ns) const { return grid_.index_at(t_ns); }
  TimeNs instant(std::int64_t index) const { return grid_.instant(index); }

  // Live: the newest instant at or before `now_ns` if not yet published. Periods passed over since
  // the last one are counted in skipped(), never published late (no bursts).
  std::optional<FrameTick> latest_due(TimeNs now_ns);
  // Live, while no camera sends: the instants up to `now_ns` go by unpublished, counted in idle()
  // rather than skipped() (the frame numbers stay on the grid, so they jump when frames resume).
  void idle_until(TimeNs now_ns);
  // Offline: the next instant after the last one if it lies at or before `now_ns` (every period
  // in turn: the replay's clock never falls behind).
  std::optional<FrameTick> next_due(TimeNs now_ns);
  // When the next instant falls due (0 before the first frame).
  TimeNs next_instant() const;

  std::uint64_t published() const { return published_; }
  std::uint64_t skipped() const { return skipped_; }
  std::uint64_t idle() const { return idle_; }

  Timecode timecode(TimeNs instant_ns) const { return grid_.timecode(instant_ns); }

 private:
  FrameTick emit(std::int64_t index);

  FrameGrid grid_;
  std::optional<std::int64_t> first_index_;
  std::int64_t last_index_ = 0;
  std::uint64_t published_ = 0;
  std::uint64_t skipped_ = 0;
  std::uint64_t idle_ = 0;
};

// What fixed-rate frames cost, for the end-of-run summary: per frame, its instant minus the
// newest processed camera stamp (the age of the newest data, what a fixed rate adds to latency)
// and, live, its write time minus its instant (a negative value is not a sample: live, the data
// age is left out once the cameras have stopped sending). The first kMaxSamples frames are kept.
struct FixedRateStats {
  static constexpr std::size_t kMaxSamples = 1 << 20;
  std::uint64_t frames = 0;
  std::vector<TimeNs> data_age_ns;
  std::vector<TimeNs> publish_delay_ns;  // live only
  void add(TimeNs data_age, TimeNs publish_delay = -1);
  // "fixed-rate: N frames; instant - newest stamp: mean .. ms, p99 .. ms, max .. ms[; publish - instant:
  // ...]"
  std::string summary() const;
};

}  // namespace panoptes::session
