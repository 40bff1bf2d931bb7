// SPDX-License-Identifier: Apache-2.0
#include "panoptes/labelling/labeller.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <unordered_map>
#include <utility>

#include <Eigen/Geometry>

#include "panoptes/estimator/assignment.h"

namespace panoptes::labelling {

namespace {

using Points = std::vector<std::optional<Eigen::Vector3d>>;

struct MarkerState {
  std::optional<std::uint64_t> track;
  std::optional<Eigen::Vector3d> last;   // seen or predicted, the latest
  std::optional<std::size_t> point;      // this instant's point
  std::optional<Eigen::Vector3d> moved;  // since the previous instant, when seen in both
  double residual_m = 0.0;               // running mean of its distance from the segment's rigid fit
  std::optional<double> absent_since_s;  // live: its track missing since (keep_absent_s)
  std::optional<double> back_at_s;       // live: when its track came back after a long absence
};

// Live: a named track back after more than this long out of the estimator's output (coasting
// through an occlusion) may have been fed by something else meanwhile: a false blob, a neighbour.
constexpr double kLongAbsenceS = 0.1;

struct SegmentState {
  std::vector<MarkerState> markers;
  std::vector<std::size_t> tracked;  // markers that are not calibration-only
  std::vector<std::size_t> children;
  std::optional<std::size_t> parent;
  const JointCentre* joint = nullptr;      // with this segment as child
  Eigen::MatrixXd mean;                    // marker-pair distances, metres
  Eigen::MatrixXd tolerance;               // with the motion allowance
  std::optional<RigidTransform> pose;      // this instant
  std::optional<RigidTransform> previous;  // the previous instant's (rigid) pose
  bool loose = false;                      // the pose is a translation only
  bool soft = false;                       // LabellerOptions::soft_segments: its fit predicts loosely
};

struct Subject {
  SubjectModel model;
  std::vector<SegmentState> segments;
  std::size_t root = 0;
  std::vector<std::size_t> order;   // breadth first from the root
  std::optional<double> revised_s;  // live: the last revise() search
  int instants_since_revision = 0;  // offline
};

// One segment's tentative assignment: (marker, point) pairs and the pose they give.
struct Found {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  RigidTransform pose;
  bool loose = false;
  double cost = 0.0;
};

// A tentative labelling of a subject: per segment what was found.
struct Hypothesis {
  std::vector<std::optional<Found>> segments;
  std::size_t markers = 0;
  double cost = 0.0;
};

std::size_t marker_in(const SegmentLayout& layout, const std::string& name) {
  for (std::size_t m = 0; m < layout.markers.size(); ++m) {
    if (layout.markers[m].name == name) return m;
  }
  return layout.markers.size();
}

bool is_soft(const LabellerOptions& options, const std::string& segment) {
  return std::find(options.soft_segments.begin(), options.soft_segments.end(), segment) !=
         options.soft_segments.end();
}

}  // namespace

double moving_tolerance(const LabellerOptions& options, const std::string& segment,
                        const DistanceStatistics& distance) {
  const double fraction = is_soft(options, segment) ? options.soft_fraction : options.allowance_fraction;
  return distance.tolerance_m + options.allowance_m + fraction * distance.mean_m;
}

namespace {

SegmentState make_segment(const SegmentLayout& layout, const LabellerOptions& options) {
  SegmentState s;
  const std::size_t n = layout.markers.size();
  s.markers.resize(n);
  for (std::size_t m = 0; m < n; ++m) {
    if (!layout.markers[m].calibration_only) s.tracked.push_back(m);
  }
  s.mean = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  s.tolerance = Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n), -1.0);
  s.soft = is_soft(options, layout.name);
  for (const auto& d : layout.distances) {
    const auto a = static_cast<Eigen::Index>(marker_in(layout, d.markers[0]));
    const auto b = static_cast<Eigen::Index>(marker_in(layout, d.markers[1]));
    if (a >= static_cast<Eigen::Index>(n) || b >= static_cast<Eigen::Index>(n)) continue;
    s.mean(a, b) = s.mean(b, a) = d.mean_m;
    s.tolerance(a, b) = s.tolerance(b, a) = moving_tolerance(options, layout.name, d);
  }
  return s;
}

Subject make_subject(SubjectModel model, const LabellerOptions& options) {
  Subject subject;
  subject.model = std::move(model);
  const auto& segments = subject.model.segments;
  for (const auto& layout : segments) subject.segments.push_back(make_segment(layout, options));
  for (std::size_t s = 0; s < segments.size(); ++s) {
    if (segments[s].parent.empty()) {
      subject.root = s;
      continue;
    }
    for (std::size_t p = 0; p < segments.size(); ++p) {
      if (segments[p].name != segments[s].parent) continue;
      subject.segments[s].parent = p;
      subject.segments[p].children.push_back(s);
    }
    for (const auto& joint : subject.model.joints) {
      if (joint.child == segments[s].name) subject.segments[s].joint = &joint;
    }
  }
  subject.order.push_back(subject.root);
  for (std::size_t i = 0; i < subject.order.size(); ++i) {
    for (std::size_t child : subject.segments[subject.order[i]].children) subject.order.push_back(child);
  }
  return subject;
}

bool distance_fits(const SegmentState& s, std::size_t a, std::size_t b, const Eigen::Vector3d& pa,
                   const Eigen::Vector3d& pb) {
  const double tolerance = s.tolerance(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
  if (tolerance < 0.0) return true;  // no statistics: no constraint
  return std::abs((pa - pb).norm() - s.mean(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b))) <=
         tolerance;
}

// The exchange of two of `named`'s points that fits the layout best below `below` (RMS, metres) and
// that `accept` takes (the fit's pose), with its fit.
struct Exchange {
  std::size_t a, b;
  LayoutFit fit;
};
template <typename Accept>
std::optional<Exchange> best_exchange(const SegmentLayout& layout, Points seen,
                                      const std::vector<std::size_t>& named, double below, Accept accept) {
  std::optional<Exchange> best;
  for (std::size_t i = 0; i < named.size(); ++i) {
    for (std::size_t j = i + 1; j < named.size(); ++j) {
      std::swap(seen[named[i]], seen[named[j]]);
      auto fit = fit_layout(layout, seen);
      std::swap(seen[named[i]], seen[named[j]]);
      if (!fit || fit->rms_m >= below || (best && fit->rms_m >= best->fit.rms_m) ||
          !accept(fit->T_world_segment))
        continue;
      best = Exchange{named[i], named[j], std::move(*fit)};
    }
  }
  return best;
}

