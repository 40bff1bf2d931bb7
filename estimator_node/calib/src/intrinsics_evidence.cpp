// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/intrinsics_evidence.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "panoptes/calib/bundle_adjustment.h"

namespace panoptes::calib {

namespace {

void note(std::string& out, const char* group, double sigma, double prior, bool determined) {
  char line[120];
  std::snprintf(line, sizeof(line), "%s%s %.3g (prior %.3g)%s", out.empty() ? "" : ", ", group, sigma, prior,
                determined ? "" : " not determined");
  out += line;
}

}  // namespace

DeterminedGroups determined_groups(const std::vector<double>& sigma, const CameraIntrinsics& given,
                                   const IntrinsicsPrior& prior) {
  DeterminedGroups out;
  if (sigma.size() < 6) return out;
  const double focal = prior.focal_fraction * 0.5 * (given.fx + given.fy);
  const double centre = prior.centre_fraction * given.width;
  const auto test = [&](const char* group, double value, double bound, unsigned bit) {
    const bool determined = value > 0 && value <= prior.determined_ratio * bound;
    if (determined) out.free |= bit;
    note(out.why, group, value, bound, determined);
  };
  test("f", sigma[0], focal, kFreeFocal);
  test("fy/fx", sigma[1], prior.aspect_fraction * given.fy, kFreeAspect);
  test("c", std::max(sigma[2], sigma[3]), centre, kFreeCentre);
  test("k1", sigma[4], prior.k1, kFreeK1);
  test("k2", sigma[5], prior.k2, kFreeK2);
  return out;
}

EvidenceJudgement judge_refinement(const EvidenceFigures& figures) {
  EvidenceJudgement out;
  char why[400];
  const bool cost_worse = figures.cost_refined > figures.cost_given;
  const bool validation_worse = figures.validation_refined > figures.validation_given * (1 + 1e-3) + 1e-4;
  if (cost_worse || validation_worse) {
    std::snprintf(why, sizeof(why),
                  "reverted to the given intrinsics: refining made the %s worse (cost %.1f -> %.1f px^2, "
                  "raw-frame median %.3f -> %.3f px)",
                  cost_worse ? "residuals" : "validation (raw-frame) residuals", figures.cost_given,
                  figures.cost_refined, figures.validation_given, figures.validation_refined);
    out.verdict = EvidenceVerdict::kReverted;
    out.why = why;
    return out;
  }
  const int n = std::max(figures.components, 1);
  const double variance = std::max(figures.cost_refined / n, 1e-12);
  const double gain = (figures.cost_given - figures.cost_refined) / variance;
  const double needed = figures.added * std::log(static_cast<double>(n));
  std::snprintf(why, sizeof(why),
                "the residual sum fell by %.0f noise variances for %d parameters (needed %.0f = %d x ln %d); "
                "raw-frame median %.3f -> %.3f px",
                gain, figures.added, needed, figures.added, n, figures.validation_given,
                figures.validation_refined);
  out.why = why;
  out.verdict = gain >= needed && figures.added > 0 ? EvidenceVerdict::kKeep : EvidenceVerdict::kDeclined;
  if (out.verdict == EvidenceVerdict::kDeclined) out.why = "kept as given: " + out.why;
  return out;
}

}  // namespace panoptes::calib
