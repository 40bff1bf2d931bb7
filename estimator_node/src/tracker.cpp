// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/tracker.h"

#include <algorithm>
#include <tuple>

#include "panoptes/estimator/triangulation.h"

namespace panoptes::estimator {

void TrackerOptions::print(std::ostream& out) const {
  out << "tracker options:\n"
      << "  process_noise            " << process_noise << " m^2/s^3\n"
      << "  measurement_noise_px     " << measurement_noise_px << " px\n"
      << "  gate_chi2                " << gate_chi2 << "\n"
      << "  init_window              " << ns_to_seconds(init_window_ns) * 1e3 << " ms\n"
      << "  init_reprojection_px     " << init_reprojection_px << " px\n"
      << "  confirm_cameras          " << confirm_cameras << "\n"
      << "  coast_after              " << ns_to_seconds(coast_after_ns) * 1e3 << " ms\n"
      << "  delete_after             " << ns_to_seconds(delete_after_ns) * 1e3 << " ms\n"
      << "  merge_distance           " << merge_distance_m * 1e3 << " mm\n";
}

Tracker::Tracker(TrackerOptions options) : options_(options) {}

void Tracker::set_calibration(const SystemCalibration& calibration) {
  for (const auto& camera : calibration.cameras) set_camera(camera);
}

void Tracker::set_camera(const CameraCalibration& camera) {
  if (!camera.T_world_cam) return;
  cameras_.insert_or_assign(camera.id, camera.model());
}

bool Tracker::has_camera(const std::string& camera_id) const {
  return cameras_.count(camera_id) != 0;
}

FrameOutcome Tracker::process(const FeatureFrame& frame) {
  ++stats_.frames;
  const auto camera_it = cameras_.find(frame.camera_id);
  if (camera_it == cameras_.end()) {
    ++stats_.frames_unknown_camera;
    return FrameOutcome::kUnknownCamera;
  }
  if (frame.stamp_ns < last_stamp_ns_) {
    ++stats_.frames_late;
    return FrameOutcome::kLate;
  }
  last_stamp_ns_ = frame.stamp_ns;
  stats_.blobs += frame.blobs.size();

  // One camera at a time (seed 003 §2.2.3.1): bring every track to this frame's instant.
  for (auto& track : tracks_) predict(track.state, frame.stamp_ns, options_.process_noise);

  std::vector<bool> used(frame.blobs.size(), false);
  associate_and_update(frame, camera_it->second, used);
  initiate(frame, camera_it->second, used);
  prune(frame.stamp_ns);
  return FrameOutcome::kProcessed;
}

void Tracker::associate_and_update(const FeatureFrame& frame, const CameraModel& camera,
                                   std::vector<bool>& used) {
  struct Candidate {
    double d2;
    std::size_t track;
    std::size_t blob;
  };
  std::vector<Candidate> candidates;
  std::vector<std::optional<PointProjection>> projections(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    projections[i] = project_point(tracks_[i].state, camera, options_.measurement_noise_px);
    if (!projections[i] || !camera.in_image(projections[i]->pixel, 20.0)) {
      projections[i].reset();
      continue;
    }
    for (std::size_t j = 0; j < frame.blobs.size(); ++j) {
      const Eigen::Vector2d z(frame.blobs[j].x, frame.blobs[j].y);
      const double d2 = mahalanobis2(*projections[i], z);
      // Verify region (seed 003 §2.2.3.2): only blobs inside the gate may update the track.
      if (d2 < options_.gate_chi2) candidates.push_back({d2, i, j});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::tie(a.d2, a.track, a.blob) < std::tie(b.d2, b.track, b.blob);
  });
  std::vector<bool> track_taken(tracks_.size(), false);
  for (const auto& candidate : candidates) {
    if (track_taken[candidate.track] || used[candidate.blob]) continue;
    track_taken[candidate.track] = true;
    used[candidate.blob] = true;
    Track& track = tracks_[candidate.track];
    const Eigen::Vector2d z(frame.blobs[candidate.blob].x, frame.blobs[candidate.blob].y);
    update(track.state, *projections[candidate.track], z, options_.measurement_noise_px);
    note_update(track, frame.camera_id, frame.stamp_ns);
    ++stats_.blobs_associated;
  }
}

void Tracker::initiate(const FeatureFrame& frame, const CameraModel& camera, const std::vector<bool>& used) {
  const double threshold = options_.init_reprojection_px;
  const int required_cameras =
      std::max(2, std::min<int>(options_.confirm_cameras, static_cast<int>(cameras_.size())));

  // Drop pending blobs that are too old to pair with this frame; this camera's older blobs are
  // superseded by the current frame.
  std::erase_if(pending_, [&](const PendingBlob& pending) {
    return pending.camera_id == frame.camera_id ||
           frame.stamp_ns - pending.stamp_ns > options_.init_window_ns;
  });

  std::vector<PendingBlob> still_unmatched;
  for (std::size_t j = 0; j < frame.blobs.size(); ++j) {
    if (used[j]) continue;
    const Eigen::Vector2d pixel(frame.blobs[j].x, frame.blobs[j].y);

    // Best pairing with another camera's pending blob, scored by how many further cameras agree.
    struct Best {
      int support = -1;
      double error = 0;
      std::vector<std::size_t> pending_indices;
      Eigen::Vector3d point;
    } best;
    for (std::size_t k = 0; k < pending_.size(); ++k) {
      const PendingBlob& partner = pending_[k];
      const CameraModel& partner_camera = cameras_.at(partner.camera_id);
      const auto pair = triangulate({{&camera, pixel}, {&partner_camera, partner.pixel}}, 3);
      if (!pair || pair->max_reprojection_px > threshold) continue;
      const Eigen::Vector3d point = pair->point;
      if ((camera.T_cam_world().apply(point)).z() < options_.min_depth_m ||
          (partner_camera.T_cam_world().apply(point)).z() < options_.min_depth_m) {
        continue;
      }
      // Support from third cameras: their nearest pending blob must reproject within threshold.
      std::vector<std::size_t> members = {k};
      std::map<std::string, std::pair<double, std::size_t>> per_camera;
      for (std::size_t m = 0; m < pending_.size(); ++m) {
        const PendingBlob& other = pending_[m];
        if (other.camera_id == partner.camera_id) continue;
        const double e = reprojection_error(cameras_.at(other.camera_id), point, other.pixel);
        if (e > threshold) continue;
        auto [it, inserted] = per_camera.try_emplace(other.camera_id, e, m);
        if (!inserted && e < it->second.first) it->second = {e, m};
      }
      for (const auto& [id, entry] : per_camera) members.push_back(entry.second);
      const int support = static_cast<int>(members.size()) - 1;
      if (support > best.support || (support == best.support && pair->max_reprojection_px < best.error)) {
        best = {support, pair->max_reprojection_px, members, point};
      }
    }
    if (best.support < 0) {
      still_unmatched.push_back({frame.camera_id, frame.stamp_ns, pixel});
      continue;
    }

    // Refine from every agreeing view.
    std::vector<Observation> observations = {{&camera, pixel}};
    for (std::size_t k : best.pending_indices) {
      observations.push_back({&cameras_.at(pending_[k].camera_id), pending_[k].pixel});
    }
    if (const auto all = triangulate(observations, 5); all && all->max_reprojection_px <= threshold) {
      best.point = all->point;
    }
    // A track already there will take this marker's blobs; do not start a duplicate.
    const bool near_existing = std::any_of(tracks_.begin(), tracks_.end(), [&](const Track& track) {
      return (track.state.position() - best.point).norm() < 4.0 * options_.merge_distance_m;
    });
    if (near_existing) continue;

    Track track;
    track.id = next_id_++;
    track.state.x.head<3>() = best.point;
    track.state.x.tail<3>().setZero();
    track.state.P.setZero();
    track.state.P.diagonal().head<3>().setConstant(options_.init_position_sigma_m *
                                                   options_.init_position_sigma_m);
    track.state.P.diagonal().tail<3>().setConstant(options_.init_velocity_sigma_mps *
                                                   options_.init_velocity_sigma_mps);
    track.state.stamp_ns = frame.stamp_ns;
    track.created_ns = frame.stamp_ns;
    track.last_update_ns = frame.stamp_ns;
    track.updates = 1;
    track.camera_last_update[frame.camera_id] = frame.stamp_ns;
    for (std::size_t k : best.pending_indices) {
      track.camera_last_update[pending_[k].camera_id] = pending_[k].stamp_ns;
    }
    if (static_cast<int>(track.camera_last_update.size()) >= required_cameras) {
      track.confirmed = true;
      ++stats_.tracks_confirmed;
    }
    ++stats_.tracks_created;
    // Consume the partner blobs (highest index first so the others stay valid).
    std::sort(best.pending_indices.rbegin(), best.pending_indices.rend());
    for (std::size_t k : best.pending_indices)
      pending_.erase(pending_.begin() + static_cast<std::ptrdiff_t>(k));
    tracks_.push_back(std::move(track));
  }
  for (auto& blob : still_unmatched) pending_.push_back(std::move(blob));
}

void Tracker::note_update(Track& track, const std::string& camera_id, TimeNs stamp_ns) {
  track.last_update_ns = stamp_ns;
  ++track.updates;
  track.camera_last_update[camera_id] = stamp_ns;
  const int required_cameras =
      std::max(2, std::min<int>(options_.confirm_cameras, static_cast<int>(cameras_.size())));
  if (!track.confirmed && static_cast<int>(track.camera_last_update.size()) >= required_cameras) {
    track.confirmed = true;
    ++stats_.tracks_confirmed;
  }
}

void Tracker::prune(TimeNs now_ns) {
  const auto before = tracks_.size();
  std::erase_if(tracks_, [&](const Track& track) {
    const TimeNs limit = track.confirmed ? options_.delete_after_ns : options_.tentative_delete_after_ns;
    return now_ns - track.last_update_ns > limit;
  });
  stats_.tracks_deleted += before - tracks_.size();

  // Duplicates of one marker: keep the track with the longer history.
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    for (std::size_t j = i + 1; j < tracks_.size(); ++j) {
      if ((tracks_[i].state.position() - tracks_[j].state.position()).norm() >= options_.merge_distance_m)
        continue;
      const bool keep_i = std::make_tuple(tracks_[i].confirmed, tracks_[i].updates) >=
                          std::make_tuple(tracks_[j].confirmed, tracks_[j].updates);
      tracks_.erase(tracks_.begin() + static_cast<std::ptrdiff_t>(keep_i ? j : i));
      ++stats_.tracks_merged;
      i = static_cast<std::size_t>(-1);  // restart: indices moved
      break;
    }
  }
}

