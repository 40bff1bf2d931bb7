// SPDX-License-Identifier: Apache-2.0
// Live segment poses (issue 33 item 4; docs/marker_sets.md, "Segment poses live"): after a frame's
// markers carry their names (LabelStage), every segment of every subject with enough named markers
// gets a 6-DoF pose in its anatomical frame (labelling::compute_kinematics, the offline
// `panoptes_label angles` maths), appended to the frame's bodies as "<subject>/<segment>". So the
// poses travel wherever bodies do: rt/panoptes/frames, the clients, ROS 2 /rigid_bodies and /tf
// (one tree per subject), recordings and their export. No files, no DDS.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/labelling/segment_kinematics.h"
#include "panoptes/labelling/subject_model.h"
#include "panoptes/session/frame_output.h"

namespace panoptes::session {

class SegmentStage {
 public:
  // Throws InputError naming the subject when `options`' axes are not orthogonal.
  SegmentStage(std::vector<labelling::SubjectModel> models, const labelling::KinematicsOptions& options);

  // One description per segment that can be posed (≥ 3 tracked markers, or 2 and a joint centre in
  // its parent; Gait2392: 9 of 13, not the two-marker arms), in the models' order then tree order:
  // name "<subject>/<segment>", the layout's tracked markers in the anatomical frame (the pose's
  // frame), kind passive. BodyDescriptions lists them after the bodies with kind "segment".
  const std::vector<BodyDefinition>& descriptions() const { return descriptions_; }

  // Appends the segments' bodies to `out.bodies` from its markers' names (MarkerOutput::subject,
  // ::name): every described segment, its id from `ids` (by name; a segment without one is left
  // out), tracking_valid where a pose was fitted (≥ 3 named markers, or 2 and the joint centre the
  // parent's pose places), mean_marker_error_m the fit's RMS, quality the share of its tracked markers
  // fitted, the pose stamped with the frame. No velocity and no σ (zeros): a fit, not a filter.
  void append(FrameOutput& out, const std::map<std::string, int>& ids) const;

  std::size_t segment_count() const { return descriptions_.size(); }

 private:
  // Where a marker name goes: segment (kinematics order) and marker (layout order) of a subject.
  struct Slot {
    std::size_t segment = 0;
    std::size_t marker = 0;
  };
  struct Subject {
    labelling::SubjectModel model;
    labelling::SegmentKinematics kinematics;
    std::vector<std::size_t> tracked;       // per kinematics segment: its tracked markers, 0 if unposeable
    std::vector<std::string> body_names;    // per kinematics segment: "<subject>/<segment>"
    std::vector<std::string> parent_names;  // per kinematics segment: the parent's body name or ""
    std::unordered_map<std::string, std::vector<Slot>> slots;  // by marker name
  };
  std::vector<Subject> subjects_;
  // The points of one subject's segments, reused from frame to frame (append runs on the estimator
  // thread only).
  mutable labelling::SegmentPoints points_;
  std::vector<BodyDefinition> descriptions_;
};

}  // namespace panoptes::session
