// SPDX-License-Identifier: Apache-2.0
// The tuning criteria (docs/recording.md, "Tune the filter").
//
// Ground truth (simulated recordings): the estimator runs over every camera and its tracks are
// compared with the scene (panoptes_evaluation); cost = RMSE + a penalty per ID switch + a
// penalty for marker-time lost (coverage of the trackable marker-time, where a judged frame
// after which no track was published counts as wholly untracked).
//
// Held-out camera (any studio): for each camera in turn the estimator runs on the others only;
// at the stamp of every held-out frame the confirmed tracks (also those too uncertain to publish)
// are predicted to that stamp and projected into the held-out camera with their covariance
// (S = J P Jᵀ + σ² I). Every held-out blob is scored against the prediction nearest to it:
//  - prediction error (the default, `residual`): the mean squared pixel residual, each capped at
//    residual_cap_px² (a blob no track explains costs the cap); it depends on the estimates
//    only, so it judges the filter's gain, i.e. the ratio of process to measurement noise;
//  - negative log-likelihood (`nll`): p(z) = ε / (image area) + (1 − ε) · max_j N(z; ẑ_j, S_j);
//    the clutter floor keeps the score proper (a tiny claimed S cannot explain large residuals).
// NIS consistency fixes the scale the residual leaves open: the mean d² = rᵀ S⁻¹ r of the blobs
// inside the χ²₂ gate against its expectation for a consistent filter (2, truncated at the gate).
// cost = ln(mean capped r² / 1 px²) (or the mean NLL) + w · ln(mean d² / expected)².
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "panoptes/eval/evaluation.h"
#include "panoptes/records.h"
#include "panoptes/session/estimator_config.h"
#include "panoptes/tune/tune_input.h"

namespace panoptes {
class Scene;
}

namespace panoptes::tune {

// Runs an EstimatorSession with `config` over `input` in stamp order, without the frames of
// `held_out_camera` ("": none). `held_out(frame, tracker)` sees each held-out frame before any
// later frame is processed; `processed(tracker)` follows every processed frame.
void replay_with_held_out(
    const session::EstimatorConfig& config, const TuneInput& input, const std::string& held_out_camera,
    const std::function<void(const estimator::Tracker&)>& processed,
    const std::function<void(const FeatureFrame&, const estimator::Tracker&)>& held_out);

// Every track record the offline estimator would write (--out-tracks) for `config`.
std::vector<TrackRecord> run_tracks(const session::EstimatorConfig& config, const TuneInput& input);

struct TruthCriterionOptions {
  double id_switch_penalty_mm = 1.0;     // added to the RMSE per ID switch
  double lost_coverage_penalty_mm = 20;  // × (1 − coverage of trackable marker-time)
  estimator::EvaluationOptions evaluation;
};

struct TruthScore {
  double rmse_mm = 0;
  std::size_t id_switches = 0;
  double coverage = 0;
  double cost = 0;  // mm
};

// `judged_frames`: frames within the judged time (after the warmup, before the scene's end); the
// evaluation has an instant only for those after which tracks were published.
TruthScore score_truth(const estimator::Evaluation& evaluation, std::size_t judged_frames,
                       const TruthCriterionOptions& options);
// Runs the estimator with `config` over `input` and scores its tracks against `scene`.
TruthScore truth_score(const session::EstimatorConfig& config, const TuneInput& input, const Scene& scene,
                       const TruthCriterionOptions& options);

struct HeldOutCriterionOptions {
  enum class Score { kResidual, kNll };
  Score score = Score::kResidual;
  double residual_cap_px = 10.0;
  double clutter_weight = 0.05;  // ε
  double nis_gate = 18.42;       // χ²₂ at p = 0.9999: blobs beyond it do not enter the NIS mean
  double nis_weight = 1.0;       // w
};

struct HeldOutScore {
  double rms_residual_px = 0;  // √ of the mean capped squared residual
  double nll_per_blob = 0;     // mean −ln p(z), z in px
  double mean_nis = 0;         // mean d² inside the gate
  double expected_nis = 0;     // of a consistent filter, truncated at the gate
  std::size_t blobs = 0;
  std::size_t nis_samples = 0;
  double cost = 0;
};

// Accumulates the held-out blobs' scores (one per held-out camera run, or all together).
class HeldOutScorer {
 public:
  HeldOutScorer(const HeldOutCriterionOptions& options, double measurement_noise_px);
  // Scores `frame`'s blobs against `tracks` (predicted to its stamp) seen by `camera`.
  void add_frame(const FeatureFrame& frame, const std::vector<TrackRecord>& tracks,
                 const CameraModel& camera);
  HeldOutScore score() const;

 private:
  HeldOutCriterionOptions options_;
  double measurement_noise_px_;
  double residual_sum_ = 0, nll_sum_ = 0, nis_sum_ = 0;
  std::size_t blobs_ = 0, nis_samples_ = 0;
};

// Leave-one-camera-out over every camera of `input` (cameras_with_frames).
HeldOutScore held_out_score(const session::EstimatorConfig& config, const TuneInput& input,
                            const HeldOutCriterionOptions& options);

}  // namespace panoptes::tune
