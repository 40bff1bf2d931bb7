// SPDX-License-Identifier: Apache-2.0
// bundle_adjust (bundle_adjustment.h): the passes of the adjustment stage and what they decide.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "panoptes/calib/bundle_adjustment.h"

namespace panoptes::calib {

namespace {

constexpr long kMinCamerasForCentre = 8;

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

// After the first adjustment: raw-frame errors far above any centroid noise mean the given
// intrinsics do not fit (fx, fy, cx, cy, k1, k2; the focal length, k1, k2 with few cameras).
Decision suspected_intrinsics(const BundleState& state, const StageInput& in) {
  if (in.options.refine_intrinsics || !in.options.auto_intrinsics) return {};
  std::vector<double> all;
  for (const auto& errors :
       raw_frame_errors(state, registered_models(state, in.given), in.tracks, in.wand.marker_count()))
    all.insert(all.end(), errors.begin(), errors.end());
  const double median = error_stats(all).median_px;
  if (all.empty() || median <= in.options.intrinsics_suspect_px) return {};
  // The principal point and the aspect ratio need many views: with fewer than
  // kMinCamerasForCentre cameras only the focal length and k1, k2 move (on the real 4-camera set,
  // freeing cx, cy, fx/fy too left the adjustment crawling to the iteration cap).
  const auto cameras = std::count_if(state.cameras.begin(), state.cameras.end(),
                                     [](const CameraParameters& c) { return c.registered; });
  const bool centre = cameras >= kMinCamerasForCentre;
  char why[240];
  std::snprintf(why, sizeof(why),
                "raw-frame error median %.2f px (2D) after the first adjustment, above %.2f px: the given "
                "intrinsics do not fit; %s",
                median, in.options.intrinsics_suspect_px,
                centre ? "fx, fy, cx, cy, k1, k2" : "focal length, k1, k2 (fewer than 8 cameras)");
  return {centre ? IntrinsicsRefinement::kSuspect : IntrinsicsRefinement::kNominal, why};
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
    const Decision suspected = suspected_intrinsics(state, in);
    if (suspected.refinement != IntrinsicsRefinement::kNone) {
      pass.refinement = suspected.refinement;
      result.intrinsics_refined_why = suspected.why;
      in.say("refining intrinsics: " + suspected.why);
      rms = run(true);
    }
  }
  result.refinement = pass.refinement;
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