// The pose of a segment from its markers seen now: a rigid fit from three, else the translation
// that puts the seen markers' layout on them with `rotation` (the parent's, or the lab's).
std::optional<std::pair<RigidTransform, bool>> segment_pose(const SegmentLayout& layout, const Points& seen,
                                                            const Eigen::Quaterniond& rotation) {
  if (layout.has_pose) {
    const auto fit = fit_layout(layout, seen);
    if (fit) return std::pair{fit->T_world_segment, false};
  }
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double count = 0.0;
  for (std::size_t m = 0; m < seen.size(); ++m) {
    if (!seen[m]) continue;
    sum += *seen[m] - rotation * layout.markers[m].position_m;
    count += 1.0;
  }
  if (count == 0.0) return std::nullopt;
  return std::pair{RigidTransform{rotation, sum / count}, true};
}

}  // namespace

struct Labeller::State {
  std::uint64_t untangled = 0;  // pairs of names untangle() moved
  std::uint64_t released = 0;   // names release() took from their tracks
  LabellerOptions options;
  std::vector<Subject> subjects;
  std::unordered_map<std::uint64_t, std::pair<std::size_t, std::pair<std::size_t, std::size_t>>> labels;
  const std::vector<TrackPoint>* points = nullptr;
  std::optional<double> now_s;  // this instant's time, live (keep_absent_s); none offline
  std::vector<char> claimed;
  std::vector<char> young;                      // per point: too new to be acquired
  std::unordered_map<std::uint64_t, int> ages;  // instants each track has been seen

  const Eigen::Vector3d& at(std::size_t point) const { return (*points)[point].position_m; }

  void keep(const std::unordered_map<std::uint64_t, std::size_t>& by_track);
  void fit_poses(Subject& subject);
  void predict(Subject& subject);
  std::optional<Eigen::Vector3d> with_parent(const Subject& subject, std::size_t s, std::size_t m,
                                             const std::optional<Eigen::Vector3d>& last) const;
  void recover();
  bool pair_keeps_handedness(const Subject& subject, std::size_t s, std::size_t m, std::size_t p) const;
  std::optional<double> recover_cost(const Subject& subject, std::size_t s, std::size_t m,
                                     std::size_t p) const;
  double shell_width(const Subject& subject, std::size_t parent, double d) const;
  std::optional<double> parent_shell(const Subject& subject, std::size_t s, std::size_t m,
                                     std::size_t p) const;
  void acquire(std::size_t subject_index);
  std::optional<Hypothesis> best_hypothesis(const Subject& subject, std::size_t s,
                                            const std::optional<RigidTransform>& parent_pose,
                                            const Points& parent_seen);
  void replace(std::size_t subject_index, const std::vector<char>& subtree, const Hypothesis& h);
  void revise(std::size_t subject_index);
  std::optional<Found> search_segment(const Subject& subject, std::size_t s,
                                      const std::optional<RigidTransform>& parent_pose,
                                      const Points& parent_seen) const;
  std::optional<double> child_marker_cost(const Subject& subject, std::size_t s, std::size_t m,
                                          const RigidTransform& parent_pose, const Points& parent_seen,
                                          std::size_t p) const;
  Points seen_now(const SegmentState& segment) const;
  bool keeps_handedness(const Subject& subject, std::size_t s, std::size_t a, std::size_t b,
                        const Points& parent_seen, std::size_t i, std::size_t j) const;
  Points seen_of(const Subject& subject, std::size_t s, const Hypothesis& h) const;
  std::optional<Found> search_pair(const Subject& subject, std::size_t s, const RigidTransform& parent_pose,
                                   const Points& parent_seen) const;
  std::optional<Found> search_rigid(const Subject& subject, std::size_t s,
                                    const std::optional<RigidTransform>& parent_pose,
                                    const std::vector<std::size_t>& candidates,
                                    std::vector<Found>* all = nullptr) const;
  void search_anchors(const Subject& subject, std::size_t s, const std::optional<RigidTransform>& parent_pose,
                      const std::vector<std::size_t>& candidates, const std::array<std::size_t, 3>& anchors,
                      std::vector<Found>* all, std::optional<Found>& best) const;
  void add_extras(const Subject& subject, std::size_t s, Found& found) const;
  void grow(const Subject& subject, std::size_t s, const RigidTransform& pose, Hypothesis& h);
  void commit(std::size_t subject_index, std::size_t s, const Found& found);
  void untangle(std::size_t subject_index);
  void untangle_pair(std::size_t subject_index, std::size_t s);
  void untangle_mirrored(std::size_t subject_index, std::size_t s, const std::vector<std::size_t>& named,
                         const RigidTransform& parent_pose);
  void exchange(std::size_t subject_index, std::size_t s, std::size_t m1, std::size_t m2);
  void release_misfits(std::size_t subject_index, std::size_t s, const std::vector<std::size_t>& named);
  void release(std::size_t subject_index, std::size_t s, std::size_t m);
  std::vector<std::size_t> candidates_near(const Subject& subject, std::size_t s,
                                           const std::optional<RigidTransform>& parent_pose) const;
  bool tree_accepts(const Subject& subject, std::size_t s, const RigidTransform& pose,
                    const std::optional<RigidTransform>& parent_pose, double& cost) const;
};

namespace {

// The origin of segment `s` in the static pose relative to its parent's, and how far from it the
// search for `s` reaches (its markers included).
std::pair<Eigen::Vector3d, double> static_offset(const SubjectModel& model, std::size_t s, std::size_t parent,
                                                 const LabellerOptions& options) {
  const Eigen::Vector3d offset = model.segments[s].origin_m - model.segments[parent].origin_m;
  double radius = 0.0;
  for (const auto& marker : model.segments[s].markers) radius = std::max(radius, marker.position_m.norm());
  return {offset, options.reach_m + options.reach_fraction * offset.norm() + radius};
}

}  // namespace

void Labeller::State::keep(const std::unordered_map<std::uint64_t, std::size_t>& by_track) {
  for (std::size_t i = 0; i < subjects.size(); ++i) {
    for (auto& segment : subjects[i].segments) {
      for (auto& marker : segment.markers) {
        marker.point.reset();
        marker.moved.reset();
        if (!marker.track) continue;
        const auto found = by_track.find(*marker.track);
        if (found == by_track.end()) {
          // Live, briefly missing: the name stays on its track (predicted like a waiting one).
          if (now_s) {
            if (!marker.absent_since_s) marker.absent_since_s = *now_s;
            if (*now_s - *marker.absent_since_s <= options.keep_absent_s) continue;
          }
          labels.erase(*marker.track);  // the track ended: the name waits
          marker.track.reset();
          marker.absent_since_s.reset();
          continue;
        }
        if (now_s && marker.absent_since_s && *now_s - *marker.absent_since_s > kLongAbsenceS)
          marker.back_at_s = *now_s;
        marker.absent_since_s.reset();
        marker.point = found->second;
        claimed[found->second] = 1;
        if (marker.last) marker.moved = at(found->second) - *marker.last;
        marker.last = at(found->second);
      }
    }
  }
}

