// SPDX-License-Identifier: Apache-2.0
// What panoptes_console knows about the bus: the latest record of every camera, the estimator's
// tracks, bodies and status, and the commands waiting for an acknowledgement. DDS listener threads
// write it; the server thread reads it ~30 times a second into one JSON snapshot shared by every
// browser (docs/console.md). Plain types only: no DDS, so the server is tested without a bus.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "panoptes/image_coverage.h"
#include "panoptes/time.h"

namespace panoptes::console {

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
};

struct EstimatorRecord {
  unsigned tracks_confirmed = 0;
  unsigned tracks_tentative = 0;
  double cpu_percent = 0;
  double update_p99_ms = 0;
  std::map<std::string, CameraUsageRecord> cameras;
};

struct TrackPoint {
  std::int64_t id = 0;
  std::array<double, 3> position{};
  int status = 0;  // 0 tentative, 1 confirmed, 2 coasting
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
  int status = 2;              // 0 tracking, 1 ambiguous, 2 not identified
  TimeNs stamp_ns = 0;
  std::vector<double> angles;                  // rad, one per joint, base first
  std::vector<std::array<double, 3>> markers;  // m, world, base first
  std::vector<bool> marker_valid;              // updated within the estimator's stale time
  std::array<double, 3> tip{};
  std::array<double, 3> predicted_tip{};  // prediction_horizon_ns ahead (= tip when 0)
  TimeNs prediction_horizon_ns = 0;
  bool grabbing = false;
};

// A grab (kind 0) or release (1) that a chain sample carried.
struct ChainEventRecord {
  std::string chain;
  int kind = 0;
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

// Why a chain sample cannot be shown (naming the chain or event and the field); empty when it can.
std::string chain_frame_error(const ChainFrameRecord& frame);

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

// A light per camera, with the reason a person can act on.
struct Health {
  std::string light;  // green | amber | red
  std::string reason;
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
  std::string result;  // applied | rejected | no_ack
  std::string reason;
};

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

class ConsoleState {
 public:
  explicit ConsoleState(StateOptions options = {}) : options_(options) {}

  void on_info(const std::string& camera, CameraInfoRecord info, TimeNs now);
  void on_status(const std::string& camera, CameraStatusRecord status, TimeNs now);
  void on_features(const std::string& camera, FeatureRecord features, TimeNs now);
  void on_predictions(const std::string& camera, std::vector<PredictedWindowRecord> windows, TimeNs now);
  // A camera's preview image (8-bit grey, row-major), as camera_node sends it on request.
  void on_preview(const std::string& camera, TimeNs stamp_ns, int width, int height, std::string pixels);
  // The camera's latest preview as a binary PGM (P5) image; nullopt when it sent none.
  std::optional<std::string> preview_pgm(const std::string& camera) const;
  void on_calibration(const std::map<std::string, CameraGeometry>& cameras);
  void on_estimator(EstimatorRecord status, TimeNs now);
  void on_tracks(std::vector<TrackPoint> tracks, TimeNs now);
  void on_body(BodyRecord body, TimeNs now);
  void on_recorder_status(const std::string& recorder, RecorderRecord status, TimeNs now);
  // A chain sample: kept (latest state per chain, events counted) or, when chain_frame_error
  // names a fault or it names more than max_chains chains, counted as dropped with that reason
  // (the full snapshot's "chain_samples"). False when dropped.
  bool on_chains(ChainFrameRecord frame, TimeNs now);

  bool knows_camera(const std::string& camera) const;
  // Image size of a camera, if its camera_info was seen.
  std::optional<std::pair<int, int>> image_size(const std::string& camera) const;
  // Records a forwarded command; its outcome comes from take_outcomes().
  void on_command_sent(PendingCommand command);
  void on_recorder_command_sent(PendingRecorderCommand command);
  bool knows_recorder(const std::string& recorder) const;
  std::vector<CommandOutcome> take_outcomes(TimeNs now);

  // Wand capture coverage (the calibration page): from start_coverage on, every camera's frames
  // and the 8x8 grid of where its blobs were seen, as `estimator_node calibrate capture` prints;
  // fed with the frames the capture writes (the same frames the CLI counts).
  void start_coverage(TimeNs now);
  void add_coverage_frame(const std::string& camera, const std::vector<BlobPoint>& blobs);
  void stop_coverage();
  // The calibration workflow's step and log (JSON text, in every full snapshot) and the same with
  // the last report and world-frame summary (served once per step by /api/calibration).
  void set_calibration_job(std::string summary_json, std::string full_json);
  std::string calibration_job() const;

