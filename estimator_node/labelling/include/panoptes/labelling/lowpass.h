// SPDX-License-Identifier: Apache-2.0
// Zero-lag low-pass filtering of marker trajectories before kinematics (docs/marker_sets.md,
// "Filtering"), as gait laboratories do (a second-order Butterworth run forwards and backwards,
// Winter's "Biomechanics and Motor Control of Human Movement", ch. 2).
#pragma once
#include "panoptes/labelling/subject_model.h"

namespace panoptes::labelling {

// Filters every marker's contiguous valid runs in place: a second-order Butterworth low-pass with
// its -3 dB point at `cutoff_hz` (bilinear transform, pre-warped) applied forwards then backwards,
// so without lag; the two passes give -6 dB at `cutoff_hz`. Each run is extended at both ends by
// its point reflection (2 x0 - x[k], up to 3 / cutoff seconds of samples) so that the ends are not
// pulled towards zero. Runs shorter than 4 samples are left as they are; invalid samples stay
// invalid. Throws std::invalid_argument when cutoff_hz is not positive or not below half of
// samples.rate_hz.
void lowpass_filter(MarkerSamples& samples, double cutoff_hz);

}  // namespace panoptes::labelling
