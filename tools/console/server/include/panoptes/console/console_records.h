// SPDX-License-Identifier: Apache-2.0
// What the console's models hold (docs/console.md, "Code"): plain records of what the bus said,
// the states as enums with the names the page reads, and the options. No DDS: app/bus_bridge.cpp
// converts the messages into these.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "panoptes/records.h"
#include "panoptes/time.h"

namespace panoptes::console {

// The states, each written into the JSON as the name below (to_string, and to_json for
// nlohmann::json). The ones that come from the bus keep the message's numbers: a value a message
// may carry outside the enumerators is checked where the sample is accepted.

// A camera's health light.
enum class Light : std::uint8_t { kGreen, kAmber, kRed };  // "green" | "amber" | "red"
// What became of a command sent to a camera or a recorder.
enum class CommandResult : std::uint8_t { kApplied, kRejected, kNoAck };  // "applied" | "rejected" | "no_ack"
// A chain's state (idl/chains.idl).
enum class ChainStatus : std::uint8_t { kTracking = 0, kAmbiguous = 1, kNotIdentified = 2 };
// "tracking" | "ambiguous" | "not_identified"
enum class ChainEventKind : std::uint8_t { kGrab = 0, kRelease = 1 };  // "grab" | "release"

std::string_view to_string(Light light);
std::string_view to_string(CommandResult result);
std::string_view to_string(ChainStatus status);  // any value other than 0 and 1 reads "not_identified"
std::string_view to_string(ChainEventKind kind);
void to_json(nlohmann::json& out, Light light);
void to_json(nlohmann::json& out, CommandResult result);
void to_json(nlohmann::json& out, ChainStatus status);
void to_json(nlohmann::json& out, ChainEventKind kind);
// A value that is one of the enumerators (a message may carry any octet).
constexpr bool known(ChainStatus status) {
  return status == ChainStatus::kTracking || status == ChainStatus::kAmbiguous ||
         status == ChainStatus::kNotIdentified;
}
constexpr bool known(ChainEventKind kind) {
  return kind == ChainEventKind::kGrab || kind == ChainEventKind::kRelease;
}
// A track's state is the core's TrackStatus (panoptes/records.h, named by its to_string), in the
// snapshot's track arrays as its number, which is the message's octet (idl/panoptes.idl: 0
// tentative, 1 confirmed, 2 coasting). Any other octet reads as coasting, as the page always
// showed it: a track the estimator did not call tentative or confirmed is not drawn as certain.
constexpr TrackStatus track_status_of(std::uint8_t octet) {
  return octet <= static_cast<std::uint8_t>(TrackStatus::kCoasting) ? static_cast<TrackStatus>(octet)
                                                                    : TrackStatus::kCoasting;
}

struct Pose {
  std::array<double, 3> position{};
  std::array<double, 4> orientation{0, 0, 0, 1};  // x, y, z, w
};

// From camera_info, replaced by rt/panoptes/calibration when that names the camera.
struct CameraGeometry {
  int width = 0;
  int height = 0;
  std::array<double, 4> K{};  // fx, fy, cx, cy
  bool has_pose = false;
  Pose T_world_cam;
};

struct CameraInfoRecord {
  std::string model;
  std::string backend;
  double nominal_rate_hz = 0;
  CameraGeometry geometry;
};

struct CameraStatusRecord {
  double fps = 0;
  std::uint64_t frames = 0;
  std::uint64_t drops_queue = 0;
  std::uint64_t drops_source = 0;
  double detect_p99_ms = 0;
  long threshold = 0;
  double exposure_us = 0;
  double gain_db = 0;
  std::int64_t clock_offset_ns = 0;
  double clock_drift_ppm = 0;
  std::string last_error;
  std::map<std::string, std::uint64_t> counters;
};

struct BlobPoint {
  float x = 0;
  float y = 0;
  float area = 0;
};

// A window the estimator predicts a track's blob in, for the camera's next frame (the
// Predictions topic that guides camera_node's search).
struct PredictedWindowRecord {
  float x = 0;  // px, centre
  float y = 0;
  float half_width = 0;
  float half_height = 0;
};

struct FeatureRecord {
  std::int64_t frame = 0;
  TimeNs stamp_ns = 0;
  std::vector<BlobPoint> blobs;
};

struct CameraUsageRecord {
  double utilisation = 0;
  double latency_p99_ms = 0;
  std::string state = "unknown";     // the estimator's view: "live", "lost" or "unknown"
  double since_last_frame_s = -1;    // wall time since its last frame reached the estimator
  std::uint64_t refused_frames = 0;  // from a second writer claiming the camera's id
  // Its calibration health (docs/continuous_calibration.md): "unknown", "ok", "small_bias" or
  // "quarantined", why, and how often it was quarantined; empty with --continuous-calibration off.
  std::string calibration;
  std::string calibration_reason;
  std::uint32_t quarantines = 0;
};

struct EstimatorRecord {
  unsigned tracks_confirmed = 0;
  unsigned tracks_tentative = 0;
  double cpu_percent = 0;
  double update_p99_ms = 0;
  std::map<std::string, CameraUsageRecord> cameras;
  unsigned tracks_coasting = 0;
  unsigned cameras_live = 0;
  unsigned cameras_lost = 0;
  unsigned tracks_unobserved = 0;  // held while every camera is lost: predictions only
};

// One labelled subject of rt/panoptes/labels (docs/marker_sets.md): its sticks (pairs of marker
// names drawn joined) and the names its tracks carry now.
struct SubjectLabelsRecord {
  std::string name;
  std::vector<std::array<std::string, 2>> sticks;
  std::map<std::int64_t, std::string> names;  // track id -> marker name
};

struct TrackPoint {
  std::int64_t id = 0;
  std::array<double, 3> position{};
  TrackStatus status = TrackStatus::kTentative;
  std::array<double, 3> velocity{};
  std::array<double, 6> covariance{};  // position: xx xy xz yy yz zz
  int cameras = 0;                     // cameras that updated the track recently
};

struct BodyRecord {
  std::string name;
  Pose pose;
  float quality = 0;
  std::array<double, 3> linear_velocity{};
  std::array<double, 3> angular_velocity{};
  std::array<double, 6> sigma{};  // square roots of the pose covariance's diagonal: x y z, rx ry rz
  TimeNs stamp_ns = 0;
};

// One articulated chain after a camera frame (rt/panoptes/chains, idl/chains.idl,
// docs/articulated.md). Markers, angles and tips mean something only while tracking.
struct ChainRecord {
  std::string name;
  std::uint32_t chain_id = 0;  // 1-based among the chains of the estimator's bodies file
  ChainStatus status = ChainStatus::kNotIdentified;
  TimeNs stamp_ns = 0;
  std::vector<double> angles;                  // rad, one per joint, base first
  std::vector<std::array<double, 3>> markers;  // m, world, base first
  std::vector<bool> marker_valid;              // updated within the estimator's stale time
  std::array<double, 3> tip{};
  std::array<double, 3> predicted_tip{};  // prediction_horizon_ns ahead (= tip when 0)
  TimeNs prediction_horizon_ns = 0;
  bool grabbing = false;
};

// A grab or release that a chain sample carried.
struct ChainEventRecord {
  std::string chain;
  ChainEventKind kind = ChainEventKind::kGrab;
  TimeNs stamp_ns = 0;
  std::array<double, 3> tip{};
  double bend = 0;  // rad
};

// One rt/panoptes/chains sample: every chain after one camera frame and the events it caused.
struct ChainFrameRecord {
  TimeNs stamp_ns = 0;
  std::vector<ChainRecord> chains;
  std::vector<ChainEventRecord> events;
};

// A recorder on the bus (rt/panoptes/recorder_status).
struct RecorderRecord {
  bool recording = false;
  std::string path;
  unsigned topics = 0;
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;
  double messages_per_s = 0;
  std::string error;
  std::map<std::string, std::uint64_t> rejections;  // samples dropped on receipt, by reason
};

// A recording seen from start to stop while the console ran.
struct RecordingEntry {
  std::string recorder;
  std::string path;
  std::uint64_t messages = 0;
  std::uint64_t bytes = 0;
  TimeNs started_ns = 0;  // wall clock, when the console first saw it recording
  TimeNs stopped_ns = 0;
};

// What the browser asked a recorder to do, waiting for its status to show it.
struct PendingRecorderCommand {
  std::uint64_t client = 0;
  std::int64_t request = 0;
  std::string recorder;
  bool want_recording = false;
  TimeNs sent_ns = 0;
};

// A command forwarded to a camera, waiting for the camera's status to count it (applied) or to
// count a bad_command (rejected, with the camera's last_error).
struct PendingCommand {
  std::uint64_t client = 0;
  std::int64_t request = 0;
  std::string camera;
  std::string command;
  std::uint64_t applied_before = 0;
  std::uint64_t rejected_before = 0;
  TimeNs sent_ns = 0;
};

struct CommandOutcome {
  std::uint64_t client = 0;
  std::int64_t request = 0;
  CommandResult result = CommandResult::kNoAck;
  std::string reason;
};
// The page's command_result message.
void to_json(nlohmann::json& out, const CommandOutcome& outcome);

struct StateOptions {
  TimeNs feature_timeout_ns = kNsPerSecond;       // no frame for this long: red
  TimeNs status_timeout_ns = 3 * kNsPerSecond;    // no status for this long: red
  TimeNs ack_timeout_ns = 3 * kNsPerSecond;       // a command not counted by then: no_ack
  TimeNs body_timeout_ns = kNsPerSecond / 2;      // a body not updated for this long is dropped
  TimeNs track_timeout_ns = kNsPerSecond / 2;     // tracks older than this are not shown
  TimeNs recorder_timeout_ns = 5 * kNsPerSecond;  // a recorder silent for this long is not listed
  TimeNs chain_timeout_ns = kNsPerSecond / 2;     // a chain not updated for this long is not shown
  std::size_t max_chains = 64;                    // chains by name; samples naming more are dropped
  std::size_t max_recordings = 200;               // the list keeps the newest
};

}  // namespace panoptes::console
