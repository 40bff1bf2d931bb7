// SPDX-License-Identifier: Apache-2.0
// Intrinsics from evidence (issue 35 item 5, intrinsics_evidence.h): which groups the data
// determine, when a refinement earns its parameters, when it is reverted; and a wand scene with
// exact intrinsics where the refinement must be declined.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "calib_scenes.h"
#include "panoptes/calib/bundle_adjustment.h"
#include "panoptes/calib/intrinsics_evidence.h"

namespace panoptes::calib::testing {
namespace {

CameraIntrinsics camera_752() {
  CameraIntrinsics k;
  k.width = 752;
  k.height = 480;
  k.fx = k.fy = 1000;
  k.cx = 375.5;
  k.cy = 239.5;
  return k;
}

TEST(IntrinsicsEvidence, OnlyGroupsTheDataPinDownAreFreed) {
  // f 5% (50 px), fy alone 1% (10 px), c 2% of the width (15 px), k1, k2 0.1; ratio 0.5
  const IntrinsicsPrior prior;
  // f 3 px, c 4 px, k1 0.01 determined; fy alone 6 px and k2 0.06 are not (above 5 px, 0.05).
  const DeterminedGroups groups = determined_groups({3.0, 6.0, 4.0, 2.0, 0.01, 0.06}, camera_752(), prior);
  EXPECT_EQ(groups.free, kFreeFocal | kFreeCentre | kFreeK1);
  EXPECT_NE(groups.why.find("fy/fx 6 (prior 10) not determined"), std::string::npos) << groups.why;
  EXPECT_NE(groups.why.find("k2 0.06 (prior 0.1) not determined"), std::string::npos) << groups.why;
  // One axis of the principal point poorly determined: the pair stays.
  EXPECT_EQ(determined_groups({3.0, 1.0, 4.0, 9.0, 0.01, 0.01}, camera_752(), prior).free,
            kFreeFocal | kFreeAspect | kFreeK1 | kFreeK2);
  // No posterior (the camera's intrinsics were not in the problem): nothing.
  EXPECT_EQ(determined_groups({3.0, 4.0, 1.0}, camera_752(), prior).free, 0U);
}

TEST(IntrinsicsEvidence, KeptOnlyWhenTheResidualFallEarnsTheParameters) {
  EvidenceFigures figures;
  figures.components = 8000;
  figures.added = 16;  // needs 16 x ln 8000 = 143.8 noise variances
  figures.validation_given = 0.33;
  figures.validation_refined = 0.31;
  figures.cost_refined = 1000;  // variance 0.125 px^2
  figures.cost_given = 1000 + 0.125 * 200;
  const EvidenceJudgement keep = judge_refinement(figures);
  EXPECT_EQ(keep.verdict, EvidenceVerdict::kKeep) << keep.why;
  figures.cost_given = 1000 + 0.125 * 100;  // a fall of 100 variances: not worth 16 parameters
  const EvidenceJudgement declined = judge_refinement(figures);
  EXPECT_EQ(declined.verdict, EvidenceVerdict::kDeclined) << declined.why;
  EXPECT_EQ(declined.why.rfind("kept as given", 0), 0U) << declined.why;
}

TEST(IntrinsicsEvidence, WorseResidualsOrWorseValidationAreReverted) {
  EvidenceFigures figures;
  figures.components = 8000;
  figures.added = 4;
  figures.cost_given = 1000;
  figures.cost_refined = 1010;  // the refined adjustment ended higher (a worse local minimum)
  figures.validation_given = figures.validation_refined = 0.3;
  const EvidenceJudgement cost = judge_refinement(figures);
  EXPECT_EQ(cost.verdict, EvidenceVerdict::kReverted) << cost.why;
  EXPECT_NE(cost.why.find("reverted"), std::string::npos);
  EXPECT_NE(cost.why.find("made the residuals worse"), std::string::npos) << cost.why;
  figures.cost_refined = 500;  // a large fall in the adjusted residuals, but the raw frames got worse
  figures.validation_refined = 0.35;
  const EvidenceJudgement validation = judge_refinement(figures);
  EXPECT_EQ(validation.verdict, EvidenceVerdict::kReverted) << validation.why;
  EXPECT_NE(validation.why.find("validation"), std::string::npos) << validation.why;
}

// Exact intrinsics, 0.1 px centroid noise: told the noise is 0.01 px, the solver looks past the noise
// gate and tries the refinement, but the residual fall cannot pay for the parameters: declined,
// intrinsics exactly as given, and the summary says so.
TEST(IntrinsicsEvidence, ExactIntrinsicsAreKeptAsGiven) {
  SceneSpec spec = wand_room6();
  spec.duration_s = 4;
  const Scene scene = Scene::from_yaml_string(scene_yaml(spec));
  SolveOptions options;
  options.centroid_noise_px = 0.01;
  const WandDefinition wand{{0.0, 0.18, 0.5}};
  const Measured m = solve_and_measure(scene, wand, options);
  print("wand_room6 exact intrinsics, noise gate forced open", m);
  std::printf("  intrinsics: '%s' / '%s'\n", m.result.intrinsics_refined.c_str(),
              m.result.intrinsics_declined.c_str());
  ASSERT_TRUE(m.result.ok());
  EXPECT_TRUE(m.result.intrinsics_refined.empty());
  EXPECT_EQ(m.result.intrinsics_declined.rfind("kept as given", 0), 0U) << m.result.intrinsics_declined;
  for (std::size_t c = 0; c < m.result.cameras.size(); ++c) {
    EXPECT_FALSE(m.result.cameras[c].intrinsics_refined);
    EXPECT_EQ(m.result.cameras[c].intrinsics.fx, scene.cameras()[c].calibration.intrinsics.fx);
    EXPECT_EQ(m.result.cameras[c].intrinsics.cx, scene.cameras()[c].calibration.intrinsics.cx);
  }
  // Default options: the residuals are at the centroid noise and nothing is tried.
  const Measured plain = solve_and_measure(scene, wand, SolveOptions{});
  EXPECT_TRUE(plain.result.intrinsics_refined.empty());
  EXPECT_NE(plain.result.intrinsics_declined.find("at the noise"), std::string::npos)
      << plain.result.intrinsics_declined;
}

}  // namespace
}  // namespace panoptes::calib::testing
