// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console_app/bus_bridge.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "panoptes/dds/convert.h"
#include "panoptes/time.h"
#include "panoptes_msgs/chains.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::console {

namespace {

namespace msg = panoptes::msg;

Pose pose_of(const msg::Pose3& pose) {
  Pose out;
  std::copy(pose.position().begin(), pose.position().end(), out.position.begin());
  std::copy(pose.orientation().begin(), pose.orientation().end(), out.orientation.begin());
  return out;
}

// The geometry through the one decoding of a CameraInfo's calibration (dds/convert.h).
CameraInfoRecord info_of(const msg::CameraInfo& info) {
  CameraInfoRecord out;
  out.model = info.model();
  out.backend = info.backend();
  out.nominal_rate_hz = info.nominal_rate_hz();
  out.geometry.width = static_cast<int>(info.width());
  out.geometry.height = static_cast<int>(info.height());
  const std::optional<CameraCalibration> calibration = dds::calibration_from(info);
  if (!calibration) return out;
  const CameraIntrinsics& K = calibration->intrinsics;
  out.geometry.K = {K.fx, K.fy, K.cx, K.cy};
  if (calibration->T_world_cam) {
    const RigidTransform& T = *calibration->T_world_cam;
    out.geometry.has_pose = true;
    out.geometry.T_world_cam.position = {T.t.x(), T.t.y(), T.t.z()};
    out.geometry.T_world_cam.orientation = {T.q.x(), T.q.y(), T.q.z(), T.q.w()};
  }
  return out;
}

CameraStatusRecord status_of(const msg::CameraStatus& status) {
  CameraStatusRecord out;
  out.fps = status.fps();
  out.frames = status.frames();
  out.drops_queue = status.drops_queue();
  out.drops_source = status.drops_source();
  out.detect_p99_ms = status.detect_p99_ms();
  out.threshold = status.threshold();
  out.exposure_us = status.exposure_us();
  out.gain_db = status.gain_db();
  out.clock_offset_ns = status.clock_offset_ns();
  out.clock_drift_ppm = status.clock_drift_ppm();
  out.last_error = status.last_error();
  for (const msg::Counter& counter : status.counters()) out.counters[counter.name()] = counter.value();
  return out;
}

EstimatorRecord estimator_of(const msg::EstimatorStatus& status) {
  EstimatorRecord out;
  out.tracks_confirmed = status.tracks_confirmed();
  out.tracks_tentative = status.tracks_tentative();
  out.cpu_percent = status.cpu_percent();
  out.update_p99_ms = status.update_p99_ms();
  out.tracks_coasting = status.tracks_coasting();
  out.cameras_live = status.cameras_live();
  out.cameras_lost = status.cameras_lost();
  out.tracks_unobserved = status.tracks_unobserved();
  static constexpr const char* kStates[] = {"live", "lost", "unknown"};
  for (const msg::CameraUsage& usage : status.cameras()) {
    CameraUsageRecord& record = out.cameras[usage.camera_id()];
    record.utilisation = usage.utilisation();
    record.latency_p99_ms = usage.latency_p99_ms();
    record.state = kStates[std::min<unsigned>(usage.state(), 2)];
    record.since_last_frame_s = usage.since_last_frame_s();
    record.refused_frames = usage.refused_frames();
  }
  static constexpr const char* kCalibrationStates[] = {"unknown", "ok", "small_bias", "quarantined"};
  for (const msg::CameraCalibrationHealth& health : status.calibration()) {
    CameraUsageRecord& record = out.cameras[health.camera_id()];
    record.calibration = kCalibrationStates[std::min<unsigned>(health.state(), 3)];
    record.calibration_reason = health.reason();
    record.quarantines = health.quarantines();
  }
  return out;
}

TrackPoint track_of(const msg::Track& track) {
  TrackPoint out;
  out.id = track.id();
  std::copy(track.position().begin(), track.position().end(), out.position.begin());
  std::copy(track.velocity().begin(), track.velocity().end(), out.velocity.begin());
  std::copy(track.covariance().begin(), track.covariance().end(), out.covariance.begin());
  out.status = track_status_of(track.status());
  out.cameras = track.cameras();
  return out;
}

BodyRecord body_of(const msg::BodyPose& pose) {
  BodyRecord out{pose.name(), pose_of(pose.pose()), pose.quality()};
  std::copy(pose.linear_velocity().begin(), pose.linear_velocity().end(), out.linear_velocity.begin());
  std::copy(pose.angular_velocity().begin(), pose.angular_velocity().end(), out.angular_velocity.begin());
  for (std::size_t k = 0; k < 6; ++k) out.sigma[k] = std::sqrt(std::max(0.0, pose.covariance()[k * 6 + k]));
  out.stamp_ns = pose.stamp_ns();
  return out;
}

// A ChainFrame as it arrived; ConsoleState::on_chains checks it (chain_frame_error).
ChainFrameRecord chains_of(const msg::ChainFrame& frame) {
  ChainFrameRecord out;
  out.stamp_ns = frame.stamp_ns();
  out.chains.reserve(frame.chains().size());
  for (const msg::ChainState& in : frame.chains()) {
    ChainRecord chain;
    chain.name = in.name();
    chain.chain_id = in.chain_id();
    chain.status = static_cast<ChainStatus>(in.status());  // an unknown value is checked on receipt
    chain.stamp_ns = in.stamp_ns();
    chain.angles = in.angles();
    for (const msg::ChainMarker& marker : in.markers()) chain.markers.push_back(marker.position());
    chain.marker_valid.assign(in.marker_valid().begin(), in.marker_valid().end());
    chain.tip = in.tip();
    chain.predicted_tip = in.predicted_tip();
    chain.prediction_horizon_ns = in.prediction_horizon_ns();
    chain.grabbing = in.grabbing();
    out.chains.push_back(std::move(chain));
  }
  for (const msg::ChainEvent& in : frame.events())
    out.events.push_back(
        {in.chain(), static_cast<ChainEventKind>(in.kind()), in.stamp_ns(), in.tip(), in.bend()});
  return out;
}

RecorderRecord recorder_of(const msg::RecorderStatus& status) {
  RecorderRecord record{status.recording(), status.path(),           status.topics(), status.messages(),
                        status.bytes(),     status.messages_per_s(), status.error(),  {}};
  for (const msg::Counter& counter : status.counters()) record.rejections[counter.name()] = counter.value();
  return record;
}

}  // namespace

