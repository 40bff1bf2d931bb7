// SPDX-License-Identifier: Apache-2.0
// EstimatorConfig: every setting of the estimator (tracker, initiation, bodies, identification,
// 7-LED markers, frame screen, and the node's inbox, windows and periods) and its YAML form
// (docs/estimator.md, "Configuration"). The YAML lives here, not in the estimator core, so
// panoptes_estimator stays free of file formats. Errors name the file and the dotted key path
// (panoptes::ConfigError, as the detector configuration).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "panoptes/estimator/frame_screen.h"
#include "panoptes/estimator/tracker.h"

namespace panoptes {
class YamlReader;
}

namespace panoptes::session {

// The ROS 2 topics the live node publishes (docs/ros2.md).
struct Ros2Settings {
  bool enabled = true;             // publish them (estimator_node --ros2 / --no-ros2)
  std::string frame_id = "world";  // header.frame_id of every message: the world frame
  std::string child_frame_prefix;  // tf child frame = prefix + body name (e.g. "mocap/")
  // /tf carries at most this many messages per second, one per period of a grid on the capture
  // clock (the fixed-rate frames' grid); 0: one per output frame.
  int tf_rate_hz = 120;
  // ROS 2 namespace of every topic but /tf ("" or "/": none), e.g. "/lab1": /lab1/rigid_bodies.
  std::string topic_namespace;
};

inline constexpr int kMaxTfRateHz = 10000;
inline constexpr std::size_t kMaxRos2NamespaceLength = 200;

// "" if `ns` is a ROS 2 namespace ("" and "/" for none; "lab1" is taken as "/lab1"), else why not:
// tokens of [A-Za-z0-9_] separated by single '/', none starting with a digit, no "__", no trailing
// '/', at most kMaxRos2NamespaceLength characters.
std::string check_ros2_namespace(const std::string& ns);
// The namespace as a DDS topic prefix: "" for none, else "/lab1" (absolute, no trailing '/').
std::string ros2_namespace_prefix(const std::string& ns);

// Settings of the session and the live node around the tracker.
struct NodeSettings {
  std::size_t inbox_capacity = 4096;   // frames waiting to be ordered by stamp
  double latency_window_ms = 0.0;      // how long frames wait in the inbox (live, --replay-arrival);
                                       // 0: none, late frames are replayed (docs/estimator.md)
  bool predictions = true;             // live: publish predicted windows
  double prediction_margin_px = 3.0;   // live: pixels added around each predicted gate
  double prediction_horizon_ms = 0.0;  // body poses are published this far ahead (seed 000 Ch. 5)
  double status_period_s = 1.0;        // live: seconds between status messages and progress lines
  double bodies_poll_s = 1.0;          // live: how often the bodies and calibration files are checked
  // rt/panoptes/frames, the ROS 2 outputs and offline --out-tracks/--out-poses (docs/frames.md):
  // "per-camera" (one per processed camera frame), "fixed" (frame_rate_hz, on a grid) or "auto"
  // (the default: fixed live, per-camera records offline).
  std::string frames = "auto";
  bool fixed_rate_live() const { return frames != "per-camera"; }
  bool fixed_rate_offline() const { return frames == "fixed"; }
  int frame_rate_hz = 120;           // with frames: fixed
  double camera_lost_after_s = 0.5;  // live: a camera without a frame this long is lost (wall time)
  // live: SCHED_FIFO priority (1-99) of the estimator thread, which publishes fixed-rate frames;
  // 0: the normal scheduler (docs/frames.md, "Timing of the live loop"). Needs CAP_SYS_NICE.
  int realtime_priority = 0;
};

// "" for "auto", "per-camera" or "fixed", else why not (the option or key is named by the caller).
std::string check_frames_mode(const std::string& mode);
// Empty if `mode` is a --continuous-calibration mode this build implements, else why not.
std::string check_continuous_calibration(const std::string& mode);

// Live auto-labelling (docs/marker_sets.md, "Live labelling"): `subjects:` in the settings YAML,
// or --subjects, --soft-segments, --label-rate-hz and --label-min-track-age. No models: off.
struct LabellingSettings {
  // Subject model files (panoptes_label model). A relative path in a settings file is taken from
  // the settings file's folder (load_estimator_config), on the command line from the working one.
  std::vector<std::string> models;
  std::vector<std::string> soft_segments;  // segments that deform while moving (e.g. Torso)
  double rate_hz = 120.0;                  // the labeller runs at most this often; 0: every frame
  int min_track_age = 3;                   // a track processed fewer frames does not acquire a subject
  // Live segment poses (docs/marker_sets.md, "Segment poses live"): each segment with enough named
  // markers is published like a body, "<subject>/<segment>". The models' static trials' vertical and
  // the direction the subject faced in them define the anatomical axes (OpenSim's TRC: +y, +x).
  bool segment_poses = true;
  std::string static_up = "+y";
  std::string static_forward = "+x";
};

// "" if `axis` names an axis (+x, -x, +y, -y, +z, -z; the sign may be left out), else why not.
std::string check_axis_name(const std::string& axis);

struct EstimatorConfig {
  NodeSettings node;
  estimator::FrameScreenOptions screen;
  estimator::TrackerOptions tracker;
  Ros2Settings ros2;
  LabellingSettings subjects;
};

// Reads a configuration: keys left out keep their defaults. Throws ConfigError
// ("<file>: <key path>: <reason>") on a missing file, bad syntax, an unknown key or a value out of
// range. Relative subject model paths are made relative to the file's folder.
EstimatorConfig load_estimator_config(const std::filesystem::path& path);
EstimatorConfig estimator_config_from_yaml(const YamlReader& reader);

// The complete configuration as YAML with a comment per key; loading it gives back equal options
// (doubles are written in their shortest form that reads back exactly).
std::string estimator_config_to_yaml(const EstimatorConfig& config);

// Field-by-field equality (tests, round trips).
bool operator==(const EstimatorConfig& a, const EstimatorConfig& b);

}  // namespace panoptes::session