void Labeller::State::fit_poses(Subject& subject) {
  for (std::size_t s : subject.order) {
    SegmentState& segment = subject.segments[s];
    Points seen(segment.markers.size());
    for (std::size_t m = 0; m < seen.size(); ++m) {
      if (segment.markers[m].point) seen[m] = at(*segment.markers[m].point);
    }
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
    if (segment.parent && subject.segments[*segment.parent].pose)
      rotation = subject.segments[*segment.parent].pose->q;
    const auto pose = segment_pose(subject.model.segments[s], seen, rotation);
    segment.pose.reset();
    if (!pose) continue;
    segment.pose = pose->first;
    segment.loose = pose->second;
  }
}

// Waiting markers follow their segment: the rigid fit's prediction, else their last position moved
// as the segment's seen markers moved; a segment with none seen follows its parent (below).
void Labeller::State::predict(Subject& subject) {
  for (std::size_t s = 0; s < subject.segments.size(); ++s) {
    SegmentState& segment = subject.segments[s];
    Eigen::Vector3d moved = Eigen::Vector3d::Zero();
    double count = 0.0;
    for (const auto& marker : segment.markers) {
      if (!marker.moved) continue;
      moved += *marker.moved;
      count += 1.0;
    }
    if (count > 0.0) moved /= count;
    for (std::size_t m : segment.tracked) {
      MarkerState& marker = segment.markers[m];
      const Eigen::Vector3d& in_segment = subject.model.segments[s].markers[m].position_m;
      if (marker.point && segment.pose && !segment.loose) {
        const double residual = (segment.pose->apply(in_segment) - at(*marker.point)).norm();
        marker.residual_m += options.residual_rate * (residual - marker.residual_m);
      }
      if (marker.point) continue;
      // A loose pose is a translation only: a marker with a place follows its seen neighbours'
      // motion, one never placed takes its layout place.
      const bool follows_seen = segment.loose && marker.last && count > 0.0;
      if (segment.pose && !follows_seen) {
        marker.last = segment.pose->apply(in_segment);
      } else if (follows_seen) {
        marker.last = *marker.last + moved;
      } else {
        marker.last = with_parent(subject, s, m, marker.last);
      }
    }
  }
}

// A waiting marker of a segment with no marker seen (Gait2392's upper arm with Bicep and Elbow both
// hidden): its last position carried by its parent's motion since the previous instant, or, never
// seen, where the parent's pose and the static posture put it. Left frozen, a swinging arm's
// prediction drifted 50-90 mm from the marker and its name came back 10 frames late.
std::optional<Eigen::Vector3d> Labeller::State::with_parent(
    const Subject& subject, std::size_t s, std::size_t m, const std::optional<Eigen::Vector3d>& last) const {
  const auto parent = subject.segments[s].parent;
  if (!parent) return last;
  const SegmentState& parent_state = subject.segments[*parent];
  if (!parent_state.pose || parent_state.loose) return last;
  if (last) {
    if (!parent_state.previous) return last;
    return parent_state.pose->apply(parent_state.previous->inverse().apply(*last));
  }
  const auto [offset, reach] = static_offset(subject.model, s, *parent, options);
  return parent_state.pose->apply(offset + subject.model.segments[s].markers[m].position_m);
}

// The half-width of the shell at static distance d about a marker of `parent`: wider about a soft
// parent, whose markers move against each other as much (Rajagopal's shoulders: 283 mm apart
// standing, 344 mm walking; its upper arm's Biceps missed the narrow shell by 0-11 % for 107 frames).
double Labeller::State::shell_width(const Subject& subject, std::size_t parent, double d) const {
  const double fraction = subject.segments[parent].soft ? options.soft_fraction : options.shell_fraction;
  return options.shell_m + fraction * d;
}

// Point p as marker m of segment s against the shell about the parent's seen marker nearest to m in
// the static pose (see child_marker_cost): the error over the shell's width, or nullopt.
std::optional<double> Labeller::State::parent_shell(const Subject& subject, std::size_t s, std::size_t m,
                                                    std::size_t p) const {
  const auto parent = subject.segments[s].parent;
  if (!parent) return std::nullopt;
  const auto& model = subject.model;
  const Eigen::Vector3d marker_static = model.segments[s].origin_m + model.segments[s].markers[m].position_m;
  std::optional<double> error;
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < subject.segments[*parent].markers.size(); ++k) {
    const auto& seen = subject.segments[*parent].markers[k].point;
    if (!seen) continue;
    const double d =
        (marker_static - (model.segments[*parent].origin_m + model.segments[*parent].markers[k].position_m))
            .norm();
    if (d >= nearest) continue;
    nearest = d;
    error = ((at(p) - at(*seen)).norm() - d) / shell_width(subject, *parent, d);
  }
  return error;
}

// The cost (< 1) of giving waiting marker m of segment s to point p: its prediction's distance over
// the gate; also the distances to its segment's seen markers over their tolerances and to its
// parent's nearest marker over the shell (all within, a track not too young; >= 2 of them, with a
// rigid fit >= 2 in the segment and the shell), the lower of the two.
std::optional<double> Labeller::State::recover_cost(const Subject& subject, std::size_t s, std::size_t m,
                                                    std::size_t p) const {
  const SegmentState& segment = subject.segments[s];
  std::optional<double> cost;
  const bool rigid = segment.pose && !segment.loose && !segment.soft;
  const double gate =
      rigid ? options.gate_m + options.residual_gate * segment.markers[m].residual_m : options.loose_gate_m;
  if (segment.markers[m].last) {
    const double d2 = (at(p) - *segment.markers[m].last).squaredNorm() / (gate * gate);
    if (d2 < 1.0) cost = d2;
  }
  if (young[p] != 0) return cost;
  double sum = 0.0;
  double seen = 0.0;
  for (std::size_t k = 0; k < segment.markers.size(); ++k) {
    const auto& other = segment.markers[k].point;
    const double tolerance = segment.tolerance(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(k));
    if (k == m || !other || tolerance <= 0.0) continue;
    const double error = ((at(p) - at(*other)).norm() -
                          segment.mean(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(k))) /
                         tolerance;
    if (std::abs(error) > 1.0) return cost;
    sum += error * error;
    seen += 1.0;
  }
  const double in_segment = seen;
  if (const auto shell = parent_shell(subject, s, m, p)) {
    if (std::abs(*shell) > 1.0) return cost;
    sum += *shell * *shell;
    seen += 1.0;
  }
  // A rigid segment's prediction can miss while the distances hold (Rajagopal's thigh: its layout
  // fits a walk to 8.9 mm, a prediction from three markers missed by 55-72 mm for 13 frames); its
  // distances then need two seen markers and the shell, which leave one place (not a circle).
  if (seen < 2.0 || (rigid && (in_segment < 2.0 || seen < 3.0))) return cost;
  return std::min(cost.value_or(1.0), sum / seen);
}

