// SPDX-License-Identifier: Apache-2.0
// bundle_adjust (bundle_adjustment.h): the passes of the adjustment stage and what they decide.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "panoptes/calib/bundle_adjustment.h"
#include "panoptes/calib/intrinsics_evidence.h"
#include "panoptes/calib/solve_diagnostics.h"

namespace panoptes::calib {

namespace {

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

// The stage's inputs that stay fixed through the passes.
struct StageInput {
  const std::vector<CameraCalibration>& cameras;
  std::vector<CameraIntrinsics> given;
  const std::vector<CameraWandTrack>& tracks;
  const WandDefinition& wand;
  const SolveOptions& options;
  const std::function<void(const std::string&)>& progress;
  void say(const std::string& message) const {
    if (progress) progress(message);
  }
};

struct Decision {
  IntrinsicsRefinement refinement = IntrinsicsRefinement::kNone;
  std::string why;
};

// Before the first adjustment: all nine when asked, the focal length, k1, k2 when the cameras
// file marks intrinsics nominal.
Decision initial_intrinsics(const BundleState& state, const StageInput& in) {
  if (in.options.refine_intrinsics) return {IntrinsicsRefinement::kAll, "--refine-intrinsics"};
  if (!in.options.auto_intrinsics) return {};
  std::vector<std::string> nominal;
  for (std::size_t c = 0; c < state.cameras.size(); ++c)
    if (state.cameras[c].registered && in.cameras[c].nominal_intrinsics) nominal.push_back(in.cameras[c].id);
  if (nominal.empty()) return {};
  return {IntrinsicsRefinement::kNominal, "nominal intrinsics (" + join(nominal) + "): focal length, k1, k2"};
}

// The raw-frame median 2D error of every registered camera at `state`: the validation figure (raw
// frames, not the adjusted samples).
double raw_frame_median(const BundleState& state, const StageInput& in) {
  std::vector<double> all;
  for (const auto& errors :
       raw_frame_errors(state, registered_models(state, in.given), in.tracks, in.wand.marker_count()))
    all.insert(all.end(), errors.begin(), errors.end());
  return all.empty() ? 0.0 : error_stats(all).median_px;
}

// The robust pass's cost at `state`: Huber over every observation's 2D residual, px^2.
double robust_cost(const BundleState& state, const StageInput& in, const PassOptions& pass, int& components) {
  PassOptions fixed = pass;
  fixed.refinement = IntrinsicsRefinement::kNone;
  const AdjustmentJacobian jacobian = adjustment_jacobian(state, in.wand, fixed);
  const Eigen::VectorXd& r = jacobian.reprojection_residuals;
  components = static_cast<int>(r.size());
  const double d = in.options.huber_px;
  double cost = 0;
  for (Eigen::Index i = 0; i + 1 < r.size(); i += 2) {
    const double squared = r(i) * r(i) + r(i + 1) * r(i + 1);
    cost += squared <= d * d ? squared : 2 * d * std::sqrt(squared) - d * d;
  }
  return cost;
}

bool nothing_freed(const std::vector<unsigned>& free) {
  return std::all_of(free.begin(), free.end(), [](unsigned groups) { return groups == 0U; });
}

std::string group_names(unsigned free) {
  std::vector<std::string> names;
  if ((free & kFreeFocal) != 0U) names.emplace_back("f");
  if ((free & kFreeAspect) != 0U) names.emplace_back("fy/fx");
  if ((free & kFreeCentre) != 0U) names.emplace_back("cx, cy");
  if ((free & kFreeK1) != 0U) names.emplace_back("k1");
  if ((free & kFreeK2) != 0U) names.emplace_back("k2");
  return join(names);
}

// Which groups of which camera the data determine at `state` (posterior against prior,
// intrinsics_evidence.h), at least those in `free`.
std::vector<unsigned> determined(const BundleState& state, const StageInput& in, PassOptions pass,
                                 std::vector<unsigned> free) {
  pass.refinement = IntrinsicsRefinement::kEvidence;
  pass.free_intrinsics.assign(state.cameras.size(), kFreeEvidenceAll);
  const IntrinsicsPosterior posterior = intrinsics_posterior(state, in.wand, pass);
  if (!posterior.ok) return free;
  IntrinsicsPrior prior;
  prior.determined_ratio = in.options.intrinsics_determined_ratio;
  for (std::size_t c = 0; c < state.cameras.size(); ++c) {
    if (!state.cameras[c].registered) continue;
    const DeterminedGroups groups = determined_groups(posterior.sigma[c], in.given[c], prior);
    in.say("intrinsics posterior 1-sigma against prior, " + in.cameras[c].id + ": " + groups.why);
    free[c] |= groups.free;
  }
  return free;
}

std::string determined_names(const std::vector<unsigned>& free, const StageInput& in) {
  std::string what;
  for (std::size_t c = 0; c < free.size(); ++c)
    if (free[c] != 0U) what += (what.empty() ? "" : "; ") + in.cameras[c].id + " " + group_names(free[c]);
  return what;
}

// One trial: `free` refined from `state` in a robust pass and judged against it. On kKeep `state`,
// `pass` and `rms` are the refined ones; otherwise they are restored.
template <typename Run>
EvidenceJudgement trial(BundleState& state, PassOptions& pass, double& rms, const StageInput& in,
                        const std::vector<unsigned>& free, Run& run) {
  EvidenceFigures figures;
  for (std::size_t c = 0; c < free.size(); ++c)
    figures.added += evidence_tangent_size(free[c]) -
                     evidence_tangent_size(c < pass.free_intrinsics.size() ? pass.free_intrinsics[c] : 0U);
  figures.validation_given = raw_frame_median(state, in);
  figures.cost_given = robust_cost(state, in, pass, figures.components);
  BundleState before = state;
  const PassOptions pass_before = pass;
  const double rms_before = rms;
  pass.refinement = IntrinsicsRefinement::kEvidence;
  pass.free_intrinsics = free;
  in.say("refining intrinsics on trial: " + determined_names(free, in));
  rms = run(true);
  int components = 0;
  figures.cost_refined = robust_cost(state, in, pass, components);
  figures.validation_refined = raw_frame_median(state, in);
  EvidenceJudgement judgement = judge_refinement(figures);
  in.say("intrinsics: " + judgement.why);
  if (judgement.verdict != EvidenceVerdict::kKeep) {
    state = std::move(before);
    pass = pass_before;
    rms = rms_before;
  }
  return judgement;
}

// After the first adjustment with the given intrinsics (none marked nominal, no flag): when the
// residuals stand above the centroid noise, the groups the data determine are refined in a robust
// pass, kept only if they earn their parameters, reverted if anything got worse; groups the refined
// solution newly determines are tried the same way, up to kEvidenceRounds trials
// (docs/calibration.md, "Intrinsics from evidence").
template <typename Run>
Decision evidence_step(BundleState& state, PassOptions& pass, double& rms, const StageInput& in,
                       std::string& declined, Run run) {
  constexpr int kEvidenceRounds = 3;
  if (in.options.refine_intrinsics || !in.options.auto_intrinsics) return {};
  const double median = raw_frame_median(state, in);
  // The median 2D error of pure centroid noise (sigma per axis) is 1.1774 sigma (Rayleigh).
  const double noise_median = 1.1774 * in.options.centroid_noise_px;
  char head[300];
  std::snprintf(head, sizeof(head),
                "raw-frame error median %.3f px (2D) after the first adjustment with the given intrinsics, "
                "against %.3f px from %.2f px/axis centroid noise",
                median, noise_median, in.options.centroid_noise_px);
  if (median <= in.options.intrinsics_noise_factor * noise_median) {
    declined = std::string("kept as given: ") + head + ": at the noise";
    return {};
  }
  std::vector<unsigned> free(state.cameras.size(), 0U);
  std::string kept;
  for (int round = 0; round < kEvidenceRounds; ++round) {
    const std::vector<unsigned> wider = determined(state, in, pass, free);
    if (wider == free) break;
    const EvidenceJudgement judgement = trial(state, pass, rms, in, wider, run);
    if (judgement.verdict != EvidenceVerdict::kKeep) {
      if (round == 0) declined = judgement.why + " (tried: " + determined_names(wider, in) + ")";
      break;
    }
    free = wider;
    kept += (kept.empty() ? "" : "; then ") + judgement.why;
  }
  if (nothing_freed(free)) {
    if (declined.empty())
      declined = std::string("kept as given: ") + head +
                 ", but no focal length, principal point, k1 or k2 is determined by the data";
    return {};
  }
  return {IntrinsicsRefinement::kEvidence,
          std::string(head) + "; determined by the data: " + determined_names(free, in) + "; " + kept};
}

// Observations beyond `limit` of the adjusted wand go; with clock offsets the tracks are looked
// up again at the shifted instants. Returns how many observations went.
int drop_outliers(BundleState& state, const StageInput& in, double limit) {
  const std::size_t markers = in.wand.marker_count();
  int removed = 0;
  for (std::size_t s = 0; s < state.instants.size(); ++s) {
    auto& instant = state.instants[s];
    for (auto& observation : instant.observations) {
      if (!observation.active) continue;
      const CameraParameters& camera = state.cameras[observation.camera];
      const CameraModel model = model_of(camera, in.given[observation.camera]);
      for (std::size_t m = 0; m < markers; ++m) {
        const auto projected = model.project(Eigen::Vector3d(&state.points[(s * markers + m) * 3]));
        if (!projected || (*projected - observed_pixel(observation, m, camera.offset_s)).norm() > limit) {
          observation.active = false;
          ++removed;
          break;
        }
      }
      if (in.options.time_offsets && observation.active) {
        const TimeNs shift = static_cast<TimeNs>(std::llround(camera.offset_s * 1e9));
        const auto& track = in.tracks[observation.camera];
        const double max_gap = in.options.max_gap_frames * track.frame_period_s;
        if (auto segment = find_segment(track, instant.t_ns + shift, max_gap)) {
          observation.segment = std::move(*segment);
          observation.shift_s = static_cast<double>(shift) * 1e-9;
        }
      }
    }
  }
  return removed;
}

// Pass bookkeeping: iterations, and whether (and where) a pass stopped short of convergence.
struct Passes {
  int count = 0;
  bool all_converged = true;
  std::string iterations;  // per pass, "12, 4, 3"
  void record(const PassReport& report, BundleAdjustmentResult& result) {
    result.iterations += report.iterations;
    ++count;
    if (!report.converged && result.convergence.empty())
      result.convergence = "pass " + std::to_string(count) + " did not converge after " +
                           std::to_string(report.steps) + " iterations (" + report.termination + ")";
    iterations += (iterations.empty() ? "" : ", ") + std::to_string(report.steps);
    all_converged = all_converged && report.converged;
  }
};

// Pass 1 from the unified start; then outliers (mislabelled frames, reflections) go, and with
// clock offsets the tracks are looked up again at the shifted instants. Intrinsics suspected after
// pass 1 are refined in an extra pass before any outlier is judged.
BundleState adjust_passes(BundleState state, PassOptions pass, const StageInput& in,
                          BundleAdjustmentResult& result) {
  Passes passes;
  const auto run = [&](bool robust) {
    PassResult adjusted = adjust_pass(std::move(state), in.wand, pass, robust);
    in.say(adjusted.report.summary);
    passes.record(adjusted.report, result);
    state = std::move(adjusted.state);
    return adjusted.report.rms_px;
  };
  const Decision initial = initial_intrinsics(state, in);
  pass.refinement = initial.refinement;
  result.intrinsics_refined_why = initial.why;
  double rms = run(true);
  if (pass.refinement == IntrinsicsRefinement::kNone) {
    const Decision evidence = evidence_step(state, pass, rms, in, result.intrinsics_declined, run);
    if (evidence.refinement != IntrinsicsRefinement::kNone) result.intrinsics_refined_why = evidence.why;
  }
  result.refinement = pass.refinement;
  result.free_intrinsics = pass.free_intrinsics;
  const int count = in.options.time_offsets ? 3 : 2;
  for (int p = 1; p < count; ++p) {
    const int removed = drop_outliers(state, in, std::max(5.0 * rms, 3.0 * in.options.huber_px));
    in.say("pass " + std::to_string(p + 1) + ": " + std::to_string(removed) +
           " outlier observations removed");
    rms = run(false);
  }
  result.converged = passes.all_converged;
  if (passes.all_converged) result.convergence = "converged in every pass";
  result.convergence += " (iterations per pass: " + passes.iterations + ")";
  return state;
}

// Refined focal lengths far from the given ones mean the given intrinsics were wrong, not just
// imprecise: such a camera is not calibrated, and the message says what to check.
void check_focal_lengths(BundleState& state, const StageInput& in, BundleAdjustmentResult& result) {
  if (result.refinement == IntrinsicsRefinement::kNone) return;
  for (std::size_t c = 0; c < state.cameras.size(); ++c) {
    CameraParameters& camera = state.cameras[c];
    if (!camera.registered) continue;
    if (result.refinement == IntrinsicsRefinement::kEvidence &&
        (c >= result.free_intrinsics.size() || result.free_intrinsics[c] == 0U))
      continue;
    result.intrinsics_refined[c] = true;
    const auto& given = in.given[c];
    const double fx = camera.intrinsics[0], fy = camera.intrinsics[1];
    const double factor = std::max({fx / given.fx, given.fx / fx, fy / given.fy, given.fy / fy});
    if (factor <= in.options.max_focal_factor) continue;
    char why[400];
    std::snprintf(
        why, sizeof(why),
        "focal length %.0f x %.0f px fits the data, the cameras file gives %.0f x %.0f px (a factor "
        "%.2f, more than %.1f): check K (fx, fy = lens focal length / pixel pitch, in pixels of the "
        "%d x %d image) and the image size",
        fx, fy, given.fx, given.fy, factor, in.options.max_focal_factor, given.width, given.height);
    result.failures[c] = why;
    camera.registered = false;
    for (auto& instant : state.instants)
      for (auto& observation : instant.observations)
        if (observation.camera == static_cast<int>(c)) observation.active = false;
  }
}

}  // namespace

BundleAdjustmentResult bundle_adjust(BundleState state, int reference,
                                     const std::vector<CameraCalibration>& cameras,
                                     const std::vector<CameraWandTrack>& tracks, const WandDefinition& wand,
                                     const SolveOptions& options,
                                     const std::function<void(const std::string&)>& progress) {
  StageInput in{cameras, {}, tracks, wand, options, progress};
  for (const auto& camera : cameras) in.given.push_back(camera.intrinsics);
  BundleAdjustmentResult result;
  result.failures.resize(cameras.size());
  result.intrinsics_refined.assign(cameras.size(), false);
  PassOptions pass;
  pass.reference = reference;
  pass.time_offsets = options.time_offsets;
  pass.huber_px = options.huber_px;
  pass.length_sigma_m = options.length_sigma_m;
  pass.max_iterations = options.max_iterations;
  pass.threads = options.threads;
  pass.alternation_iterations = options.alternation_iterations;
  state = triangulate_instants(std::move(state), in.given, wand.marker_count());
  if (options.alternation_iterations > 0) {
    PassResult alternated = alternate(std::move(state), wand, pass);
    in.say(alternated.report.summary);
    result.iterations = alternated.report.iterations;
    result.state = std::move(alternated.state);
    return result;
  }
  result.state = adjust_passes(std::move(state), pass, in, result);
  check_focal_lengths(result.state, in, result);
  return result;
}

}  // namespace panoptes::calib
