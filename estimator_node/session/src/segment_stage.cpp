// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/segment_stage.h"

#include <utility>

namespace panoptes::session {

SegmentStage::SegmentStage(std::vector<labelling::SubjectModel> models,
                           const labelling::KinematicsOptions& options) {
  for (auto& model : models) {
    Subject subject;
    subject.kinematics = labelling::build_segment_kinematics(model, options);
    subject.model = std::move(model);
    const auto& segments = subject.kinematics.segments;
    for (const auto& segment : segments) {
      const labelling::SegmentLayout& layout = subject.model.segments[segment.model_segment];
      // Only a segment that can be posed: 3 tracked markers, or 2 and a joint centre in its parent.
      const std::size_t tracked = layout.tracked_marker_names().size();
      const bool poseable = tracked >= 3 || (tracked == 2 && segment.joint && segment.parent);
      subject.tracked.push_back(poseable ? tracked : 0);
      subject.body_names.push_back(subject.model.subject + "/" + segment.name);
    }
    for (std::size_t s = 0; s < segments.size(); ++s) {
      const labelling::SegmentLayout& layout = subject.model.segments[segments[s].model_segment];
      for (std::size_t m = 0; m < layout.markers.size(); ++m)
        subject.slots[layout.markers[m].name].push_back({s, m});
    }
    for (std::size_t s = 0; s < segments.size(); ++s) {
      // The nearest ancestor that is published (a segment without tracked markers has no body).
      auto parent = segments[s].parent;
      while (parent && subject.tracked[*parent] == 0) parent = segments[*parent].parent;
      subject.parent_names.push_back(parent ? subject.body_names[*parent] : "");
      if (subject.tracked[s] == 0) continue;
      const labelling::SegmentLayout& layout = subject.model.segments[segments[s].model_segment];
      const RigidTransform T_anatomical_technical = segments[s].T_technical_anatomical.inverse();
      BodyDefinition description;
      description.name = subject.body_names[s];
      for (const auto& marker : layout.markers) {
        if (!marker.calibration_only)
          description.markers.push_back(T_anatomical_technical.apply(marker.position_m));
      }
      descriptions_.push_back(std::move(description));
    }
    subjects_.push_back(std::move(subject));
  }
}

void SegmentStage::append(FrameOutput& out, const std::map<std::string, int>& ids) const {
  for (const Subject& subject : subjects_) {
    const auto& segments = subject.kinematics.segments;
    points_.resize(segments.size());
    for (std::size_t s = 0; s < segments.size(); ++s) {
      points_[s].assign(subject.model.segments[segments[s].model_segment].markers.size(), std::nullopt);
    }
    for (const auto& marker : out.markers) {
      if (marker.name.empty() || marker.subject != subject.model.subject) continue;
      const auto slots = subject.slots.find(marker.name);
      if (slots == subject.slots.end()) continue;
      for (const Slot& slot : slots->second) points_[slot.segment][slot.marker] = marker.track.p;
    }
    const labelling::KinematicsFrame frame =
        labelling::compute_kinematics(subject.kinematics, subject.model, points_);
    for (std::size_t s = 0; s < segments.size(); ++s) {
      const auto id = ids.find(subject.body_names[s]);
      if (subject.tracked[s] == 0 || id == ids.end()) continue;
      BodyOutput body;
      body.name = subject.body_names[s];
      body.id = id->second;
      body.segment = true;
      body.parent = subject.parent_names[s];
      body.pose.body = body.name;
      body.pose.stamp_ns = out.stamp_ns;
      const labelling::SegmentPose& pose = frame.poses[s];
      if (pose.valid) {
        body.tracking_valid = true;
        body.pose.p = pose.T_world_anatomical.t;
        const Eigen::Quaterniond& q = pose.T_world_anatomical.q;
        body.pose.q = Eigen::Vector4d(q.x(), q.y(), q.z(), q.w());
        body.pose.quality = static_cast<double>(pose.markers_used) / static_cast<double>(subject.tracked[s]);
        body.mean_marker_error_m = pose.rms_m;
        body.labelled_markers = static_cast<int>(pose.markers_used);
      }
      out.bodies.push_back(std::move(body));
    }
  }
}

}  // namespace panoptes::session
