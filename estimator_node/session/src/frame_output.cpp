// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/frame_output.h"

#include <algorithm>
#include <cstddef>
#include <map>

#include "panoptes/estimator/marker_labels.h"

namespace panoptes::session {

FrameOutput FrameOutputBuilder::build(const estimator::Tracker& tracker, const FeatureFrame& frame,
                                      const FrameStages& stages, const std::vector<PoseRecord>& poses,
                                      const std::vector<TrackRecord>& tracks) {
  FrameOutput out;
  out.frame_number = ++frame_number_;
  out.stamp_ns = frame.stamp_ns;
  out.source_camera = frame.camera_id;
  out.source_frame = frame.frame;
  out.stages = stages;
  fill(out, tracker, frame.stamp_ns, poses, tracks);
  return out;
}

FrameOutput FrameOutputBuilder::build_at(const estimator::Tracker& tracker, std::uint64_t frame_number,
                                         TimeNs instant_ns, const FrameStages& stages,
                                         const std::vector<PoseRecord>& poses,
                                         const std::vector<TrackRecord>& tracks) const {
  FrameOutput out;
  out.frame_number = frame_number;
  out.stamp_ns = instant_ns;
  out.source_frame = -1;
  out.stages = stages;
  fill(out, tracker, instant_ns, poses, tracks);
  return out;
}

void FrameOutputBuilder::fill(FrameOutput& out, const estimator::Tracker& tracker, TimeNs label_stamp_ns,
                              const std::vector<PoseRecord>& poses,
                              const std::vector<TrackRecord>& tracks) const {
  const std::vector<BodyDefinition>& definitions = tracker.body_definitions();
  // Markers are labelled with the bodies' filter poses at this frame, not predicted or smoothed ones.
  const bool elsewhere = std::any_of(poses.begin(), poses.end(), [&](const PoseRecord& p) {
    return p.horizon_ns != 0 || p.stamp_ns != label_stamp_ns;
  });
  const estimator::MarkerLabelling labelling = estimator::label_markers(
      tracks, elsewhere ? tracker.poses_at(label_stamp_ns, 0, false) : poses, definitions, label_distance_m_);

  std::map<std::string, const PoseRecord*> pose_of;
  for (const auto& pose : poses) pose_of.emplace(pose.body, &pose);
  out.bodies.reserve(definitions.size());
  for (std::size_t b = 0; b < definitions.size(); ++b) {
    BodyOutput body;
    body.name = definitions[b].name;
    body.id = static_cast<int>(b) + 1;
    if (const auto it = pose_of.find(body.name); it != pose_of.end()) {
      body.tracking_valid = true;
      body.pose = *it->second;
    } else {
      body.pose.body = body.name;
      body.pose.stamp_ns = label_stamp_ns;
    }
    body.mean_marker_error_m = labelling.mean_error_m[b];
    body.labelled_markers = labelling.labelled_markers[b];
    out.bodies.push_back(std::move(body));
  }
  out.markers.reserve(tracks.size());
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    MarkerOutput marker;
    marker.track = tracks[t];
    if (const auto& label = labelling.labels[t]; label.body >= 0) {
      marker.body = definitions[static_cast<std::size_t>(label.body)].name;
      marker.body_marker = label.marker;
    }
    out.markers.push_back(std::move(marker));
  }
}

}  // namespace panoptes::session
