// SPDX-License-Identifier: Apache-2.0
#include "panoptes/labelling/subject_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <utility>

#include "panoptes/errors.h"
#include "panoptes/rigid_fit.h"

namespace panoptes::labelling {

namespace {

using Points = std::vector<std::optional<Eigen::Vector3d>>;

std::string millimetres(double metres) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f mm", metres * 1000.0);
  return text;
}

std::optional<std::size_t> column_of(const MarkerSamples& trial, const std::string& name) {
  const auto found = std::find(trial.names.begin(), trial.names.end(), name);
  if (found == trial.names.end()) return std::nullopt;
  return static_cast<std::size_t>(found - trial.names.begin());
}

std::size_t seen_frames(const MarkerSamples& trial, std::size_t column) {
  std::size_t seen = 0;
  for (std::size_t f = 0; f < trial.frame_count(); ++f) seen += trial.is_valid(f, column) ? 1 : 0;
  return seen;
}

const char* trial_kind(const ModelOptions& options) {
  return options.dynamic ? "labelled trial" : "static trial";
}

// The trial's column of every marker of the set; nullopt for an optional marker the trial lacks
// (flagged). Throws for a marker that is not optional.
std::vector<std::optional<std::size_t>> match_markers(const MarkerSet& set, const MarkerSamples& trial,
                                                      const ModelOptions& options,
                                                      std::vector<MarkerFlag>& flags) {
  std::vector<std::optional<std::size_t>> columns;
  for (std::size_t i = 0; i < set.markers.size(); ++i) {
    const MarkerDefinition& marker = set.markers[i];
    const auto column = column_of(trial, marker.name);
    const bool seen = column && seen_frames(trial, *column) > 0;
    std::string why = std::string(column ? "is never seen in the " : "is not in the ") + trial_kind(options);
    const bool may_lack = marker.optional || (options.dynamic && marker.calibration_only);
    if (!seen && !may_lack)
      throw InputError(trial.source + ": marker '" + marker.name + "' (marker set '" + set.name +
                       "', markers[" + std::to_string(i) + "]) " + why +
                       " (mark it `optional: true` to build without it)");
    if (!seen)
      flags.push_back(
          {MarkerFlag::Kind::kAbsent, marker.name,
           std::string(marker.optional ? "optional" : "calibration-only") + " marker " + why + ": left out"});
    const auto repeats = std::count(trial.names.begin(), trial.names.end(), marker.name);
    if (repeats > 1)
      flags.push_back({MarkerFlag::Kind::kRepeated, marker.name,
                       std::string("the ") + trial_kind(options) + " has " + std::to_string(repeats) +
                           " points of this name: the first is used"});
    columns.push_back(seen ? column : std::nullopt);
  }
  return columns;
}

std::vector<std::string> ignored_points(const MarkerSet& set, const MarkerSamples& trial) {
  std::vector<std::string> ignored;
  for (const auto& name : trial.names) {
    bool named = set.marker_index(name).has_value();
    for (const auto& joint : set.joints)
      named = named || std::count(joint.points.begin(), joint.points.end(), name);
    if (!named) ignored.push_back(name);
  }
  return ignored;
}

// Frames missing and the RMS spread about the mean position; flags both.
ModelMarker describe_marker(const MarkerSamples& trial, const MarkerDefinition& marker, std::size_t column,
                            const ModelOptions& options, std::vector<MarkerFlag>& flags) {
  ModelMarker out{marker.name, marker.calibration_only};
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::size_t seen = 0;
  for (std::size_t f = 0; f < trial.frame_count(); ++f) {
    if (!trial.is_valid(f, column)) continue;
    sum += trial.position(f, column);
    ++seen;
  }
  const Eigen::Vector3d mean = sum / static_cast<double>(seen);
  double squares = 0.0;
  for (std::size_t f = 0; f < trial.frame_count(); ++f) {
    if (trial.is_valid(f, column)) squares += (trial.position(f, column) - mean).squaredNorm();
  }
  out.position_m = mean;  // world for now; the layout moves it into the segment frame
  out.missing_frames = trial.frame_count() - seen;
  out.spread_m = std::sqrt(squares / static_cast<double>(seen));
  if (out.missing_frames > 0)
    flags.push_back({MarkerFlag::Kind::kMissingFrames, marker.name,
                     "missing in " + std::to_string(out.missing_frames) + " of " +
                         std::to_string(trial.frame_count()) + " frames of the " + trial_kind(options)});
  if (out.spread_m > options.still_m && !options.dynamic)
    flags.push_back({MarkerFlag::Kind::kMoved, marker.name,
                     "moved " + millimetres(out.spread_m) +
                         " RMS during the static trial (still: " + millimetres(options.still_m) + ")"});
  return out;
}

// One segment while it is built: the layout and each of its markers' trial column.
struct SegmentWork {
  SegmentLayout layout;
  std::vector<std::size_t> columns;
  std::vector<std::optional<RigidTransform>> T_world_segment;  // per frame of the trial
  bool static_rigid = false;  // all its markers (calibration-only too) span a frame
};

Points frame_points(const MarkerSamples& trial, const SegmentWork& work, std::size_t frame) {
  Points points;
  for (std::size_t column : work.columns) {
    points.push_back(trial.is_valid(frame, column) ? std::optional(trial.position(frame, column))
                                                   : std::nullopt);
  }
  return points;
}

// Moves the origin to the centroid of the tracked markers.
void recentre(SegmentLayout& layout) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double count = 0.0;
  for (const auto& marker : layout.markers) {
    if (marker.calibration_only) continue;
    sum += marker.position_m;
    count += 1.0;
  }
  if (count == 0.0) return;
  const Eigen::Vector3d centroid = sum / count;
  for (auto& marker : layout.markers) marker.position_m -= centroid;
}