struct BusBridge::Impl {
  static constexpr std::size_t kMaxCameraWriters = 256;

  explicit Impl(dds::Bus& bus_in) : bus(bus_in) {}
  dds::Bus& bus;
  std::unique_ptr<dds::Writer<msg::CameraCommand>> commands;  // for every camera ('*')
  // One command writer per camera seen, in its DDS partition, so that a command for one camera
  // reaches that camera only (docs/security.md, "Camera-scoped permissions"). Created by poll(),
  // never on a DDS listener thread.
  std::mutex camera_mutex;
  std::set<std::string> cameras_seen;
  std::map<std::string, std::unique_ptr<dds::Writer<msg::CameraCommand>>> camera_commands;
  void saw(const std::string& camera) {
    std::lock_guard lock(camera_mutex);
    if (cameras_seen.size() < kMaxCameraWriters) cameras_seen.insert(camera);
  }
  std::unique_ptr<dds::Writer<msg::RecorderCommand>> recorder_commands;
  std::unique_ptr<dds::Reader<msg::RecorderStatus>> recorders;
  std::unique_ptr<dds::Reader<msg::CameraInfo>> info;
  std::unique_ptr<dds::Reader<msg::CameraStatus>> status;
  std::unique_ptr<dds::Reader<msg::FeatureFrame>> features;
  std::unique_ptr<dds::Reader<msg::Predictions>> predictions;
  std::unique_ptr<dds::Reader<msg::CameraPreview>> previews;
  std::unique_ptr<dds::Reader<msg::SystemCalibration>> calibration;
  std::unique_ptr<dds::Reader<msg::EstimatorStatus>> estimator;
  std::unique_ptr<dds::Reader<msg::TrackFrame>> tracks;
  std::unique_ptr<dds::Reader<msg::BodyPose>> bodies;
  std::unique_ptr<dds::Reader<msg::ChainFrame>> chains;
  std::unique_ptr<dds::Reader<msg::MarkerLabels>> labels;
};

