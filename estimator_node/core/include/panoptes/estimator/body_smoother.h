// SPDX-License-Identifier: Apache-2.0
// Fixed-lag smoothing of a body filter (issue 16; docs/bodies.md, "Smoothing"): the filter keeps,
// for each camera frame that updated the body, the state before and after that frame's updates;
// the pose reported `lag` behind the newest frame is the Rauch–Tung–Striebel smoothed state,
// which also uses the frames that came after it. Only the mean is smoothed; the covariance stays
// the filter's (an upper bound of the smoothed one).
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "panoptes/estimator/body_ekf.h"

namespace panoptes::estimator {

// One camera frame's step of a body filter.
struct BodyFilterStep {
  BodyState predicted;  // before the frame's marker updates (P: A P Aᵀ + Q from the previous step)
  BodyState filtered;   // after them
  BodyMatrix A;         // error-state transition from the previous step's `filtered` to `predicted`
  // The previous step's RTS gain, transposed (C_{k-1}ᵀ below), set by append_step: it depends only
  // on the two steps, so it is computed once, not at every query of a smoothed state.
  BodyMatrix previous_gain_t = BodyMatrix::Zero();
  bool has_previous_gain = false;
};

// Appends `step` to `steps` (stamp order) and sets its previous_gain_t from the step before it.
void append_step(std::vector<BodyFilterStep>& steps, BodyFilterStep step);

// A body's window of steps, in stamp order, whose steps copies of it share: the tracker copies
// its whole state (every body's window with it) into a checkpoint before every frame, and a step
// is 10 KB (two states' and two 18 × 18 matrices). A recorded step never changes.
class BodyFilterHistory {
 public:
  // append_step's work: the step's previous gain from the newest step, then the step appended.
  void append(BodyFilterStep step);
  // Drops the steps before the newest one whose filtered stamp is at or before `oldest_ns`.
  void keep_from(TimeNs oldest_ns);
  void clear() { steps_.clear(); }
  std::size_t size() const { return steps_.size(); }
  const BodyFilterStep& operator[](std::size_t i) const { return *steps_[i]; }
  const BodyFilterStep& back() const { return *steps_.back(); }

 private:
  std::vector<std::shared_ptr<const BodyFilterStep>> steps_;
};

// The RTS backward pass from the newest step down to `index`:
//   C_k = P_k|k A_{k+1}ᵀ P_{k+1|k}⁻¹,  x_k|n = x_k|k ⊕ C_k (x_{k+1|n} ⊖ x_{k+1|k}).
// Returns the filtered state of `index` with the smoothed mean. `steps` is in stamp order; a step
// without its previous gain (not appended by append_step) has it computed here.
BodyState smoothed_state(const std::vector<BodyFilterStep>& steps, std::size_t index);
BodyState smoothed_state(const BodyFilterHistory& steps, std::size_t index);

}  // namespace panoptes::estimator