// The rigid fit of the layout's markers (with `calibration_only`: all of them) to one frame.
std::optional<LayoutFit> fit_markers(const SegmentLayout& layout, const Points& points,
                                     bool calibration_only) {
  std::vector<Eigen::Vector3d> from;
  std::vector<Eigen::Vector3d> to;
  for (std::size_t i = 0; i < layout.markers.size() && i < points.size(); ++i) {
    if ((layout.markers[i].calibration_only && !calibration_only) || !points[i]) continue;
    from.push_back(layout.markers[i].position_m);
    to.push_back(*points[i]);
  }
  double rms = 0.0;
  const auto T = fit_rigid_transform(from, to, &rms);
  if (!T) return std::nullopt;
  return LayoutFit{*T, rms, from.size()};
}

// The segment's pose in one frame of the static trial, where calibration-only markers are seen
// too: the rigid fit of every seen marker when they span a frame, else the mean translation of
// the seen markers (the static pose's orientation).
std::optional<LayoutFit> static_pose(const SegmentLayout& layout, const Points& points, bool rigid) {
  if (rigid) return fit_markers(layout, points, true);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::size_t used = 0;
  for (std::size_t i = 0; i < layout.markers.size(); ++i) {
    if (!points[i]) continue;
    sum += *points[i] - layout.markers[i].position_m;
    ++used;
  }
  if (used == 0) return std::nullopt;
  LayoutFit fit;
  fit.T_world_segment.t = sum / static_cast<double>(used);
  fit.markers_used = used;
  double squares = 0.0;
  for (std::size_t i = 0; i < layout.markers.size(); ++i) {
    if (points[i])
      squares += (fit.T_world_segment.apply(layout.markers[i].position_m) - *points[i]).squaredNorm();
  }
  fit.rms_m = std::sqrt(squares / static_cast<double>(used));
  return fit;
}

// One generalised Procrustes pass: every frame fitted, its points mapped into the segment frame
// and averaged. Returns the RMS residual of the fits (over every tracked marker used).
double procrustes_pass(const MarkerSamples& trial, SegmentWork& work, bool update_layout) {
  const std::size_t count = work.layout.markers.size();
  std::vector<Eigen::Vector3d> sums(count, Eigen::Vector3d::Zero());
  std::vector<double> seen(count, 0.0);
  double squares = 0.0;
  double used = 0.0;
  work.T_world_segment.assign(trial.frame_count(), std::nullopt);
  for (std::size_t f = 0; f < trial.frame_count(); ++f) {
    const Points points = frame_points(trial, work, f);
    const auto fit = static_pose(work.layout, points, work.static_rigid);
    if (!fit) continue;
    work.T_world_segment[f] = fit->T_world_segment;
    squares += fit->rms_m * fit->rms_m * static_cast<double>(fit->markers_used);
    used += static_cast<double>(fit->markers_used);
    const RigidTransform T_segment_world = fit->T_world_segment.inverse();
    for (std::size_t i = 0; i < count; ++i) {
      if (!points[i]) continue;
      sums[i] += T_segment_world.apply(*points[i]);
      seen[i] += 1.0;
    }
  }
  if (update_layout) {
    for (std::size_t i = 0; i < count; ++i) {
      if (seen[i] > 0.0) work.layout.markers[i].position_m = sums[i] / seen[i];
    }
    recentre(work.layout);
  }
  return used > 0.0 ? std::sqrt(squares / used) : 0.0;
}

