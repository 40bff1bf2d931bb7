// SPDX-License-Identifier: Apache-2.0
// camera_node's live mode: the camera pipeline wired to DDS. Publishes rt/panoptes/features,
// camera_info (once), camera_status (1 Hz) and camera_preview (on request); reads camera_command
// and this camera's predictions; synchronises the node's clock with the estimator's time service
// (docs/camera_node.md). Entities are created in the constructor; run() returns when the source
// ends, the duration has passed, a signal came or stop() was called.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "panoptes/camera/detector.h"
#include "panoptes/camera/mailbox.h"
#include "panoptes/camera/node_clock.h"
#include "panoptes/camera/node_log.h"
#include "panoptes/camera/pipeline.h"
#include "panoptes/camera/sources.h"
#include "panoptes/camera_app/dds_feature_sink.h"
#include "panoptes/camera_app/latency_probe_sender.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/decode.h"
#include "panoptes/dds/time_sync.h"
#include "panoptes/jsonl.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::camera_app {

struct LiveOptions {
  std::string source_spec;  // --source: a sim camera's scene clock offset is part of the node clock
  std::string dds_profile;
  dds::SecurityOptions security;  // DDS Security files (docs/security.md)
  std::string out_features;       // also write every published frame here ("" = no)
  std::size_t queue_capacity = 4;
  double prediction_max_age_ms = 50;
  double duration_s = 0;
  bool quiet = false;
  bool no_clock_sync = false;
  double clock_sync_wait_s = 2.0;
  camera::ClockSkew clock_skew;
  double inject_loss = 0;
  double inject_jitter_ms = 0;
  bool latency_probe = false;
};

// Whether the node runs the software clock synchronisation: not with --no-clock-sync, and not for
// a PTP-timed camera, whose stamps are already on the common time base (docs/camera_node.md,
// "PTP and hardware triggers").
bool uses_clock_sync(const LiveOptions& options, const camera::SourceInfo& info);

class LiveCamera final : public camera::PipelineObserver {
 public:
  // Throws dds::DdsError if DDS cannot start, ConfigError for a bad scene file.
  LiveCamera(LiveOptions options, camera::FrameSource& source, camera::Detector& detector,
             std::string camera_id, const camera::NodeLog& log);
  ~LiveCamera() override;
  LiveCamera(const LiveCamera&) = delete;
  LiveCamera& operator=(const LiveCamera&) = delete;

  // Runs the pipeline, then logs the summary. Returns the exit code.
  int run();
  void stop() { pipeline_.stop(); }

  void on_start(TimeNs start_wall_ns) override;
  void on_pass(TimeNs wall_now_ns) override;
  void on_preview(const Image& preview, TimeNs stamp_ns) override;

 private:
  void publish_camera_info();
  void publish_status(TimeNs wall_now_ns);
  void log_summary();

  const LiveOptions options_;
  camera::FrameSource& source_;
  camera::Detector& detector_;
  const std::string camera_id_;
  const camera::NodeLog& log_;

  const camera::NodeClock clock_;
  dds::Bus bus_;
  std::unique_ptr<dds::TimeSyncClient> time_sync_;  // null with --no-clock-sync
  std::unique_ptr<TimeSyncClockView> sync_view_;
  const camera::StampCorrection stamps_;
  std::unique_ptr<dds::Writer<msg::CameraInfo>> info_writer_;
  std::unique_ptr<dds::Writer<msg::FeatureFrame>> feature_writer_;
  std::unique_ptr<dds::Writer<msg::CameraStatus>> status_writer_;
  std::unique_ptr<dds::Writer<msg::CameraPreview>> preview_writer_;
  camera::Mailbox<camera::Command> commands_;
  camera::PredictionBox predictions_;
  dds::ReceiveCounters rejections_;  // decoded samples dropped by this node, by reason
  std::unique_ptr<dds::Reader<msg::CameraCommand>> command_reader_;
  std::unique_ptr<dds::Reader<msg::Predictions>> prediction_reader_;
  std::unique_ptr<JsonlWriter> out_;  // --out-features
  DdsFeatureSink sink_;
  std::optional<LatencyProbeSender> latency_probe_;
  camera::CameraPipeline pipeline_;

  TimeNs start_ = 0;
  TimeNs next_status_ = 0;
  std::uint64_t frames_at_status_ = 0;
  bool logged_synchronised_ = false;
};

}  // namespace panoptes::camera_app
