// SPDX-License-Identifier: Apache-2.0
// A marker set: the named markers placed on a person, grouped into segments that form a tree
// (docs/marker_sets.md). Types and their validation only; the YAML file is
// panoptes/labelling_files/marker_set_file.h.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace panoptes::labelling {

struct MarkerDefinition {
  std::string name;
  bool calibration_only = false;  // in the static trial only (medial knee and ankle markers)
  bool optional = false;          // the model is built without it when the static trial lacks it
};

// Markers on one body part; `parent` is empty for the root of the tree.
struct SegmentDefinition {
  std::string name;
  std::string parent;
  std::vector<std::string> markers;
};

// A joint centre between `child` and its parent segment, from the static trial: the midpoint of
// two points (`points` has two names), or one named point of the static file (`points` has one).
struct JointDefinition {
  std::string name;
  std::string child;
  std::vector<std::string> points;
};

struct MarkerSet {
  std::string name;
  std::vector<MarkerDefinition> markers;  // export order
  std::vector<SegmentDefinition> segments;
  std::vector<std::array<std::string, 2>> sticks;
  std::vector<JointDefinition> joints;

  std::optional<std::size_t> marker_index(const std::string& marker) const;
  std::optional<std::size_t> segment_index(const std::string& segment) const;
  // The segment `marker` belongs to (a valid set has exactly one).
  std::optional<std::size_t> segment_of(const std::string& marker) const;
};

// What is wrong with a set: `entry` is its path in the file's terms ("segments[2].markers[1]"),
// `reason` says why. The file reader turns it into a ConfigError naming the file.
struct MarkerSetProblem {
  std::string entry;
  std::string reason;
};

// The first problem, or nullopt for a valid set: duplicate names, unknown markers, segments or
// parents, a marker listed twice in a segment, in two segments or in none, a cycle in the
// segment tree, not exactly one root, bad sticks and joints.
std::optional<MarkerSetProblem> find_marker_set_problem(const MarkerSet& set);

// The segment tree's part of it (names, parents, cycles, one root), for anything with segments.
std::optional<MarkerSetProblem> find_segment_tree_problem(const std::vector<SegmentDefinition>& segments);

}  // namespace panoptes::labelling
