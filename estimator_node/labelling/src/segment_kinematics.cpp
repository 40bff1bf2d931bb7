// SPDX-License-Identifier: Apache-2.0
#include "panoptes/labelling/segment_kinematics.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>

#include <Eigen/Geometry>

#include "panoptes/errors.h"
#include "panoptes/rigid_fit.h"

namespace panoptes::labelling {

namespace {

constexpr double kDegrees = 180.0 / 3.14159265358979323846;

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

bool contains(const std::string& text, const char* part) {
  return lower(text).find(part) != std::string::npos;
}

// The model's segment indices, every parent before its children. Throws on an unknown parent, a
// cycle or not exactly one root.
std::vector<std::size_t> tree_order(const SubjectModel& model) {
  std::map<std::string, std::size_t> index;
  for (std::size_t s = 0; s < model.segments.size(); ++s) index[model.segments[s].name] = s;
  std::vector<std::size_t> order;
  std::vector<bool> placed(model.segments.size(), false);
  for (const auto& segment : model.segments) {
    if (!segment.parent.empty() && index.count(segment.parent) == 0)
      throw InputError(model.subject + ": segment " + segment.name + ": unknown parent " + segment.parent);
  }
  while (order.size() < model.segments.size()) {
    const std::size_t before = order.size();
    for (std::size_t s = 0; s < model.segments.size(); ++s) {
      const auto& parent = model.segments[s].parent;
      if (placed[s] || (!parent.empty() && !placed[index[parent]])) continue;
      if (parent.empty() && !order.empty())
        throw InputError(model.subject + ": segment " + model.segments[s].name + ": a second root");
      placed[s] = true;
      order.push_back(s);
    }
    if (order.size() == before)
      throw InputError(model.subject + ": the segments do not form a tree (a cycle or no root)");
  }
  return order;
}

// A joint centre's position in the static trial's world: the child's origin plus the centre in the
// child's layout frame (layout axes are the lab's in the static pose).
Eigen::Vector3d static_centre(const SubjectModel& model, const JointCentre& joint) {
  const SegmentLayout* child = model.segment(joint.child);
  return child->origin_m + joint.in_child_m;
}

std::optional<std::size_t> find_joint(const SubjectModel& model, const std::string& child) {
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    if (model.joints[j].child == child) return j;
  }
  return std::nullopt;
}

// The anatomical frame of one segment in the static pose (module comment; docs/marker_sets.md):
// Y from the distal to the proximal joint centre where the model has both, else the vertical; Z
// the subject's right made orthogonal to Y; X = Y × Z. Origin: the proximal joint centre, else the
// technical origin.
AnatomicalSegment anatomical_segment(const SubjectModel& model, std::size_t s, const Eigen::Vector3d& right,
                                     const KinematicsOptions& options) {
  const SegmentLayout& layout = model.segments[s];
  AnatomicalSegment out;
  out.name = layout.name;
  out.model_segment = s;
  out.joint = find_joint(model, layout.name);
  std::vector<std::size_t> distal;
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    if (model.joints[j].parent == layout.name) distal.push_back(j);
  }
  Eigen::Vector3d y = options.up.normalized();
  out.long_axis = "vertical";
  Eigen::Vector3d origin = layout.origin_m;
  if (out.joint) origin = static_centre(model, model.joints[*out.joint]);
  if (out.joint && distal.size() == 1) {
    const Eigen::Vector3d along = origin - static_centre(model, model.joints[distal.front()]);
    if (along.norm() > 1e-3) {
      y = along.normalized();
      out.long_axis = model.joints[distal.front()].name + " -> " + model.joints[*out.joint].name;
    }
  }
  const Eigen::Vector3d z = (right - right.dot(y) * y).normalized();
  Eigen::Matrix3d axes;
  axes.col(0) = y.cross(z);
  axes.col(1) = y;
  axes.col(2) = z;
  out.T_technical_anatomical.q = Eigen::Quaterniond(axes);
  out.T_technical_anatomical.t = origin - layout.origin_m;
  return out;
}

