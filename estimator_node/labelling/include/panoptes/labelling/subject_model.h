// SPDX-License-Identifier: Apache-2.0
// A subject model: one person's marker layouts per segment, inter-marker distance statistics with
// tolerances and joint centres, built from a static trial (docs/marker_sets.md, "Algorithm").
// Maths only: the static file is read and the model written by panoptes_labelling_files.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/geometry.h"
#include "panoptes/labelling/marker_set.h"

namespace panoptes::labelling {

// Named points sampled over frames, in metres (what a static trial holds). Per-sample arrays are
// frame-major: [frame * names.size() + point].
struct MarkerSamples {
  std::string source;  // the file, for messages
  double rate_hz = 0.0;
  std::vector<std::string> names;
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::uint8_t> valid;

  std::size_t point_count() const { return names.size(); }
  std::size_t frame_count() const { return names.empty() ? 0 : positions.size() / names.size(); }
  const Eigen::Vector3d& position(std::size_t frame, std::size_t point) const {
    return positions[frame * point_count() + point];
  }
  bool is_valid(std::size_t frame, std::size_t point) const {
    return valid[frame * point_count() + point] != 0;
  }
};

struct ModelOptions {
  double sigmas = 3.0;  // tolerance = max(sigmas * sd, min_tolerance_m), dynamic: and the range
  double min_tolerance_m = 0.002;
  double still_m = 0.020;  // a marker spreading more (RMS about its mean) has moved
  int procrustes_iterations = 3;
  // Trained from an already-labelled dynamic trial instead of a static one (as AIM can): the
  // subject moves (no `moved` flags), calibration-only markers and the joints that need them may be
  // absent (left out and flagged), and each tolerance also covers the distance's whole range.
  bool dynamic = false;
};

struct ModelMarker {
  std::string name;
  bool calibration_only = false;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // in the segment frame
  std::size_t missing_frames = 0;
  double spread_m = 0.0;  // RMS of its world position about its mean over the trial
};

struct DistanceStatistics {
  std::array<std::string, 2> markers;
  double mean_m = 0.0;
  double sd_m = 0.0;
  double min_m = 0.0;
  double max_m = 0.0;
  double tolerance_m = 0.0;
  std::size_t frames = 0;
};

// Segment frame: origin the centroid of the tracked (not calibration-only) markers, axes parallel
// to the lab's in the static pose.
struct SegmentLayout {
  std::string name;
  std::string parent;
  bool has_pose = false;          // >= 3 tracked markers, not collinear
  double static_fit_rms_m = 0.0;  // the static frames fitted with every marker (calibration-only too)
  // The frame's origin in the trial's world, averaged: where the segment sat relative to the others in
  // the static pose (the labeller's tree search starts from it).
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  std::vector<ModelMarker> markers;
  std::vector<DistanceStatistics> distances;

  std::vector<std::string> tracked_marker_names() const;
};

struct JointCentre {
  std::string name;
  std::string parent;
  std::string child;
  Eigen::Vector3d in_parent_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d in_child_m = Eigen::Vector3d::Zero();
};

// A marker (or, for "absent", a marker set entry) the report must mention.
struct MarkerFlag {
  // kRepeated: the trial has several points of the marker's name (C3D files can); the first is used.
  enum class Kind { kAbsent, kMissingFrames, kMoved, kRepeated };
  Kind kind = Kind::kMoved;
  std::string marker;
  std::string reason;
};

struct SubjectModel {
  std::string subject;
  std::string marker_set;
  std::string trial_file;  // the static (or, options.dynamic, labelled) trial it was built from
  std::size_t frames = 0;
  double rate_hz = 0.0;
  ModelOptions options;
  std::vector<SegmentLayout> segments;
  std::vector<JointCentre> joints;
  std::vector<std::array<std::string, 2>> sticks;
  std::vector<MarkerFlag> flags;
  std::vector<std::string> ignored_points;  // in the trial, not named by the set

  const SegmentLayout* segment(const std::string& name) const;
  std::size_t marker_count() const;
};

// Builds the model of `set` (valid: find_marker_set_problem) from `trial`. Throws InputError naming
// the trial and the marker when a marker that is not optional is absent or never seen, and when a
// joint's point is; an optional one is left out and flagged (options.dynamic: calibration-only
// markers and joints too).
SubjectModel build_subject_model(const MarkerSet& set, const MarkerSamples& trial, const std::string& subject,
                                 const ModelOptions& options = {});

// What is wrong with a model read from a file (entry as in the file: "segments[2].distances[0]"),
// or nullopt: duplicate segment or marker names, an unknown parent or a cycle, a distance between
// markers not in its segment or a tolerance that is not positive, a joint on unknown segments,
// non-finite numbers.
std::optional<MarkerSetProblem> find_subject_model_problem(const SubjectModel& model);

// Frames [first, last) of `samples` (clamped to its length), e.g. half a trial to train on.
MarkerSamples slice_frames(const MarkerSamples& samples, std::size_t first, std::size_t last);

// The rigid fit of `layout`'s tracked markers to one frame of points: T_world_segment, its RMS
// residual and how many markers were used. `frame_points[i]` is the observation of
// layout.markers[i] or nullopt when unseen. nullopt below 3 seen tracked markers or collinear ones.
struct LayoutFit {
  RigidTransform T_world_segment;
  double rms_m = 0.0;
  std::size_t markers_used = 0;
};
std::optional<LayoutFit> fit_layout(const SegmentLayout& layout,
                                    const std::vector<std::optional<Eigen::Vector3d>>& frame_points);

}  // namespace panoptes::labelling
