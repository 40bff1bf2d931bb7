// SPDX-License-Identifier: Apache-2.0
// Intrinsics from evidence (issue 35): after the first adjustment with the given intrinsics, which
// groups (focal length, pixel aspect, principal point, k1, k2) the data determine, and whether refining them
// earns its parameters. docs/calibration.md, "Intrinsics from evidence". Pure functions, no Ceres type.
#pragma once

#include <string>
#include <vector>

#include "panoptes/calibration.h"

namespace panoptes::calib {

// How well a cameras file is assumed to know its intrinsics (1-sigma): a group is refined only when
// the data pin it down to `determined_ratio` of this or better.
struct IntrinsicsPrior {
  double focal_fraction = 0.05;   // of the focal length
  double aspect_fraction = 0.01;  // fy alone (the pixels' aspect), of fy
  double centre_fraction = 0.02;  // of the image width
  double k1 = 0.1;
  double k2 = 0.1;
  double determined_ratio = 0.5;
};

// The groups (IntrinsicsGroup bits of bundle_adjustment.h) whose posterior 1-sigma is at most
// determined_ratio x the prior. `sigma` is one camera's posterior over kFreeEvidenceAll's tangent
// (focal, fy alone, cx, cy, k1, k2); fewer than 6 values: nothing is determined. `why` lists each group's
// posterior against its prior.
struct DeterminedGroups {
  unsigned free = 0;
  std::string why;
};
DeterminedGroups determined_groups(const std::vector<double>& sigma, const CameraIntrinsics& given,
                                   const IntrinsicsPrior& prior);

// The two adjustments compared: cost is the robust (Huber) sum over the residual components, px^2;
// validation the raw-frame median 2D error, px (frames, not the adjusted samples).
struct EvidenceFigures {
  double cost_given = 0, cost_refined = 0;
  int components = 0;  // residual components (2 per observation)
  int added = 0;       // parameters freed
  double validation_given = 0, validation_refined = 0;
};

enum class EvidenceVerdict { kKeep, kDeclined, kReverted };
struct EvidenceJudgement {
  EvidenceVerdict verdict = EvidenceVerdict::kDeclined;
  std::string why;
};

// kReverted when the refinement made the cost or the validation error worse; kDeclined when the
// cost fell by less than `added` x ln(components) noise variances (the Bayesian information
// criterion: the parameters did not earn their place); otherwise kKeep.
EvidenceJudgement judge_refinement(const EvidenceFigures& figures);

}  // namespace panoptes::calib