bool is_knee(const JointAngleDefinition& joint, const std::string& child, const KinematicsOptions& options) {
  if (!options.knee_joints.empty())
    return std::find(options.knee_joints.begin(), options.knee_joints.end(), joint.name) !=
           options.knee_joints.end();
  return contains(joint.name, "knee") || contains(child, "shank") || contains(child, "tibia");
}

}  // namespace

std::optional<Eigen::Vector3d> axis_from_name(const std::string& name) {
  std::string axis = name;
  double sign = 1.0;
  if (!axis.empty() && (axis[0] == '+' || axis[0] == '-')) {
    sign = axis[0] == '-' ? -1.0 : 1.0;
    axis = axis.substr(1);
  }
  if (axis == "x" || axis == "X") return sign * Eigen::Vector3d::UnitX();
  if (axis == "y" || axis == "Y") return sign * Eigen::Vector3d::UnitY();
  if (axis == "z" || axis == "Z") return sign * Eigen::Vector3d::UnitZ();
  return std::nullopt;
}

SegmentKinematics build_segment_kinematics(const SubjectModel& model, const KinematicsOptions& options) {
  const Eigen::Vector3d up = options.up;
  const Eigen::Vector3d forward = options.forward;
  if (up.norm() < 1e-9 || forward.norm() < 1e-9 || std::abs(up.normalized().dot(forward.normalized())) > 1e-6)
    throw InputError(model.subject + ": the up and forward axes must be orthogonal and non-zero");
  const Eigen::Vector3d right = forward.normalized().cross(up.normalized());
  SegmentKinematics out;
  out.subject = model.subject;
  out.joint_centres_in_fit = options.joint_centres_in_fit;
  const auto order = tree_order(model);
  std::map<std::string, std::size_t> position;
  for (const std::size_t s : order) {
    AnatomicalSegment segment = anatomical_segment(model, s, right, options);
    const auto& parent = model.segments[s].parent;
    if (!parent.empty()) segment.parent = position.at(parent);
    const double across = (model.segments[s].origin_m - model.segments[order.front()].origin_m).dot(right);
    if (std::abs(across) > options.side_threshold_m) segment.side = across > 0 ? 1 : -1;
    position[segment.name] = out.segments.size();
    out.segments.push_back(segment);
  }
  for (std::size_t c = 0; c < out.segments.size(); ++c) {
    const AnatomicalSegment& child = out.segments[c];
    if (!child.parent) continue;
    JointAngleDefinition joint;
    joint.parent = *child.parent;
    joint.child = c;
    joint.name =
        child.joint ? model.joints[*child.joint].name : out.segments[joint.parent].name + "-" + child.name;
    joint.knee = is_knee(joint, child.name, options);
    out.joints.push_back(joint);
  }
  return out;
}

SegmentPoints segment_points(const SegmentKinematics& kinematics, const SubjectModel& model,
                             const MarkerSamples& samples, std::size_t frame) {
  std::map<std::string, std::size_t> column;
  for (std::size_t p = 0; p < samples.point_count(); ++p) column.emplace(samples.names[p], p);
  SegmentPoints points;
  for (const auto& segment : kinematics.segments) {
    const SegmentLayout& layout = model.segments[segment.model_segment];
    std::vector<std::optional<Eigen::Vector3d>> seen(layout.markers.size());
    for (std::size_t m = 0; m < layout.markers.size(); ++m) {
      const auto found = column.find(layout.markers[m].name);
      if (found == column.end() || frame >= samples.frame_count() || !samples.is_valid(frame, found->second))
        continue;
      const Eigen::Vector3d& p = samples.position(frame, found->second);
      if (p.allFinite()) seen[m] = p;
    }
    points.push_back(std::move(seen));
  }
  return points;
}