// A waiting marker of a two-marker segment whose other marker is seen: point p keeps the pair's
// handedness with the parent (keeps_handedness), so a name does not return to its neighbour.
bool Labeller::State::pair_keeps_handedness(const Subject& subject, std::size_t s, std::size_t m,
                                            std::size_t p) const {
  const SegmentState& segment = subject.segments[s];
  if (segment.tracked.size() != 2 || !segment.parent) return true;
  const std::size_t other = segment.tracked[0] == m ? segment.tracked[1] : segment.tracked[0];
  const auto& other_point = segment.markers[other].point;
  if (!other_point) return true;
  const Points parent_seen = seen_now(subject.segments[*segment.parent]);
  return m == segment.tracked[0] ? keeps_handedness(subject, s, m, other, parent_seen, p, *other_point)
                                 : keeps_handedness(subject, s, other, m, parent_seen, *other_point, p);
}

// New tracks take waiting names: gated on the predictions, assigned jointly (assign_gated).
void Labeller::State::recover() {
  struct Row {
    std::size_t subject, segment, marker;
  };
  std::vector<Row> rows;
  std::vector<estimator::GatedPair> pairs;
  for (std::size_t i = 0; i < subjects.size(); ++i) {
    for (std::size_t s = 0; s < subjects[i].segments.size(); ++s) {
      const SegmentState& segment = subjects[i].segments[s];
      for (std::size_t m : segment.tracked) {
        if (segment.markers[m].point) continue;
        for (std::size_t p = 0; p < claimed.size(); ++p) {
          if (claimed[p] != 0) continue;
          if (!pair_keeps_handedness(subjects[i], s, m, p)) continue;
          if (const auto cost = recover_cost(subjects[i], s, m, p)) pairs.push_back({rows.size(), p, *cost});
        }
        rows.push_back({i, s, m});
      }
    }
  }
  for (const auto& [row, p] : estimator::assign_gated(pairs, 0.5)) {
    Found found;
    found.pairs.emplace_back(rows[row].marker, p);
    commit(rows[row].subject, rows[row].segment, found);
  }
}

// LabellerOptions::untangle_rms_m: a rigid segment's named points refitted with each pair exchanged;
// an exchange that fits far better moves the two names (and what their markers learned stays with
// the markers). Costs a fit per pair only when a segment fits poorly.
void Labeller::State::untangle(std::size_t subject_index) {
  Subject& subject = subjects[subject_index];
  for (std::size_t s : subject.order) {
    SegmentState& segment = subject.segments[s];
    const SegmentLayout& layout = subject.model.segments[s];
    if (!layout.has_pose && segment.tracked.size() == 2) {
      untangle_pair(subject_index, s);
      continue;
    }
    if (!segment.pose || segment.loose || segment.soft || !layout.has_pose) continue;
    Points seen = seen_now(segment);
    std::vector<std::size_t> named;
    for (std::size_t m : segment.tracked) {
      if (seen[m]) named.push_back(m);
    }
    if (named.size() < 3) continue;
    // Turned further from its parent than acquisition allows (tree_accepts): the names fit the
    // layout mirrored (a foot's medial and lateral markers exchanged fit it turned upside down).
    if (const auto parent = segment.parent) {
      const SegmentState& p = subject.segments[*parent];
      if (p.pose && !p.loose &&
          p.pose->q.angularDistance(segment.pose->q) > options.max_relative_rotation_rad) {
        untangle_mirrored(subject_index, s, named, *p.pose);
        continue;
      }
    }
    // The pose is fit_poses()'s rigid fit of these points: its RMS without a second fit.
    double sum = 0.0;
    for (std::size_t m : named)
      sum += (segment.pose->apply(layout.markers[m].position_m) - *seen[m]).squaredNorm();
    const double rms_now = std::sqrt(sum / static_cast<double>(named.size()));
    if (rms_now <= options.untangle_rms_m) continue;
    const auto best = best_exchange(layout, seen, named, options.untangle_ratio * rms_now,
                                    [](const RigidTransform&) { return true; });
    if (!best) {
      if (rms_now > options.release_rms_m) release_misfits(subject_index, s, named);
      continue;
    }
    exchange(subject_index, s, best->a, best->b);
    const auto pose = segment_pose(layout, seen_now(segment), segment.pose->q);
    if (pose) {
      segment.pose = pose->first;
      segment.loose = pose->second;
    }
  }
}

// A rigid segment whose named tracks fit its layout only mirrored (turned from its parent further
// than max_relative_rotation_rad). When the tracker exchanged two of its tracks (seen under load: a
// shank's Upper and Rear tracks exchanged after a 108 ms stall of every camera; its near-isosceles
// triangle fits mirrored within 3 mm), exchanging the two names back fits the layout turned as the
// parent allows: the names follow the markers. Otherwise every name is released and waits where the
// parent's pose puts it in the static posture, not on the tracks that fit mirrored (recover() would
// otherwise give them straight back).
void Labeller::State::untangle_mirrored(std::size_t subject_index, std::size_t s,
                                        const std::vector<std::size_t>& named,
                                        const RigidTransform& parent_pose) {
  Subject& subject = subjects[subject_index];
  SegmentState& segment = subject.segments[s];
  const SegmentLayout& layout = subject.model.segments[s];
  // Below untangle_rms_m, not a ratio: the mirrored fit is already good.
  const auto best = best_exchange(
      layout, seen_now(segment), named, options.untangle_rms_m, [&](const RigidTransform& pose) {
        return parent_pose.q.angularDistance(pose.q) <= options.max_relative_rotation_rad;
      });
  if (best) {
    exchange(subject_index, s, best->a, best->b);
    segment.pose = best->fit.T_world_segment;
    segment.loose = false;
    return;
  }
  for (std::size_t m : named) {
    release(subject_index, s, m);
    segment.markers[m].last = with_parent(subject, s, m, std::nullopt);
  }
  segment.pose.reset();
}

// Two named markers of segment s exchange their tracks (and what they learned stays with the
// markers).
void Labeller::State::exchange(std::size_t subject_index, std::size_t s, std::size_t m1, std::size_t m2) {
  ++untangled;
  MarkerState& a = subjects[subject_index].segments[s].markers[m1];
  MarkerState& b = subjects[subject_index].segments[s].markers[m2];
  std::swap(a.track, b.track);
  std::swap(a.point, b.point);
  std::swap(a.last, b.last);
  std::swap(a.moved, b.moved);
  labels[*a.track] = {subject_index, {s, m1}};
  labels[*b.track] = {subject_index, {s, m2}};
}

