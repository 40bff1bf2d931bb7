// SPDX-License-Identifier: Apache-2.0
// Segment poses and joint angles from labelled markers and a subject model (docs/marker_sets.md,
// "Segment poses and joint angles"): per frame a 6-DoF pose of every segment that has enough
// markers, in an anatomical frame (X anterior, Y superior, Z right, as ISB), and the Cardan angles
// Z-X-Y (Grood-Suntay) between each segment and its parent. Maths only: no files, no DDS.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/geometry.h"
#include "panoptes/labelling/subject_model.h"

namespace panoptes::labelling {

struct KinematicsOptions {
  // The static trial's vertical and the direction the subject faces in it, in the trial's axes
  // (OpenSim's TRC files: Y up, the subject facing +X). Right = forward × up.
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  Eigen::Vector3d forward = Eigen::Vector3d::UnitX();
  // Joints whose flexion is the negative rotation about the parent's Z (the knee: the shank swings
  // back). Empty: every joint whose name contains "knee" or whose child's name contains "shank" or
  // "tibia" (any case).
  std::vector<std::string> knee_joints;
  // A segment whose origin is farther than this from the root's along the right axis in the static
  // pose is on the right (+) or left (−) side; its adduction and rotation are mirrored on the left.
  double side_threshold_m = 0.03;
  // Fit a child segment's markers together with its proximal joint centre placed by the parent's
  // pose (one more point: steadier against marker noise, but the parent's soft tissue and the
  // centre's error move the child: Gait2392's knee flexion changes by 2.4 deg RMS, 6.9 max).
  // Without it (default, each segment on its own markers: "6 DoF") the joint centre is used only
  // when two markers are seen.
  bool joint_centres_in_fit = false;
};

// "+x", "-y", "z", … (a sign, then x, y or z in either case) as a unit axis; nullopt otherwise.
std::optional<Eigen::Vector3d> axis_from_name(const std::string& name);

// A segment's anatomical frame, fixed in its technical (layout) frame from the static pose.
struct AnatomicalSegment {
  std::string name;
  std::optional<std::size_t> parent;      // index into SegmentKinematics::segments
  std::optional<std::size_t> joint;       // the model's joint centre with this segment as child
  std::size_t model_segment = 0;          // index into SubjectModel::segments
  RigidTransform T_technical_anatomical;  // the anatomical frame in the layout's frame
  std::string long_axis;                  // how Y was defined, for the report
  int side = 0;                           // +1 right, −1 left, 0 on the midline
};

// The angles of `child` relative to its parent segment.
struct JointAngleDefinition {
  std::string name;  // the model's joint name, else "<parent>-<child>"
  std::size_t parent = 0;
  std::size_t child = 0;
  bool knee = false;  // flexion = −(rotation about Z)
};

// Built once per subject model; segments in tree order (every parent before its children).
struct SegmentKinematics {
  std::string subject;
  std::vector<AnatomicalSegment> segments;
  std::vector<JointAngleDefinition> joints;
  bool joint_centres_in_fit = false;
};

// Throws InputError naming the subject when `up` and `forward` are not orthogonal non-zero axes, or
// the model's segments do not form one tree (unknown parent, cycle).
SegmentKinematics build_segment_kinematics(const SubjectModel& model, const KinematicsOptions& options = {});

struct SegmentPose {
  bool valid = false;
  RigidTransform T_world_anatomical;
  double rms_m = 0.0;              // RMS residual of the rigid fit
  std::size_t markers_used = 0;    // tracked markers fitted
  bool used_joint_centre = false;  // two markers and the joint centre from the parent's pose
};

// Degrees. Flexion positive (hip and knee flexion, ankle dorsiflexion, elbow flexion), adduction
// positive, internal rotation positive, on both sides (left mirrored, ISB).
struct JointAngles {
  bool valid = false;
  double flexion_deg = 0.0;
  double adduction_deg = 0.0;
  double internal_rotation_deg = 0.0;
};

struct KinematicsFrame {
  std::vector<SegmentPose> poses;   // as SegmentKinematics::segments
  std::vector<JointAngles> angles;  // as SegmentKinematics::joints
};

// One frame's observations per segment of SegmentKinematics::segments, each in its model layout's
// marker order (as fit_layout takes them): nullopt when unseen.
using SegmentPoints = std::vector<std::vector<std::optional<Eigen::Vector3d>>>;

// The points of frame `frame` of `samples`, matched to the model's markers by name.
SegmentPoints segment_points(const SegmentKinematics& kinematics, const SubjectModel& model,
                             const MarkerSamples& samples, std::size_t frame);

// Poses (a rigid fit of the layout's tracked markers: ≥ 3 seen, or 2 and the joint centre placed by
// the parent's pose) and angles. No pose rather than a wrong one: too few markers or collinear.
KinematicsFrame compute_kinematics(const SegmentKinematics& kinematics, const SubjectModel& model,
                                   const SegmentPoints& points);

// Rotation R = Rz(a)·Rx(b)·Ry(c) (intrinsic Z, then X', then Y''): {a, b, c} in radians, b in
// [−π/2, π/2].
Eigen::Vector3d cardan_zxy(const Eigen::Matrix3d& R);

// The angle in degrees of the rotation between two frames' orientations.
double rotation_angle_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);

}  // namespace panoptes::labelling