bool markers_span_a_frame(const SegmentLayout& layout, bool calibration_only) {
  std::vector<Eigen::Vector3d> points;
  for (const auto& marker : layout.markers) {
    if (!marker.calibration_only || calibration_only) points.push_back(marker.position_m);
  }
  return points.size() >= 3 && fit_rigid_transform(points, points).has_value();
}

DistanceStatistics distance_statistics(const MarkerSamples& trial, const SegmentWork& work, std::size_t a,
                                       std::size_t b, const ModelOptions& options) {
  DistanceStatistics out;
  out.markers = {work.layout.markers[a].name, work.layout.markers[b].name};
  out.min_m = std::numeric_limits<double>::infinity();
  out.max_m = 0.0;
  double sum = 0.0;
  double squares = 0.0;
  for (std::size_t f = 0; f < trial.frame_count(); ++f) {
    if (!trial.is_valid(f, work.columns[a]) || !trial.is_valid(f, work.columns[b])) continue;
    const double d = (trial.position(f, work.columns[a]) - trial.position(f, work.columns[b])).norm();
    sum += d;
    squares += d * d;
    out.min_m = std::min(out.min_m, d);
    out.max_m = std::max(out.max_m, d);
    ++out.frames;
  }
  if (out.frames == 0) {
    out.min_m = 0.0;
    out.tolerance_m = options.min_tolerance_m;
    return out;
  }
  const double n = static_cast<double>(out.frames);
  out.mean_m = sum / n;
  out.sd_m = std::sqrt(std::max(0.0, squares / n - out.mean_m * out.mean_m));
  out.tolerance_m = std::max(options.sigmas * out.sd_m, options.min_tolerance_m);
  if (options.dynamic)
    out.tolerance_m = std::max({out.tolerance_m, out.max_m - out.mean_m, out.mean_m - out.min_m});
  return out;
}

// A pair that turned during the trial has mean positions closer than its mean distance: the
// layout keeps the mean direction and the mean distance.
void keep_mean_distance(SegmentLayout& layout) {
  if (layout.distances[0].frames == 0) return;
  Eigen::Vector3d& a = layout.markers[0].position_m;
  Eigen::Vector3d& b = layout.markers[1].position_m;
  const Eigen::Vector3d middle = (a + b) / 2.0;
  const Eigen::Vector3d half = (b - a).normalized() * (layout.distances[0].mean_m / 2.0);
  if (!half.allFinite()) return;
  a = middle - half;
  b = middle + half;
}

// The segment frame's origin in the trial's world, averaged over frames: the layout's axes are the
// lab's, so each seen marker's world position less its layout position estimates it.
Eigen::Vector3d mean_origin(const MarkerSamples& trial, const SegmentWork& work) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double count = 0.0;
  for (std::size_t f = 0; f < trial.frame_count(); ++f) {
    for (std::size_t m = 0; m < work.columns.size(); ++m) {
      if (work.layout.markers[m].calibration_only || !trial.is_valid(f, work.columns[m])) continue;
      sum += trial.position(f, work.columns[m]) - work.layout.markers[m].position_m;
      count += 1.0;
    }
  }
  return count > 0.0 ? Eigen::Vector3d(sum / count) : Eigen::Vector3d::Zero();
}