// A two-marker segment (no rigid fit; Gait2392's upper arm, Bicep and Elbow) whose two named
// tracks lost the static pose's handedness with the parent's two nearest markers, and would keep it
// exchanged: the tracker exchanged them, the names follow the markers.
void Labeller::State::untangle_pair(std::size_t subject_index, std::size_t s) {
  const Subject& subject = subjects[subject_index];
  const SegmentState& segment = subject.segments[s];
  if (!segment.parent) return;
  const std::size_t a = segment.tracked[0];
  const std::size_t b = segment.tracked[1];
  const auto& pa = segment.markers[a].point;
  const auto& pb = segment.markers[b].point;
  if (!pa || !pb) return;
  // Two tracks that are not the pair's distance apart are not the pair exchanged (seen under load:
  // a wrist marker's track coasting through its occlusion came back 3 mm from the other wrist
  // marker after 93 ms, too soon to count as a long absence, and an exchange named the seen marker
  // after the hidden one for the rest of the walk). The tracker ends the duplicate; nothing moves.
  if (!distance_fits(segment, a, b, at(*pa), at(*pb))) return;
  const Points parent_seen = seen_now(subject.segments[*segment.parent]);
  if (keeps_handedness(subject, s, a, b, parent_seen, *pa, *pb) ||
      !keeps_handedness(subject, s, a, b, parent_seen, *pb, *pa))
    return;
  // One of the two just came back from a long absence and the other stayed: the one that came back
  // is astray (seen: a wrist marker hidden for 0.6 s, its coasting track back on the far side of the
  // other wrist marker, which the exchange then named after the hidden one), not an exchange.
  const auto back = [&](std::size_t m) {
    const auto& at_s = segment.markers[m].back_at_s;
    return now_s && at_s && *now_s - *at_s <= options.keep_absent_s;
  };
  if (back(a) != back(b)) {
    release(subject_index, s, back(a) ? a : b);
    return;
  }
  exchange(subject_index, s, a, b);
}

// A named marker's track leaves it: the name waits (recover(), acquire() and revise() may give it
// to another track, this one included).
void Labeller::State::release(std::size_t subject_index, std::size_t s, std::size_t m) {
  MarkerState& marker = subjects[subject_index].segments[s].markers[m];
  if (marker.point) claimed[*marker.point] = 0;
  if (marker.track) labels.erase(*marker.track);
  marker.track.reset();
  marker.point.reset();
  marker.moved.reset();
  marker.absent_since_s.reset();
  marker.back_at_s.reset();
  ++released;
}

// LabellerOptions::release_rms_m: a rigid segment that no exchange of two names fits (the tracker
// moved three tracks round, or one to another segment's marker). The one name whose track leaving
// makes the rest fit within untangle_rms_m is released (the worst such); when none does, every name
// of the segment and its pose, so that it is searched afresh from its parent's pose.
void Labeller::State::release_misfits(std::size_t subject_index, std::size_t s,
                                      const std::vector<std::size_t>& named) {
  SegmentState& segment = subjects[subject_index].segments[s];
  const SegmentLayout& layout = subjects[subject_index].model.segments[s];
  Points seen = seen_now(segment);
  std::optional<std::size_t> outlier;
  std::optional<LayoutFit> outlier_fit;
  if (named.size() > 3) {
    for (std::size_t m : named) {
      auto point = std::exchange(seen[m], std::nullopt);
      auto fit = fit_layout(layout, seen);
      seen[m] = point;
      if (fit && fit->rms_m <= options.untangle_rms_m && (!outlier_fit || fit->rms_m < outlier_fit->rms_m)) {
        outlier = m;
        outlier_fit = std::move(fit);
      }
    }
  }
  if (outlier) {
    release(subject_index, s, *outlier);
    segment.pose = outlier_fit->T_world_segment;
    segment.loose = false;
    return;
  }
  for (std::size_t m : named) {
    release(subject_index, s, m);
    // Waiting where the previous instant's pose put it, not where the wrong track is now.
    if (segment.previous) segment.markers[m].last = segment.previous->apply(layout.markers[m].position_m);
  }
  segment.pose.reset();
  segment.loose = false;
}

void Labeller::State::commit(std::size_t subject_index, std::size_t s, const Found& found) {
  SegmentState& segment = subjects[subject_index].segments[s];
  for (const auto& [m, p] : found.pairs) {
    MarkerState& marker = segment.markers[m];
    // A name kept on a missing track (keep_absent_s) moves to the new one.
    if (marker.track && *marker.track != (*points)[p].track) labels.erase(*marker.track);
    marker.absent_since_s.reset();
    marker.back_at_s.reset();
    marker.track = (*points)[p].track;
    marker.point = p;
    marker.last = at(p);
    claimed[p] = 1;
    labels[(*points)[p].track] = {subject_index, {s, m}};
  }
}

std::vector<std::size_t> Labeller::State::candidates_near(
    const Subject& subject, std::size_t s, const std::optional<RigidTransform>& parent_pose) const {
  std::vector<std::size_t> out;
  const auto parent = subject.segments[s].parent;
  for (std::size_t p = 0; p < claimed.size(); ++p) {
    if (claimed[p] != 0 || young[p] != 0) continue;
    if (parent_pose && parent) {
      const auto [offset, reach] = static_offset(subject.model, s, *parent, options);
      if ((at(p) - (parent_pose->t + parent_pose->q * offset)).norm() > reach) continue;
    }
    out.push_back(p);
  }
  return out;
}

// The tree's constraints on a child's pose: not turned over against its parent, its joint centre
// where the parent's pose puts it, else its origin within reach of the static offset.
bool Labeller::State::tree_accepts(const Subject& subject, std::size_t s, const RigidTransform& pose,
                                   const std::optional<RigidTransform>& parent_pose, double& cost) const {
  const auto& segment = subject.segments[s];
  if (!parent_pose || !segment.parent) return true;
  if (parent_pose->q.angularDistance(pose.q) > options.max_relative_rotation_rad) return false;
  if (segment.joint != nullptr) {
    const double error =
        (parent_pose->apply(segment.joint->in_parent_m) - pose.apply(segment.joint->in_child_m)).norm();
    cost += error;
    return error <= options.joint_gate_m;
  }
  const auto [offset, reach] = static_offset(subject.model, s, *segment.parent, options);
  const double error = (pose.t - (parent_pose->t + parent_pose->q * offset)).norm();
  cost += error;
  return error <= reach;
}

// Segments with a pose: every choice of three anchor markers (a hidden one leaves the others),
// until one finds them all; see search_anchors.
std::optional<Found> Labeller::State::search_rigid(const Subject& subject, std::size_t s,
                                                   const std::optional<RigidTransform>& parent_pose,
                                                   const std::vector<std::size_t>& candidates,
                                                   std::vector<Found>* all) const {
  const auto& tracked = subject.segments[s].tracked;
  std::optional<Found> best;
  for (std::size_t a = 0; a < tracked.size(); ++a) {
    for (std::size_t b = a + 1; b < tracked.size(); ++b) {
      for (std::size_t c = b + 1; c < tracked.size(); ++c) {
        search_anchors(subject, s, parent_pose, candidates, {tracked[a], tracked[b], tracked[c]}, all, best);
        if (all != nullptr || (best && best->pairs.size() == tracked.size())) return best;
      }
    }
  }
  return best;
}