namespace {

// The layout's seen tracked markers and, with `joint`, its centre where the parent's pose puts it.
std::optional<LayoutFit> fit_segment(const SegmentLayout& layout, const JointCentre* joint,
                                     const RigidTransform& T_world_parent,
                                     const std::vector<std::optional<Eigen::Vector3d>>& points) {
  std::vector<Eigen::Vector3d> from;
  std::vector<Eigen::Vector3d> to;
  for (std::size_t m = 0; m < layout.markers.size() && m < points.size(); ++m) {
    if (layout.markers[m].calibration_only || !points[m]) continue;
    from.push_back(layout.markers[m].position_m);
    to.push_back(*points[m]);
  }
  const std::size_t markers = from.size();
  if (joint) {
    from.push_back(joint->in_child_m);
    to.push_back(T_world_parent.apply(joint->in_parent_m));
  }
  double rms = 0.0;
  const auto T = fit_rigid_transform(from, to, &rms);
  if (!T) return std::nullopt;
  return LayoutFit{*T, rms, markers};
}

std::size_t seen_tracked(const SegmentLayout& layout,
                         const std::vector<std::optional<Eigen::Vector3d>>& points) {
  std::size_t seen = 0;
  for (std::size_t m = 0; m < layout.markers.size() && m < points.size(); ++m) {
    if (!layout.markers[m].calibration_only && points[m]) ++seen;
  }
  return seen;
}

JointAngles joint_angles(const JointAngleDefinition& joint, const SegmentKinematics& kinematics,
                         const std::vector<SegmentPose>& poses) {
  JointAngles angles;
  const SegmentPose& parent = poses[joint.parent];
  const SegmentPose& child = poses[joint.child];
  if (!parent.valid || !child.valid) return angles;
  const Eigen::Matrix3d relative =
      parent.T_world_anatomical.rotation().transpose() * child.T_world_anatomical.rotation();
  const Eigen::Vector3d zxy = cardan_zxy(relative) * kDegrees;
  const double mirror = kinematics.segments[joint.child].side < 0 ? -1.0 : 1.0;
  angles.valid = true;
  angles.flexion_deg = joint.knee ? -zxy.x() : zxy.x();
  angles.adduction_deg = mirror * zxy.y();
  angles.internal_rotation_deg = mirror * zxy.z();
  return angles;
}

}  // namespace

KinematicsFrame compute_kinematics(const SegmentKinematics& kinematics, const SubjectModel& model,
                                   const SegmentPoints& points) {
  KinematicsFrame frame;
  frame.poses.resize(kinematics.segments.size());
  for (std::size_t s = 0; s < kinematics.segments.size() && s < points.size(); ++s) {
    const AnatomicalSegment& segment = kinematics.segments[s];
    const SegmentLayout& layout = model.segments[segment.model_segment];
    const std::size_t seen = seen_tracked(layout, points[s]);
    const bool parent_posed = segment.joint && segment.parent && frame.poses[*segment.parent].valid;
    const bool joint_centre = parent_posed && (seen == 2 || (seen >= 2 && kinematics.joint_centres_in_fit));
    RigidTransform T_world_parent;
    if (joint_centre) {
      const AnatomicalSegment& parent = kinematics.segments[*segment.parent];
      T_world_parent =
          frame.poses[*segment.parent].T_world_anatomical * parent.T_technical_anatomical.inverse();
    }
    std::optional<LayoutFit> fit;
    if (seen >= 3 || joint_centre)
      fit = fit_segment(layout, joint_centre ? &model.joints[*segment.joint] : nullptr, T_world_parent,
                        points[s]);
    if (!fit) continue;
    SegmentPose& pose = frame.poses[s];
    pose.valid = true;
    pose.T_world_anatomical = fit->T_world_segment * segment.T_technical_anatomical;
    pose.rms_m = fit->rms_m;
    pose.markers_used = fit->markers_used;
    pose.used_joint_centre = joint_centre;
  }
  for (const auto& joint : kinematics.joints)
    frame.angles.push_back(joint_angles(joint, kinematics, frame.poses));
  return frame;
}

Eigen::Vector3d cardan_zxy(const Eigen::Matrix3d& R) {
  // Rz(a)Rx(b)Ry(c): R(2,1) = sin b, R(0,1) = −sin a cos b, R(1,1) = cos a cos b,
  // R(2,0) = −cos b sin c, R(2,2) = cos b cos c.
  const double b = std::asin(std::clamp(R(2, 1), -1.0, 1.0));
  const double a = std::atan2(-R(0, 1), R(1, 1));
  const double c = std::atan2(-R(2, 0), R(2, 2));
  return {a, b, c};
}

double rotation_angle_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return Eigen::AngleAxisd(a.conjugate() * b).angle() * kDegrees;
}

}  // namespace panoptes::labelling