SegmentWork build_segment(const MarkerSet& set, const SegmentDefinition& segment, const MarkerSamples& trial,
                          const std::vector<std::optional<std::size_t>>& columns, const ModelOptions& options,
                          std::vector<MarkerFlag>& flags) {
  SegmentWork work;
  work.layout.name = segment.name;
  work.layout.parent = segment.parent;
  for (const auto& name : segment.markers) {
    const std::size_t index = *set.marker_index(name);
    if (!columns[index]) continue;  // an optional marker the trial lacks
    work.layout.markers.push_back(
        describe_marker(trial, set.markers[index], *columns[index], options, flags));
    work.columns.push_back(*columns[index]);
  }
  recentre(work.layout);
  work.layout.has_pose = markers_span_a_frame(work.layout, false);
  work.static_rigid = markers_span_a_frame(work.layout, true);
  for (int pass = 0; pass < options.procrustes_iterations; ++pass) procrustes_pass(trial, work, true);
  work.layout.static_fit_rms_m = procrustes_pass(trial, work, false);
  work.layout.origin_m = mean_origin(trial, work);
  for (std::size_t a = 0; a < work.layout.markers.size(); ++a) {
    for (std::size_t b = a + 1; b < work.layout.markers.size(); ++b)
      work.layout.distances.push_back(distance_statistics(trial, work, a, b, options));
  }
  if (!work.static_rigid && work.layout.markers.size() == 2) keep_mean_distance(work.layout);
  return work;
}

// The joint's centre in world coordinates in frame `f`, when its points are seen.
std::optional<Eigen::Vector3d> joint_point(const MarkerSamples& trial,
                                           const std::vector<std::size_t>& columns, std::size_t f) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t column : columns) {
    if (!trial.is_valid(f, column)) return std::nullopt;
    sum += trial.position(f, column);
  }
  return sum / static_cast<double>(columns.size());
}

bool joint_points_seen(const JointDefinition& joint, const MarkerSamples& trial) {
  for (const auto& point : joint.points) {
    const auto column = column_of(trial, point);
    if (!column || seen_frames(trial, *column) == 0) return false;
  }
  return true;
}

JointCentre build_joint(const MarkerSet& set, const JointDefinition& joint, const MarkerSamples& trial,
                        const std::vector<SegmentWork>& works) {
  const std::size_t child = *set.segment_index(joint.child);
  const std::size_t parent = *set.segment_index(set.segments[child].parent);
  JointCentre out{joint.name, set.segments[parent].name, joint.child};
  std::vector<std::size_t> columns;
  for (const auto& point : joint.points) {
    const auto column = column_of(trial, point);
    if (!column || seen_frames(trial, *column) == 0)
      throw InputError(trial.source + ": joint '" + joint.name + "' (marker set '" + set.name +
                       "'): point '" + point + "' is " + (column ? "never seen in" : "not in") +
                       " the static trial");
    columns.push_back(*column);
  }
  Eigen::Vector3d in_parent = Eigen::Vector3d::Zero();
  Eigen::Vector3d in_child = Eigen::Vector3d::Zero();
  double frames = 0.0;
  for (std::size_t f = 0; f < trial.frame_count(); ++f) {
    const auto centre = joint_point(trial, columns, f);
    const auto& T_parent = works[parent].T_world_segment[f];
    const auto& T_child = works[child].T_world_segment[f];
    if (!centre || !T_parent || !T_child) continue;
    in_parent += T_parent->inverse().apply(*centre);
    in_child += T_child->inverse().apply(*centre);
    frames += 1.0;
  }
  if (frames == 0.0)
    throw InputError(trial.source + ": joint '" + joint.name +
                     "': no frame of the static trial sees its points and " + "both segments '" + out.parent +
                     "' and '" + out.child + "'");
  out.in_parent_m = in_parent / frames;
  out.in_child_m = in_child / frames;
  return out;
}

}  // namespace

std::vector<std::string> SegmentLayout::tracked_marker_names() const {
  std::vector<std::string> names;
  for (const auto& marker : markers) {
    if (!marker.calibration_only) names.push_back(marker.name);
  }
  return names;
}

const SegmentLayout* SubjectModel::segment(const std::string& name) const {
  for (const auto& layout : segments) {
    if (layout.name == name) return &layout;
  }
  return nullptr;
}

std::size_t SubjectModel::marker_count() const {
  std::size_t count = 0;
  for (const auto& layout : segments) count += layout.markers.size();
  return count;
}

std::optional<LayoutFit> fit_layout(const SegmentLayout& layout, const Points& frame_points) {
  return fit_markers(layout, frame_points, false);
}