// Ordered candidate triples for three anchor markers whose distances fit, the layout fitted, the
// tree's constraints checked, the other markers taken near their prediction; the best kept.
void Labeller::State::search_anchors(const Subject& subject, std::size_t s,
                                     const std::optional<RigidTransform>& parent_pose,
                                     const std::vector<std::size_t>& candidates,
                                     const std::array<std::size_t, 3>& anchors, std::vector<Found>* all,
                                     std::optional<Found>& best) const {
  const SegmentState& segment = subject.segments[s];
  const SegmentLayout& layout = subject.model.segments[s];
  const auto [a, b, c] = anchors;
  for (std::size_t i : candidates) {
    for (std::size_t j : candidates) {
      if (j == i || !distance_fits(segment, a, b, at(i), at(j))) continue;
      for (std::size_t k : candidates) {
        if (k == i || k == j || !distance_fits(segment, a, c, at(i), at(k)) ||
            !distance_fits(segment, b, c, at(j), at(k)))
          continue;
        Points seen(layout.markers.size());
        seen[a] = at(i);
        seen[b] = at(j);
        seen[c] = at(k);
        const auto fit = fit_layout(layout, seen);
        if (!fit) continue;
        Found found{{{a, i}, {b, j}, {c, k}}, fit->T_world_segment, false, fit->rms_m};
        if (!tree_accepts(subject, s, found.pose, parent_pose, found.cost)) continue;
        add_extras(subject, s, found);
        if (all != nullptr) all->push_back(found);
        if (!best || found.pairs.size() > best->pairs.size() ||
            (found.pairs.size() == best->pairs.size() && found.cost < best->cost))
          best = std::move(found);
      }
    }
  }
}

// The segment's other tracked markers: the unclaimed point nearest each prediction, within the gate;
// the pose refitted to them all.
void Labeller::State::add_extras(const Subject& subject, std::size_t s, Found& found) const {
  const SegmentState& segment = subject.segments[s];
  const SegmentLayout& layout = subject.model.segments[s];
  const auto used = [&](std::size_t p) {
    return std::any_of(found.pairs.begin(), found.pairs.end(),
                       [p](const auto& pair) { return pair.second == p; });
  };
  Points seen(layout.markers.size());
  for (const auto& [m, p] : found.pairs) seen[m] = at(p);
  for (std::size_t m : segment.tracked) {
    if (seen[m]) continue;
    const Eigen::Vector3d predicted = found.pose.apply(layout.markers[m].position_m);
    std::optional<std::size_t> nearest;
    double best = options.loose_gate_m;
    for (std::size_t p = 0; p < claimed.size(); ++p) {
      const double d = (at(p) - predicted).norm();
      if (claimed[p] != 0 || young[p] != 0 || d >= best || used(p)) continue;
      best = d;
      nearest = p;
    }
    if (!nearest) continue;
    found.pairs.emplace_back(m, *nearest);
    seen[m] = at(*nearest);
    found.cost += best;
  }
  if (const auto fit = fit_layout(layout, seen)) found.pose = fit->T_world_segment;
}

// Where a child's marker may be: on a shell about the parent's marker nearest to it in the static
// pose (a joint sits near it, so the distance holds while the joint turns), else near where the
// parent's pose and the static posture put it. Returns the cost of point `p` or nullopt.
std::optional<double> Labeller::State::child_marker_cost(const Subject& subject, std::size_t s, std::size_t m,
                                                         const RigidTransform& parent_pose,
                                                         const Points& parent_seen, std::size_t p) const {
  const auto& model = subject.model;
  const std::size_t parent = *subject.segments[s].parent;
  const auto [offset, reach] = static_offset(model, s, parent, options);
  const Eigen::Vector3d marker_static = model.segments[s].origin_m + model.segments[s].markers[m].position_m;
  std::optional<double> shell;
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < parent_seen.size(); ++k) {
    if (!parent_seen[k]) continue;
    const double d =
        (marker_static - (model.segments[parent].origin_m + model.segments[parent].markers[k].position_m))
            .norm();
    if (d >= nearest) continue;
    nearest = d;
    shell = std::abs((at(p) - *parent_seen[k]).norm() - d) / shell_width(subject, parent, d);
  }
  const double predicted =
      (at(p) - (parent_pose.t + parent_pose.q * (offset + model.segments[s].markers[m].position_m))).norm();
  if (shell) return *shell <= 1.0 ? std::optional(*shell + 0.1 * predicted / reach) : std::nullopt;
  return predicted <= reach ? std::optional(predicted / reach) : std::nullopt;
}

namespace {

// The signed volume of the tetrahedron (p0, p1, a, b), normalised by its edge lengths: four points
// have a handedness that two markers and their parent's two nearest do not lose while the joint
// turns (Gait2392's forearm: -0.08 static, -0.09..-0.12 walking on the right, +0.06 / +0.08..+0.12
// on the left), so it orders a segment's two markers where distances cannot.
double handedness(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& a,
                  const Eigen::Vector3d& b) {
  const Eigen::Vector3d u = p1 - p0;
  const Eigen::Vector3d v = a - p1;
  const Eigen::Vector3d w = b - p1;
  return u.cross(v).dot(w) / (u.norm() * v.norm() * w.norm());
}

// The parent's two seen markers nearest to the child's origin in the static pose, farther first.
std::optional<std::pair<std::size_t, std::size_t>> nearest_two(const SubjectModel& model, std::size_t s,
                                                               std::size_t parent,
                                                               const Points& parent_seen) {
  std::vector<std::pair<double, std::size_t>> by_distance;
  for (std::size_t k = 0; k < parent_seen.size(); ++k) {
    if (!parent_seen[k]) continue;
    const Eigen::Vector3d at = model.segments[parent].origin_m + model.segments[parent].markers[k].position_m;
    by_distance.emplace_back((at - model.segments[s].origin_m).norm(), k);
  }
  if (by_distance.size() < 2) return std::nullopt;
  std::sort(by_distance.begin(), by_distance.end());
  return std::pair{by_distance[1].second, by_distance[0].second};
}

}  // namespace

// Whether points (i, j) as markers (a, b) of segment s keep the static pose's handedness with the
// parent's two nearest markers (when that handedness is clear).
bool Labeller::State::keeps_handedness(const Subject& subject, std::size_t s, std::size_t a, std::size_t b,
                                       const Points& parent_seen, std::size_t i, std::size_t j) const {
  const auto& model = subject.model;
  const std::size_t parent = *subject.segments[s].parent;
  const auto pair = nearest_two(model, s, parent, parent_seen);
  if (!pair) return true;
  const auto world = [&](std::size_t seg, std::size_t m) {
    return Eigen::Vector3d(model.segments[seg].origin_m + model.segments[seg].markers[m].position_m);
  };
  const double expected =
      handedness(world(parent, pair->first), world(parent, pair->second), world(s, a), world(s, b));
  if (std::abs(expected) < options.min_handedness) return true;
  return handedness(*parent_seen[pair->first], *parent_seen[pair->second], at(i), at(j)) * expected > 0.0;
}

