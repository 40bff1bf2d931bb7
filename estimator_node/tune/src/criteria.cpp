// SPDX-License-Identifier: Apache-2.0
#include "panoptes/tune/criteria.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "panoptes/estimator/frame_screen.h"
#include "panoptes/estimator/point_ekf.h"
#include "panoptes/session/estimator_session.h"
#include "panoptes/simulator.h"

namespace panoptes::tune {

namespace est = panoptes::estimator;

void replay_with_held_out(const session::EstimatorConfig& config, const TuneInput& input,
                          const std::string& held_out_camera,
                          const std::function<void(const est::Tracker&)>& processed,
                          const std::function<void(const FeatureFrame&, const est::Tracker&)>& held_out) {
  session::EstimatorSession estimator(config);
  estimator.tracker().set_calibration(input.calibration);
  std::vector<FeatureFrame> used;
  std::vector<const FeatureFrame*> held;
  used.reserve(input.frames.size());
  for (const auto& frame : input.frames) {
    if (!held_out_camera.empty() && frame.camera_id == held_out_camera)
      held.push_back(&frame);
    else
      used.push_back(frame);
  }
  // As session::replay_frames in stamp order, with the held-out frames slotted in between.
  const auto references = est::offline_reference_stamps(used);
  std::size_t next_held = 0;
  for (std::size_t i = 0; i < used.size(); ++i) {
    for (; next_held < held.size() && held[next_held]->stamp_ns < used[i].stamp_ns; ++next_held)
      if (held_out) held_out(*held[next_held], estimator.tracker());
    if (!estimator.admit(used[i], references[i], false)) continue;
    if (estimator.process(used[i]) == est::FrameOutcome::kProcessed && processed)
      processed(estimator.tracker());
  }
  for (; next_held < held.size(); ++next_held)
    if (held_out) held_out(*held[next_held], estimator.tracker());
}

std::vector<TrackRecord> run_tracks(const session::EstimatorConfig& config, const TuneInput& input) {
  std::vector<TrackRecord> tracks;
  replay_with_held_out(config, input, "",
                       [&](const est::Tracker& tracker) {
                         auto current = tracker.current_tracks();
                         tracks.insert(tracks.end(), current.begin(), current.end());
                       },
                       {});
  return tracks;
}

TruthScore score_truth(const est::Evaluation& evaluation, std::size_t judged_frames,
                       const TruthCriterionOptions& options) {
  TruthScore score;
  score.rmse_mm = evaluation.rmse_m * 1e3;
  score.id_switches = evaluation.id_switch_count;
  const double published =
      judged_frames == 0
          ? 1.0
          : std::min(1.0, static_cast<double>(evaluation.instants) / static_cast<double>(judged_frames));
  score.coverage = evaluation.instants == 0 ? 0.0 : evaluation.coverage() * published;
  score.cost = score.rmse_mm + options.id_switch_penalty_mm * static_cast<double>(score.id_switches) +
               options.lost_coverage_penalty_mm * (1.0 - score.coverage);
  return score;
}

TruthScore truth_score(const session::EstimatorConfig& config, const TuneInput& input, const Scene& scene,
                       const TruthCriterionOptions& options) {
  const TimeNs begin = options.evaluation.epoch_ns + options.evaluation.warmup_ns;
  const TimeNs end = options.evaluation.epoch_ns + scene.duration_ns();
  const auto judged = std::count_if(input.frames.begin(), input.frames.end(), [&](const FeatureFrame& frame) {
    return frame.stamp_ns >= begin && frame.stamp_ns < end;
  });
  return score_truth(est::evaluate(scene, run_tracks(config, input), options.evaluation),
                     static_cast<std::size_t>(judged), options);
}

HeldOutScorer::HeldOutScorer(const HeldOutCriterionOptions& options, double measurement_noise_px)
    : options_(options), measurement_noise_px_(measurement_noise_px) {}

void HeldOutScorer::add_frame(const FeatureFrame& frame, const std::vector<TrackRecord>& tracks,
                              const CameraModel& camera) {
  std::vector<est::PointProjection> predictions;
  predictions.reserve(tracks.size());
  for (const auto& track : tracks) {
    const auto& c = track.position_covariance;  // xx xy xz yy yz zz
    est::Matrix6d P = est::Matrix6d::Zero();
    P.topLeftCorner<3, 3>() << c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5];
    est::PointState state;
    state.x.head<3>() = track.p;
    state.P = est::FilterCovariance<6>(P);
    auto projection = est::project_point(state, camera, measurement_noise_px_);
    if (projection && camera.in_image(projection->pixel)) predictions.push_back(*projection);
  }
  const auto& intrinsics = camera.intrinsics();
  const double area = std::max(1.0, static_cast<double>(intrinsics.width) * intrinsics.height);
  const double clutter = options_.clutter_weight / area;
  for (const auto& blob : frame.blobs) {
    const Eigen::Vector2d z(blob.x, blob.y);
    if (!z.allFinite()) continue;
    double best_density = 0.0, best_d2 = std::numeric_limits<double>::infinity();
    double residual2 = options_.residual_cap_px * options_.residual_cap_px;
    for (const auto& prediction : predictions) {
      residual2 = std::min(residual2, (z - prediction.pixel).squaredNorm());
      const double d2 = est::mahalanobis2(prediction, z);
      const double density = std::exp(-0.5 * d2) / (2.0 * std::numbers::pi *
                                                    std::sqrt(std::max(prediction.S.determinant(), 1e-300)));
      if (density > best_density) best_density = density, best_d2 = d2;
    }
    residual_sum_ += residual2;
    nll_sum_ -= std::log(clutter + (1.0 - options_.clutter_weight) * best_density);
    ++blobs_;
    if (best_d2 < options_.nis_gate) nis_sum_ += best_d2, ++nis_samples_;
  }
}

