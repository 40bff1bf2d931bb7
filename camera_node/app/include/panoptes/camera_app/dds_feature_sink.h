// SPDX-License-Identifier: Apache-2.0
// The live feature sink: holds frames until the clock is synchronised (camera::SyncHold), moves
// their stamps to the common time base, optionally injects loss and jitter, and writes them on
// rt/panoptes/features (and to --out-features), each followed by a latency probe when asked.
#pragma once

#include "panoptes/camera/fault_injection.h"
#include "panoptes/camera/node_clock.h"
#include "panoptes/camera/pipeline.h"
#include "panoptes/camera/sync_hold.h"
#include "panoptes/camera_app/latency_probe_sender.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/time_sync.h"
#include "panoptes/jsonl.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::camera_app {

// The time-sync client seen through the camera library's ClockSyncView.
class TimeSyncClockView final : public camera::ClockSyncView {
 public:
  explicit TimeSyncClockView(const dds::TimeSyncClient& client) : client_(client) {}
  bool synchronised() const override { return client_.synchronised(); }
  ClockEstimate estimate() const override { return client_.estimate(); }
  std::optional<TimeNs> to_server(TimeNs local_ns) const override { return client_.to_server(local_ns); }

 private:
  const dds::TimeSyncClient& client_;
};

class DdsFeatureSink final : public camera::FeatureSink {
 public:
  // `out` (may be null) also receives every frame published, stamps on the common time base.
  DdsFeatureSink(const camera::StampCorrection& stamps, dds::Writer<msg::FeatureFrame>& writer,
                 JsonlWriter* out, const camera::NodeLog& log);

  void set_hold_deadline(TimeNs hold_until_wall_ns) { hold_.set_deadline(hold_until_wall_ns); }
  void inject_faults(const camera::FaultInjector& faults) { faults_ = faults; }
  void enable_latency_probe(LatencyProbeSender* probe) { probe_ = probe; }

  void add(FeatureFrame&& frame) override;
  // Publishes what the hold released and the delayed frames whose time has come.
  void poll() override;
  void finish() override;

  const camera::SyncHold& hold() const { return hold_; }
  std::uint64_t injected_losses() const { return faults_.injected_losses(); }

 private:
  void publish(const FeatureFrame& frame, const ClockEstimate* estimate);
  void send(msg::FeatureFrame message);
  void send_due();
  void write(const msg::FeatureFrame& message);

  const camera::StampCorrection& stamps_;
  dds::Writer<msg::FeatureFrame>& writer_;
  JsonlWriter* out_;
  camera::SyncHold hold_;
  camera::FaultInjector faults_;
  camera::DelayLine<msg::FeatureFrame> delayed_;
  LatencyProbeSender* probe_ = nullptr;
};

}  // namespace panoptes::camera_app