// Segments without a pose (one or two tracked markers): the candidates that fit child_marker_cost
// best, a pair's distance within tolerance.
std::optional<Found> Labeller::State::search_pair(const Subject& subject, std::size_t s,
                                                  const RigidTransform& parent_pose,
                                                  const Points& parent_seen) const {
  const SegmentState& segment = subject.segments[s];
  const SegmentLayout& layout = subject.model.segments[s];
  if (segment.tracked.empty() || !segment.parent) return std::nullopt;
  const auto candidates = candidates_near(subject, s, std::nullopt);
  const std::size_t a = segment.tracked[0];
  std::optional<Found> best;
  for (std::size_t i : candidates) {
    const auto ci = child_marker_cost(subject, s, a, parent_pose, parent_seen, i);
    if (!ci) continue;
    if (segment.tracked.size() == 1) {
      if (!best || *ci < best->cost) best = Found{{{a, i}}, {}, true, *ci};
      continue;
    }
    const std::size_t b = segment.tracked[1];
    for (std::size_t j : candidates) {
      if (j == i || !distance_fits(segment, a, b, at(i), at(j)) ||
          !keeps_handedness(subject, s, a, b, parent_seen, i, j))
        continue;
      const auto cj = child_marker_cost(subject, s, b, parent_pose, parent_seen, j);
      if (cj && (!best || *ci + *cj < best->cost)) best = Found{{{a, i}, {b, j}}, {}, true, *ci + *cj};
    }
  }
  if (!best) return std::nullopt;
  Points seen(layout.markers.size());
  for (const auto& [m, p] : best->pairs) seen[m] = at(p);
  best->pose = segment_pose(layout, seen, parent_pose.q)->first;
  return best;
}

std::optional<Found> Labeller::State::search_segment(const Subject& subject, std::size_t s,
                                                     const std::optional<RigidTransform>& parent_pose,
                                                     const Points& parent_seen) const {
  const SegmentState& segment = subject.segments[s];
  if (segment.tracked.size() >= 3 && subject.model.segments[s].has_pose)
    return search_rigid(subject, s, parent_pose, candidates_near(subject, s, parent_pose));
  if (parent_pose) return search_pair(subject, s, *parent_pose, parent_seen);
  return std::nullopt;
}

Points Labeller::State::seen_now(const SegmentState& segment) const {
  Points seen(segment.markers.size());
  for (std::size_t m = 0; m < seen.size(); ++m) {
    if (segment.markers[m].point) seen[m] = at(*segment.markers[m].point);
  }
  return seen;
}

Points Labeller::State::seen_of(const Subject& subject, std::size_t s, const Hypothesis& h) const {
  Points seen(subject.segments[s].markers.size());
  if (h.segments[s]) {
    for (const auto& [m, p] : h.segments[s]->pairs) seen[m] = at(p);
  }
  return seen;
}

// Down the tree from a segment found at `pose`: each child searched where the pose puts it, its
// points claimed for the rest of the hypothesis.
void Labeller::State::grow(const Subject& subject, std::size_t s, const RigidTransform& pose, Hypothesis& h) {
  for (std::size_t child : subject.segments[s].children) {
    auto found = search_segment(subject, child, pose, seen_of(subject, s, h));
    if (!found) continue;
    for (const auto& pair : found->pairs) claimed[pair.second] = 1;
    h.markers += found->pairs.size();
    h.cost += found->cost;
    const RigidTransform child_pose = found->pose;
    h.segments[child] = std::move(found);
    grow(subject, child, child_pose, h);
  }
}

namespace {

bool has_track(const SegmentState& segment) {
  return std::any_of(segment.markers.begin(), segment.markers.end(),
                     [](const MarkerState& marker) { return marker.track.has_value(); });
}

bool better(const Hypothesis& a, const Hypothesis& b) {
  return a.markers > b.markers || (a.markers == b.markers && a.cost < b.cost);
}

}  // namespace

// Segment s searched afresh (the root in the lab, else from its parent's pose and seen markers):
// each candidate (up to root_hypotheses of a rigid segment's, the best of a pair's) grown over its
// subtree, the hypothesis that explains the most markers (then the lowest cost) taken. A mirrored
// root puts its children where there are none, so left and right come from the tree. `claimed` is
// as it was on return.
std::optional<Hypothesis> Labeller::State::best_hypothesis(const Subject& subject, std::size_t s,
                                                           const std::optional<RigidTransform>& parent_pose,
                                                           const Points& parent_seen) {
  std::vector<Found> starts;
  const bool rigid = subject.segments[s].tracked.size() >= 3 && subject.model.segments[s].has_pose;
  if (rigid) {
    search_rigid(subject, s, parent_pose, candidates_near(subject, s, parent_pose), &starts);
  } else if (auto found = search_segment(subject, s, parent_pose, parent_seen)) {
    starts.push_back(std::move(*found));
  }
  std::sort(starts.begin(), starts.end(), [](const Found& a, const Found& b) {
    return a.pairs.size() > b.pairs.size() || (a.pairs.size() == b.pairs.size() && a.cost < b.cost);
  });
  if (starts.size() > options.root_hypotheses) starts.resize(options.root_hypotheses);
  std::optional<Hypothesis> best;
  const std::vector<char> before = claimed;
  for (const Found& start : starts) {
    Hypothesis h;
    h.segments.resize(subject.segments.size());
    for (const auto& pair : start.pairs) claimed[pair.second] = 1;
    h.markers = start.pairs.size();
    h.cost = start.cost;
    h.segments[s] = start;
    grow(subject, s, start.pose, h);
    claimed = before;
    if (!best || better(h, *best)) best = std::move(h);
  }
  return best;
}

// The hypothesis's segments named (those of `subtree` it left out wait), their poses its own; the
// names the subtree had cleared first.
void Labeller::State::replace(std::size_t subject_index, const std::vector<char>& subtree,
                              const Hypothesis& h) {
  Subject& subject = subjects[subject_index];
  for (std::size_t s = 0; s < subject.segments.size(); ++s) {
    if (subtree[s] == 0) continue;
    for (auto& marker : subject.segments[s].markers) {
      if (marker.point) claimed[*marker.point] = 0;
      if (marker.track) labels.erase(*marker.track);
      marker = MarkerState{};
    }
    subject.segments[s].pose.reset();
  }
  // Named only once every old name is gone: a track may move to a segment cleared later.
  for (std::size_t s = 0; s < subject.segments.size(); ++s) {
    if (subtree[s] == 0 || !h.segments[s]) continue;
    commit(subject_index, s, *h.segments[s]);
    subject.segments[s].pose = h.segments[s]->pose;
    subject.segments[s].loose = h.segments[s]->loose;
  }
}