TrackRecord Tracker::to_record(const Track& track, TimeNs stamp_ns) const {
  const PointState state = predicted(track.state, stamp_ns, options_.process_noise);
  TrackRecord record;
  record.stamp_ns = stamp_ns;
  record.id = track.id;
  record.p = state.position();
  record.v = state.velocity();
  const auto& P = state.P;
  record.position_covariance = {P(0, 0), P(0, 1), P(0, 2), P(1, 1), P(1, 2), P(2, 2)};
  if (!track.confirmed) {
    record.status = TrackStatus::kTentative;
  } else if (stamp_ns - track.last_update_ns > options_.coast_after_ns) {
    record.status = TrackStatus::kCoasting;
  } else {
    record.status = TrackStatus::kConfirmed;
  }
  record.cameras = static_cast<int>(std::count_if(
      track.camera_last_update.begin(), track.camera_last_update.end(),
      [&](const auto& entry) { return stamp_ns - entry.second <= options_.recent_camera_window_ns; }));
  return record;
}

std::vector<TrackRecord> Tracker::tracks_at(TimeNs stamp_ns) const {
  std::vector<TrackRecord> records;
  for (const auto& track : tracks_) {
    if (track.confirmed) records.push_back(to_record(track, stamp_ns));
  }
  std::sort(records.begin(), records.end(),
            [](const TrackRecord& a, const TrackRecord& b) { return a.id < b.id; });
  return records;
}

}  // namespace panoptes::estimator