HeldOutScore HeldOutScorer::score() const {
  HeldOutScore score;
  score.blobs = blobs_;
  score.nis_samples = nis_samples_;
  // E[d² | d² < c] for d² ~ χ²₂ (density e^{-x/2}/2): 2 − c e^{-c/2} / (1 − e^{-c/2}).
  const double tail = std::exp(-0.5 * options_.nis_gate);
  score.expected_nis = 2.0 - options_.nis_gate * tail / (1.0 - tail);
  if (blobs_ == 0) {
    score.cost = std::numeric_limits<double>::infinity();
    return score;
  }
  const double mean_residual2 = residual_sum_ / static_cast<double>(blobs_);
  score.rms_residual_px = std::sqrt(mean_residual2);
  score.nll_per_blob = nll_sum_ / static_cast<double>(blobs_);
  score.mean_nis = nis_samples_ == 0 ? options_.nis_gate : nis_sum_ / static_cast<double>(nis_samples_);
  const double log_ratio = std::log(score.mean_nis / score.expected_nis);
  const double fit = options_.score == HeldOutCriterionOptions::Score::kResidual
                         ? std::log(std::max(mean_residual2, 1e-12))
                         : score.nll_per_blob;
  score.cost = fit + options_.nis_weight * log_ratio * log_ratio;
  return score;
}

HeldOutScore held_out_score(const session::EstimatorConfig& config, const TuneInput& input,
                            const HeldOutCriterionOptions& options) {
  HeldOutScorer scorer(options, config.tracker.measurement_noise_px);
  // Every confirmed track predicts, also one the node would not publish (publish_max_sigma_m):
  // the criterion judges the filter's predictions, not the publishing policy.
  session::EstimatorConfig predicting = config;
  predicting.tracker.publish_max_sigma_m = 0.0;
  for (const auto& camera_id : cameras_with_frames(input)) {
    const auto calibration = std::find_if(input.calibration.cameras.begin(), input.calibration.cameras.end(),
                                          [&](const auto& camera) { return camera.id == camera_id; });
    const CameraModel model = calibration->model();
    replay_with_held_out(predicting, input, camera_id, {},
                         [&](const FeatureFrame& frame, const est::Tracker& tracker) {
                           scorer.add_frame(frame, tracker.tracks_at(frame.stamp_ns), model);
                         });
  }
  return scorer.score();
}

}  // namespace panoptes::tune