// Listener callbacks copy only what the page shows and return: the state's lock is the only wait.
BusBridge::BusBridge(dds::Bus& bus, ConsoleState& state) : impl_(std::make_unique<Impl>(bus)) {
  impl_->commands = bus.make_writer<msg::CameraCommand>();
  Impl* impl = impl_.get();
  impl_->info = bus.make_reader<msg::CameraInfo>([&state, impl](msg::CameraInfo&& info) {
    impl->saw(info.camera_id());
    state.on_info(info.camera_id(), info_of(info), wall_now_ns());
  });
  impl_->status = bus.make_reader<msg::CameraStatus>([&state](msg::CameraStatus&& status) {
    state.on_status(status.camera_id(), status_of(status), wall_now_ns());
  });
  impl_->features = bus.make_reader<msg::FeatureFrame>([&state](msg::FeatureFrame&& frame) {
    FeatureRecord record{frame.frame(), frame.stamp_ns(), {}};
    record.blobs.reserve(frame.blobs().size());
    for (const msg::Blob& blob : frame.blobs()) record.blobs.push_back({blob.x(), blob.y(), blob.area()});
    state.on_features(frame.camera_id(), std::move(record), wall_now_ns());
  });
  impl_->previews = bus.make_reader<msg::CameraPreview>([&state](msg::CameraPreview&& preview) {
    state.on_preview(preview.camera_id(), preview.stamp_ns(), static_cast<int>(preview.width()),
                     static_cast<int>(preview.height()),
                     std::string(preview.pixels().begin(), preview.pixels().end()));
  });
  impl_->predictions = bus.make_reader<msg::Predictions>([&state](msg::Predictions&& predictions) {
    std::vector<PredictedWindowRecord> windows;
    windows.reserve(predictions.windows().size());
    for (const msg::PredictedWindow& window : predictions.windows())
      windows.push_back({window.x(), window.y(), window.half_width(), window.half_height()});
    state.on_predictions(predictions.camera_id(), std::move(windows), wall_now_ns());
  });
  impl_->calibration =
      bus.make_reader<msg::SystemCalibration>([&state](msg::SystemCalibration&& calibration) {
        std::map<std::string, CameraGeometry> cameras;
        for (const msg::CameraCalibration& camera : calibration.cameras()) {
          CameraGeometry geometry;
          geometry.width = static_cast<int>(camera.width());
          geometry.height = static_cast<int>(camera.height());
          std::copy(camera.K().begin(), camera.K().end(), geometry.K.begin());
          geometry.has_pose = camera.has_pose();
          geometry.T_world_cam = pose_of(camera.T_world_cam());
          cameras[camera.camera_id()] = geometry;
        }
        state.on_calibration(cameras);
      });
  impl_->estimator = bus.make_reader<msg::EstimatorStatus>(
      [&state](msg::EstimatorStatus&& status) { state.on_estimator(estimator_of(status), wall_now_ns()); });
  impl_->tracks = bus.make_reader<msg::TrackFrame>([&state](msg::TrackFrame&& frame) {
    std::vector<TrackPoint> tracks;
    tracks.reserve(frame.tracks().size());
    for (const msg::Track& track : frame.tracks()) tracks.push_back(track_of(track));
    state.on_tracks(std::move(tracks), wall_now_ns());
  });
  impl_->bodies = bus.make_reader<msg::BodyPose>(
      [&state](msg::BodyPose&& pose) { state.on_body(body_of(pose), wall_now_ns()); });
  impl_->chains = bus.make_reader<msg::ChainFrame>(
      [&state](msg::ChainFrame&& frame) { state.on_chains(chains_of(frame), wall_now_ns()); });
  impl_->labels = bus.make_reader<msg::MarkerLabels>([&state](msg::MarkerLabels&& message) {
    std::vector<SubjectLabelsRecord> subjects;
    for (const msg::SubjectLabels& subject : message.subjects()) {
      SubjectLabelsRecord record;
      record.name = subject.name();
      for (const msg::LabelStick& stick : subject.sticks())
        record.sticks.push_back({stick.from(), stick.to()});
      for (const msg::TrackLabel& label : subject.labels()) record.names[label.track_id()] = label.marker();
      subjects.push_back(std::move(record));
    }
    state.on_labels(std::move(subjects));
  });
  impl_->recorder_commands = bus.make_writer<msg::RecorderCommand>();
  impl_->recorders = bus.make_reader<msg::RecorderStatus>([&state](msg::RecorderStatus&& status) {
    state.on_recorder_status(status.recorder_id(), recorder_of(status), wall_now_ns());
  });
}

BusBridge::~BusBridge() = default;

void BusBridge::poll() {
  // The writers are made without camera_mutex held: a DDS listener thread takes that lock (saw())
  // while Fast DDS holds its own locks, and making a writer takes Fast DDS's locks, so holding
  // camera_mutex here can deadlock this thread with the listener (issue 37: the console's watcher
  // thread stopped as six cameras appeared, and the calibration page froze).
  std::vector<std::string> wanted;
  {
    std::lock_guard lock(impl_->camera_mutex);
    for (const std::string& camera : impl_->cameras_seen)
      if (impl_->camera_commands.count(camera) == 0) wanted.push_back(camera);
  }
  for (const std::string& camera : wanted) {
    std::unique_ptr<dds::Writer<msg::CameraCommand>> writer;
    try {
      writer = impl_->bus.make_writer<msg::CameraCommand>(dds::Qos::kDefault, {}, camera);
    } catch (const dds::DdsInputError&) {
      // An id that cannot name a partition: its commands go out through the writer for every camera.
    } catch (const dds::DdsError&) {
      // Nor for a writer DDS refused.
    }
    std::lock_guard lock(impl_->camera_mutex);
    impl_->camera_commands.emplace(camera, std::move(writer));
  }
}

bool BusBridge::send(const CameraCommandRequest& command) {
  msg::CameraCommand message;
  message.target(command.camera);
  message.seq(static_cast<unsigned long long>(wall_now_ns()));
  message.command(command.command);
  message.arguments(command.arguments);
  {
    // The camera's own writer once it matched the camera; before, the one for every camera.
    std::lock_guard lock(impl_->camera_mutex);
    const auto writer = impl_->camera_commands.find(command.camera);
    if (writer != impl_->camera_commands.end() && writer->second && writer->second->matched_readers() > 0)
      return writer->second->write(message);
  }
  if (impl_->commands->matched_readers() == 0) return false;
  return impl_->commands->write(message);
}

bool BusBridge::send(const RecorderCommandRequest& command) {
  if (impl_->recorder_commands->matched_readers() == 0) return false;
  msg::RecorderCommand message;
  message.target(command.recorder);
  message.seq(static_cast<unsigned long long>(wall_now_ns()));
  message.command(command.command);
  message.path(command.path);
  return impl_->recorder_commands->write(message);
}

}  // namespace panoptes::console