// A subject with no name on any track: acquired from the root's best hypothesis. A subject with
// names: each segment that lost them all is searched from its parent's pose, then revise().
void Labeller::State::acquire(std::size_t subject_index) {
  Subject& subject = subjects[subject_index];
  if (std::none_of(subject.segments.begin(), subject.segments.end(), has_track)) {
    const auto best = best_hypothesis(subject, subject.root, std::nullopt, {});
    if (best && best->markers >= options.min_markers)
      replace(subject_index, std::vector<char>(subject.segments.size(), 1), *best);
    return;
  }
  for (std::size_t s : subject.order) {
    SegmentState& segment = subject.segments[s];
    if (has_track(segment) || !segment.parent || !subject.segments[*segment.parent].pose) continue;
    const auto found = search_segment(subject, s, subject.segments[*segment.parent].pose,
                                      seen_now(subject.segments[*segment.parent]));
    if (!found) continue;
    commit(subject_index, s, *found);
    segment.pose = found->pose;
    segment.loose = found->loose;
  }
  revise(subject_index);
}

// An acquired subject is searched afresh now and then (revise_period_s live, revise_period_instants
// offline) while unnamed mature tracks are left over: the whole tree from the root, then each
// segment's subtree from its parent's pose (a fresh whole tree often misses what tracking keeps
// mid-walk). A hypothesis explaining at least revise_margin more of the markers seen now than the
// names do replaces them. A subject acquired while one marker of a three-marker segment was hidden
// (Gait2392's torso without L.Acromium: no rigid fit, so neither head nor arms) took the hypothesis
// that fitted a wrong marker there (L.Temple as L.Acromium, the soft torso's distances allow it)
// and unlocked the subtree; its names stayed on living tracks, the head and the left arm never
// found their places, and nothing else ever took a name from a track.
void Labeller::State::revise(std::size_t subject_index) {
  Subject& subject = subjects[subject_index];
  const bool due = now_s ? (!subject.revised_s || *now_s - *subject.revised_s >= options.revise_period_s)
                         : ++subject.instants_since_revision >= options.revise_period_instants;
  if (!due) return;
  std::size_t spare = 0;
  for (std::size_t p = 0; p < claimed.size(); ++p) spare += claimed[p] == 0 && young[p] == 0 ? 1 : 0;
  if (spare < options.revise_margin) return;
  subject.revised_s = now_s;
  subject.instants_since_revision = 0;
  for (std::size_t s : subject.order) {
    const auto parent = subject.segments[s].parent;
    std::optional<RigidTransform> parent_pose;
    if (parent) {
      const SegmentState& p = subject.segments[*parent];
      if (!p.pose || p.loose) continue;
      parent_pose = p.pose;
    }
    std::vector<char> subtree(subject.segments.size(), 0);
    subtree[s] = 1;
    for (std::size_t t : subject.order) {
      if (subject.segments[t].parent && subtree[*subject.segments[t].parent] != 0) subtree[t] = 1;
    }
    const std::vector<char> before = claimed;
    std::size_t seen = 0;
    for (std::size_t t = 0; t < subject.segments.size(); ++t) {
      for (const auto& marker : subject.segments[t].markers) {
        if (subtree[t] == 0 || !marker.point) continue;
        claimed[*marker.point] = 0;
        ++seen;
      }
    }
    const auto best =
        best_hypothesis(subject, s, parent_pose, parent ? seen_now(subject.segments[*parent]) : Points{});
    claimed = before;
    if (!best || best->markers < seen + options.revise_margin ||
        (!parent && best->markers < options.min_markers))
      continue;
    replace(subject_index, subtree, *best);
    if (!parent) return;  // the whole tree
  }
}

Labeller::Labeller(std::vector<SubjectModel> models, LabellerOptions options)
    : state_(std::make_unique<State>()) {
  state_->options = std::move(options);
  for (auto& model : models) state_->subjects.push_back(make_subject(std::move(model), state_->options));
}

Labeller::~Labeller() = default;
Labeller::Labeller(Labeller&&) noexcept = default;
Labeller& Labeller::operator=(Labeller&&) noexcept = default;

void Labeller::update(const std::vector<TrackPoint>& points, std::optional<double> time_s) {
  State& s = *state_;
  s.points = &points;
  s.now_s = time_s;
  s.claimed.assign(points.size(), 0);
  std::unordered_map<std::uint64_t, std::size_t> by_track;
  std::unordered_map<std::uint64_t, int> ages;
  s.young.assign(points.size(), 0);
  for (std::size_t p = 0; p < points.size(); ++p) {
    by_track.emplace(points[p].track, p);
    const auto age = s.ages.find(points[p].track);
    const int seen = (age == s.ages.end() ? 0 : age->second) + 1;
    ages[points[p].track] = seen;
    s.young[p] = seen < s.options.min_track_age ? 1 : 0;
  }
  s.ages = std::move(ages);
  for (auto& subject : s.subjects) {
    for (auto& segment : subject.segments) {
      segment.previous.reset();
      if (segment.pose && !segment.loose) segment.previous = segment.pose;
    }
  }
  s.keep(by_track);
  for (std::size_t i = 0; i < s.subjects.size(); ++i) {
    s.fit_poses(s.subjects[i]);
    s.untangle(i);
    s.predict(s.subjects[i]);
  }
  s.recover();
  for (std::size_t i = 0; i < s.subjects.size(); ++i) {
    s.fit_poses(s.subjects[i]);
    s.acquire(i);
  }
  s.points = nullptr;
}

void Labeller::name_track(std::uint64_t track, const MarkerLabel& label) {
  State& s = *state_;
  if (label.subject >= s.subjects.size()) return;
  Subject& subject = s.subjects[label.subject];
  for (std::size_t seg = 0; seg < subject.segments.size(); ++seg) {
    const auto& tracked = subject.segments[seg].tracked;
    for (std::size_t m : tracked) {
      if (subject.model.segments[seg].markers[m].name != label.marker) continue;
      if (const auto old = s.labels.find(track); old != s.labels.end()) {
        const auto& [i, where] = old->second;
        s.subjects[i].segments[where.first].markers[where.second].track.reset();
        s.labels.erase(old);
      }
      MarkerState& marker = subject.segments[seg].markers[m];
      if (marker.track) s.labels.erase(*marker.track);
      marker.track = track;
      s.labels[track] = {label.subject, {seg, m}};
      return;
    }
  }
}

std::optional<MarkerLabel> Labeller::label_of(std::uint64_t track) const {
  const auto found = state_->labels.find(track);
  if (found == state_->labels.end()) return std::nullopt;
  const auto& [subject, where] = found->second;
  return MarkerLabel{subject,
                     state_->subjects[subject].model.segments[where.first].markers[where.second].name};
}

std::vector<std::pair<std::uint64_t, MarkerLabel>> Labeller::labels() const {
  std::vector<std::pair<std::uint64_t, MarkerLabel>> out;
  out.reserve(state_->labels.size());
  for (const auto& entry : state_->labels) {
    if (auto label = label_of(entry.first)) out.emplace_back(entry.first, std::move(*label));
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

std::uint64_t Labeller::untangled() const {
  return state_->untangled;
}

std::uint64_t Labeller::released() const {
  return state_->released;
}

const SubjectModel& Labeller::model(std::size_t subject) const {
  return state_->subjects.at(subject).model;
}

}  // namespace panoptes::labelling