SubjectModel build_subject_model(const MarkerSet& set, const MarkerSamples& trial, const std::string& subject,
                                 const ModelOptions& options) {
  SubjectModel model;
  model.subject = subject;
  model.marker_set = set.name;
  model.trial_file = trial.source;
  model.frames = trial.frame_count();
  model.rate_hz = trial.rate_hz;
  model.options = options;
  model.sticks = set.sticks;
  if (model.frames == 0) throw InputError(trial.source + ": the " + trial_kind(options) + " has no frames");
  const auto columns = match_markers(set, trial, options, model.flags);
  model.ignored_points = ignored_points(set, trial);
  std::vector<SegmentWork> works;
  for (const auto& segment : set.segments) {
    works.push_back(build_segment(set, segment, trial, columns, options, model.flags));
    model.segments.push_back(works.back().layout);
  }
  for (const auto& joint : set.joints) {
    if (options.dynamic && !joint_points_seen(joint, trial)) {
      model.flags.push_back(
          {MarkerFlag::Kind::kAbsent, joint.name, "joint left out: the labelled trial lacks its points"});
      continue;
    }
    model.joints.push_back(build_joint(set, joint, trial, works));
  }
  return model;
}

namespace {

std::string entry(const char* list, std::size_t index) {
  return std::string(list) + "[" + std::to_string(index) + "]";
}

std::optional<MarkerSetProblem> check_layout(const SegmentLayout& segment, const std::string& at,
                                             std::map<std::string, std::string>& owner) {
  for (std::size_t m = 0; m < segment.markers.size(); ++m) {
    const ModelMarker& marker = segment.markers[m];
    const std::string key = at + "." + entry("markers", m);
    if (marker.name.empty()) return MarkerSetProblem{key, "a marker needs a name"};
    if (!marker.position_m.allFinite())
      return MarkerSetProblem{key + ".position_m", "expected finite numbers"};
    const auto [where, inserted] = owner.emplace(marker.name, segment.name);
    if (!inserted)
      return MarkerSetProblem{key,
                              "marker '" + marker.name + "' is already in segment '" + where->second + "'"};
  }
  for (std::size_t d = 0; d < segment.distances.size(); ++d) {
    const DistanceStatistics& distance = segment.distances[d];
    const std::string key = at + "." + entry("distances", d);
    for (const auto& name : distance.markers) {
      if (owner.contains(name) && owner.at(name) == segment.name) continue;
      return MarkerSetProblem{key + ".markers",
                              "marker '" + name + "' is not in segment '" + segment.name + "'"};
    }
    if (!(distance.tolerance_m > 0.0) || !std::isfinite(distance.tolerance_m) ||
        !std::isfinite(distance.mean_m))
      return MarkerSetProblem{key, "expected a finite mean and a positive tolerance"};
  }
  return std::nullopt;
}

}  // namespace

std::optional<MarkerSetProblem> find_subject_model_problem(const SubjectModel& model) {
  // The segment tree has the marker set's rules.
  MarkerSet tree;
  for (const auto& segment : model.segments) tree.segments.push_back({segment.name, segment.parent, {}});
  if (auto problem = find_segment_tree_problem(tree.segments)) return problem;
  std::map<std::string, std::string> owner;  // marker -> segment
  for (std::size_t s = 0; s < model.segments.size(); ++s) {
    if (auto problem = check_layout(model.segments[s], entry("segments", s), owner)) return problem;
  }
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const JointCentre& joint = model.joints[j];
    const auto child = tree.segment_index(joint.child);
    if (!child || tree.segments[*child].parent != joint.parent)
      return MarkerSetProblem{entry("joints", j), "joint '" + joint.name + "': '" + joint.child +
                                                      "' is not a segment whose parent is '" + joint.parent +
                                                      "'"};
    if (!joint.in_parent_m.allFinite() || !joint.in_child_m.allFinite())
      return MarkerSetProblem{entry("joints", j), "expected finite numbers"};
  }
  return std::nullopt;
}

MarkerSamples slice_frames(const MarkerSamples& samples, std::size_t first, std::size_t last) {
  MarkerSamples out = samples;
  last = std::min(last, samples.frame_count());
  first = std::min(first, last);
  const auto begin = static_cast<std::ptrdiff_t>(first * samples.point_count());
  const auto end = static_cast<std::ptrdiff_t>(last * samples.point_count());
  out.positions.assign(samples.positions.begin() + begin, samples.positions.begin() + end);
  out.valid.assign(samples.valid.begin() + begin, samples.valid.begin() + end);
  return out;
}

}  // namespace panoptes::labelling
