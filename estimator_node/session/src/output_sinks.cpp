// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/output_sinks.h"

namespace panoptes::session {

JsonlOutputs::JsonlOutputs(const std::string& tracks_path, const std::string& poses_path) {
  if (!tracks_path.empty()) tracks_.emplace(tracks_path);
  if (!poses_path.empty()) poses_.emplace(poses_path);
}

void JsonlOutputs::write_tracks(const std::vector<TrackRecord>& tracks) {
  if (!tracks_) return;
  for (const auto& track : tracks) tracks_->write(track);
  track_records_ += tracks.size();
}

void JsonlOutputs::write_poses(const std::vector<PoseRecord>& poses) {
  if (!poses_) return;
  for (const auto& pose : poses) poses_->write(pose);
  pose_records_ += poses.size();
}

void JsonlOutputs::flush() {
  if (tracks_) tracks_->flush();
  if (poses_) poses_->flush();
}

std::string JsonlOutputs::summary() const {
  return "wrote " + std::to_string(track_records_) + " track records" +
         (poses_ ? ", " + std::to_string(pose_records_) + " pose records" : "");
}

}  // namespace panoptes::session
