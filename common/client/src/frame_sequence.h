// SPDX-License-Identifier: Apache-2.0
// Frame numbers as they arrive: gaps (frames the bus did not deliver) and restarts of the
// estimator (its frame numbers begin again at 1).
#pragma once

#include <cstdint>

namespace panoptes::client::detail {

class FrameSequence {
 public:
  struct Step {
    std::uint64_t missed = 0;  // frames skipped before this one
    bool restart = false;      // a new estimator run began
  };

  Step observe(std::uint64_t frame_number) {
    Step step;
    if (last_ == 0) {
      // The first frame: frames published before the client subscribed are not "missed".
    } else if (frame_number <= last_) {
      // Numbers only grow within a run; going back means a new run (a restarted estimator),
      // whose earlier frames this client should have had.
      step.restart = true;
      step.missed = frame_number - 1;
    } else {
      step.missed = frame_number - last_ - 1;
    }
    last_ = frame_number;
    return step;
  }

 private:
  std::uint64_t last_ = 0;
};

}  // namespace panoptes::client::detail
