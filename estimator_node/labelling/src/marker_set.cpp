// SPDX-License-Identifier: Apache-2.0
#include "panoptes/labelling/marker_set.h"

#include <map>
#include <string>

namespace panoptes::labelling {

namespace {

std::string at(const std::string& list, std::size_t index) {
  return list + "[" + std::to_string(index) + "]";
}

std::optional<MarkerSetProblem> check_markers(const MarkerSet& set) {
  if (set.markers.empty()) return MarkerSetProblem{"markers", "expected at least one marker"};
  std::map<std::string, std::size_t> first;
  for (std::size_t i = 0; i < set.markers.size(); ++i) {
    const std::string& name = set.markers[i].name;
    if (name.empty()) return MarkerSetProblem{at("markers", i), "a marker needs a name"};
    const auto [where, inserted] = first.emplace(name, i);
    if (!inserted)
      return MarkerSetProblem{at("markers", i), "duplicate marker '" + name + "' (first at " +
                                                    at("markers", where->second) + ")"};
  }
  return std::nullopt;
}

// Every marker in exactly one segment, each listed once there.
std::optional<MarkerSetProblem> check_segment_markers(const MarkerSet& set) {
  std::map<std::string, std::size_t> owner;  // marker -> segment index
  for (std::size_t s = 0; s < set.segments.size(); ++s) {
    const SegmentDefinition& segment = set.segments[s];
    const std::string entry = at("segments", s);
    if (segment.markers.empty()) return MarkerSetProblem{entry + ".markers", "expected at least one marker"};
    for (std::size_t m = 0; m < segment.markers.size(); ++m) {
      const std::string& marker = segment.markers[m];
      const std::string key = at(entry + ".markers", m);
      if (!set.marker_index(marker))
        return MarkerSetProblem{key, "unknown marker '" + marker + "' (not in markers)"};
      const auto [where, inserted] = owner.emplace(marker, s);
      if (inserted) continue;
      if (where->second == s)
        return MarkerSetProblem{key,
                                "marker '" + marker + "' listed twice in segment '" + segment.name + "'"};
      return MarkerSetProblem{key, "marker '" + marker + "' is already in segment '" +
                                       set.segments[where->second].name + "' (" +
                                       at("segments", where->second) + ")"};
    }
  }
  for (std::size_t i = 0; i < set.markers.size(); ++i) {
    if (!owner.contains(set.markers[i].name))
      return MarkerSetProblem{at("markers", i), "marker '" + set.markers[i].name + "' belongs to no segment"};
  }
  return std::nullopt;
}

// Follows parents from `start`; a walk that comes back to a segment it passed is a cycle.
std::optional<MarkerSetProblem> check_cycle_from(const MarkerSet& set, std::size_t start) {
  std::vector<std::size_t> path{start};
  std::size_t current = start;
  while (!set.segments[current].parent.empty()) {
    current = *set.segment_index(set.segments[current].parent);
    for (std::size_t i = 0; i < path.size(); ++i) {
      if (path[i] != current) continue;
      std::string cycle;
      for (std::size_t j = i; j < path.size(); ++j) cycle += set.segments[path[j]].name + " -> ";
      return MarkerSetProblem{at("segments", start) + ".parent",
                              "cycle in the segment tree: " + cycle + set.segments[current].name};
    }
    path.push_back(current);
  }
  return std::nullopt;
}

std::optional<MarkerSetProblem> check_segment_tree(const MarkerSet& set) {
  if (set.segments.empty()) return MarkerSetProblem{"segments", "expected at least one segment"};
  std::map<std::string, std::size_t> first;
  std::vector<std::string> roots;
  for (std::size_t s = 0; s < set.segments.size(); ++s) {
    const SegmentDefinition& segment = set.segments[s];
    if (segment.name.empty()) return MarkerSetProblem{at("segments", s), "a segment needs a name"};
    const auto [where, inserted] = first.emplace(segment.name, s);
    if (!inserted)
      return MarkerSetProblem{
          at("segments", s) + ".name",
          "duplicate segment '" + segment.name + "' (first at " + at("segments", where->second) + ")"};
  }
  for (std::size_t s = 0; s < set.segments.size(); ++s) {
    const SegmentDefinition& segment = set.segments[s];
    if (segment.parent.empty()) {
      roots.push_back(segment.name);
    } else if (!set.segment_index(segment.parent)) {
      return MarkerSetProblem{at("segments", s) + ".parent",
                              "unknown parent segment '" + segment.parent + "'"};
    }
  }
  for (std::size_t s = 0; s < set.segments.size(); ++s) {
    if (auto problem = check_cycle_from(set, s)) return problem;
  }
  if (roots.size() != 1) {
    std::string names;
    for (const auto& root : roots) names += (names.empty() ? "" : ", ") + root;
    return MarkerSetProblem{"segments", "expected exactly one segment without a parent (the root), found " +
                                            std::to_string(roots.size()) +
                                            (names.empty() ? "" : ": " + names)};
  }
  return std::nullopt;
}

std::optional<MarkerSetProblem> check_sticks(const MarkerSet& set) {
  for (std::size_t i = 0; i < set.sticks.size(); ++i) {
    for (std::size_t end = 0; end < 2; ++end) {
      if (!set.marker_index(set.sticks[i][end]))
        return MarkerSetProblem{at(at("sticks", i), end), "unknown marker '" + set.sticks[i][end] + "'"};
    }
    if (set.sticks[i][0] == set.sticks[i][1])
      return MarkerSetProblem{at("sticks", i), "a stick joins two different markers"};
  }
  return std::nullopt;
}

std::optional<MarkerSetProblem> check_joints(const MarkerSet& set) {
  std::map<std::string, std::size_t> first;
  for (std::size_t j = 0; j < set.joints.size(); ++j) {
    const JointDefinition& joint = set.joints[j];
    const std::string entry = at("joints", j);
    if (joint.name.empty()) return MarkerSetProblem{entry, "a joint needs a name"};
    if (!first.emplace(joint.name, j).second)
      return MarkerSetProblem{entry + ".name", "duplicate joint '" + joint.name + "'"};
    const auto child = set.segment_index(joint.child);
    if (!child) return MarkerSetProblem{entry + ".child", "unknown segment '" + joint.child + "'"};
    if (set.segments[*child].parent.empty())
      return MarkerSetProblem{entry + ".child",
                              "segment '" + joint.child + "' is the root: a joint needs a parent"};
    if (joint.points.empty() || joint.points.size() > 2)
      return MarkerSetProblem{entry, "expected `midpoint: [a, b]` or `point: name`"};
    for (std::size_t p = 0; p < joint.points.size(); ++p) {
      if (joint.points[p].empty()) return MarkerSetProblem{entry, "a point needs a name"};
    }
    if (joint.points.size() == 2 && joint.points[0] == joint.points[1])
      return MarkerSetProblem{entry + ".midpoint", "the midpoint of two different points"};
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::size_t> MarkerSet::marker_index(const std::string& marker) const {
  for (std::size_t i = 0; i < markers.size(); ++i) {
    if (markers[i].name == marker) return i;
  }
  return std::nullopt;
}

std::optional<std::size_t> MarkerSet::segment_index(const std::string& segment) const {
  for (std::size_t i = 0; i < segments.size(); ++i) {
    if (segments[i].name == segment) return i;
  }
  return std::nullopt;
}

std::optional<std::size_t> MarkerSet::segment_of(const std::string& marker) const {
  for (std::size_t s = 0; s < segments.size(); ++s) {
    for (const auto& name : segments[s].markers) {
      if (name == marker) return s;
    }
  }
  return std::nullopt;
}

std::optional<MarkerSetProblem> find_segment_tree_problem(const std::vector<SegmentDefinition>& segments) {
  MarkerSet tree;
  tree.segments = segments;
  return check_segment_tree(tree);
}

std::optional<MarkerSetProblem> find_marker_set_problem(const MarkerSet& set) {
  if (auto problem = check_markers(set)) return problem;
  if (auto problem = check_segment_tree(set)) return problem;
  if (auto problem = check_segment_markers(set)) return problem;
  if (auto problem = check_sticks(set)) return problem;
  return check_joints(set);
}

}  // namespace panoptes::labelling