  // The figures of one track (`kind` "track", key its id), body ("body", key its name) or chain
  // ("chain", key its name) for the page's details panel; null when it is not (or no longer) live.
  nlohmann::json details(const std::string& kind, const std::string& key, TimeNs now) const;

  // The state as JSON (docs/console.md, "Protocol"): cameras with blobs, health and, when `full`,
  // their info, geometry and status; tracks; bodies; chains; estimator status.
  nlohmann::json snapshot(TimeNs now, bool full) const;

 private:
  struct Camera {
    std::optional<CameraInfoRecord> info;
    std::optional<CameraGeometry> calibrated;
    std::optional<CameraStatusRecord> status;
    TimeNs status_ns = 0;
    std::uint64_t drops_last_period = 0;  // drops between the last two statuses
    FeatureRecord features;
    TimeNs features_ns = 0;
    std::vector<PredictedWindowRecord> windows;
    TimeNs windows_ns = 0;
    TimeNs preview_stamp_ns = 0;  // 0: no preview yet
    int preview_width = 0;
    int preview_height = 0;
    std::string preview_pixels;
    std::uint64_t frames_received = 0;
    double latency_ms = 0;  // receive time minus stamp, smoothed
    // Frames received per second, over the last whole second.
    TimeNs rate_window_start_ns = 0;
    std::uint64_t rate_window_frames = 0;
    double received_fps = 0;
  };

  struct Recorder {
    RecorderRecord status;
    TimeNs status_ns = 0;
    TimeNs started_ns = 0;
  };

  struct Chain {
    ChainRecord latest;
    TimeNs received_ns = 0;
    TimeNs first_seen_ns = 0;
    std::uint64_t grabs = 0;
    std::uint64_t releases = 0;
    std::optional<ChainEventRecord> last_event;
  };
  struct ChainSampleCounts {
    std::uint64_t received = 0;
    std::uint64_t dropped = 0;
    std::string last_error;
  };

  Health health_of(const std::string& id, const Camera& camera, TimeNs now) const;
  nlohmann::json chains_json(TimeNs now) const;
  nlohmann::json chain_details(const std::string& name, TimeNs now) const;
  void resolve_pending(const std::string& camera, const CameraStatusRecord& status);
  nlohmann::json recorders_json(TimeNs now) const;
  nlohmann::json calibration_json(TimeNs now) const;

  struct Coverage {
    std::uint64_t frames = 0;
    std::uint64_t frames_with_blobs = 0;
    ImageCoverage grid;
  };

  StateOptions options_;
  mutable std::mutex mutex_;
  std::map<std::string, Camera> cameras_;
  std::optional<EstimatorRecord> estimator_;
  TimeNs estimator_ns_ = 0;
  std::vector<TrackPoint> tracks_;
  TimeNs tracks_ns_ = 0;
  std::map<std::int64_t, TimeNs> track_first_seen_ns_;
  std::map<std::string, std::pair<BodyRecord, TimeNs>> bodies_;
  std::map<std::string, TimeNs> body_first_seen_ns_;
  std::map<std::string, Chain> chains_;
  ChainSampleCounts chain_samples_;
  std::map<std::string, Recorder> recorders_;
  std::vector<RecordingEntry> recordings_;
  std::vector<PendingCommand> pending_;
  std::vector<PendingRecorderCommand> pending_recorder_;
  bool coverage_active_ = false;
  TimeNs coverage_start_ns_ = 0;
  TimeNs coverage_stop_ns_ = 0;
  std::map<std::string, Coverage> coverage_;
  std::string calibration_job_ = "{}";
  std::string calibration_job_full_ = "{}";
  std::vector<CommandOutcome> outcomes_;
};

// The health light of one camera from what the console knows (pure, tested).
struct HealthInputs {
  bool has_status = false;
  TimeNs since_status_ns = 0;
  bool has_frames = false;
  TimeNs since_frame_ns = 0;
  double camera_fps = 0;       // from the camera's status
  double nominal_rate_hz = 0;  // from camera_info; 0 unknown
  std::uint64_t drops_last_period = 0;
  double detect_p99_ms = 0;
  std::string last_error;
};
Health camera_health(const HealthInputs& inputs, const StateOptions& options);

}  // namespace panoptes::console
