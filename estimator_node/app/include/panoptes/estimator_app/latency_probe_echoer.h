// SPDX-License-Identifier: Apache-2.0
// LatencyProbeEchoer: the estimator side of --latency-probe (bench_latency).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "panoptes/dds/bus.h"
#include "panoptes/records.h"
#include "panoptes/time.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::estimator_app {

// --latency-probe (tests/bench/bench_latency.cpp; docs/protocol.md, "Latency probes"). Echoes each
// LatencyProbe of camera_node --latency-probe at once, as a message of a BodyPose's serialized
// size, and traces when each processed frame arrived and when its output was written.
// The echo is written from the DDS listener thread that received the probe, not handed to the
// estimator thread: that hand-over (inbox, wake-up) is part of what the benchmark measures against
// the raw DDS floor, so the floor must not include it. Probes and feature frames reach this
// process on the same receive thread, so the probe after a frame is echoed once that frame is in
// the inbox, while the estimator thread works on it: both see the same contention.
class LatencyProbeEchoer {
 public:
  explicit LatencyProbeEchoer(panoptes::dds::Bus& bus)
      : echo_writer_(bus.make_writer<panoptes::msg::LatencyProbeEcho>()),
        trace_writer_(bus.make_writer<panoptes::msg::LatencyTraces>()),
        pose_size_(panoptes::msg::BodyPose::getCdrSerializedSize(panoptes::msg::BodyPose())),
        probe_reader_(bus.make_reader<panoptes::msg::LatencyProbe>(
            [this](panoptes::msg::LatencyProbe&& probe) { echo(std::move(probe)); })) {}

  // Estimator thread: echoes take the size of the BodyPose last written.
  void note_pose(const panoptes::msg::BodyPose& pose) {
    pose_size_.store(panoptes::msg::BodyPose::getCdrSerializedSize(pose), std::memory_order_relaxed);
  }

  // When the estimator thread took a frame, had updated the tracker with it and wrote its poses.
  struct Stamps {
    TimeNs dequeued_ns = 0;
    TimeNs updated_ns = 0;
    TimeNs poses_published_ns = 0;
    TimeNs pose_stamp_ns = 0;
    std::uint32_t poses = 0;
  };

  // Estimator thread, once everything `frame` caused was written. Sent in batches by flush().
  void trace(const panoptes::FeatureFrame& frame, const Stamps& stamps, TimeNs tracks_published_ns) {
    panoptes::msg::LatencyTrace trace;
    trace.camera_id(frame.camera_id);
    trace.frame(frame.frame);
    trace.stamp_ns(frame.stamp_ns);
    trace.arrival_ns(frame.arrival_ns);
    trace.processing_ns(frame.processing_ns);
    trace.received_ns(frame.received_ns);
    trace.dequeued_ns(stamps.dequeued_ns);
    trace.updated_ns(stamps.updated_ns);
    trace.poses_published_ns(stamps.poses_published_ns);
    trace.pose_stamp_ns(stamps.pose_stamp_ns);
    trace.poses(stamps.poses);
    trace.tracks_published_ns(tracks_published_ns);
    traces_.frames().push_back(std::move(trace));
  }

  // Estimator thread, when it has nothing more urgent to do: sends the traces every 20 ms (or all,
  // with `force`).
  void flush(TimeNs now_ns, bool force) {
    if (traces_.frames().empty() || (!force && now_ns - flushed_ns_ < kFlushPeriodNs)) return;
    trace_writer_->write(traces_);
    traces_.frames().clear();
    flushed_ns_ = now_ns;
  }

 private:
  // Listener thread (one at a time: the reader's listener is serialised).
  void echo(panoptes::msg::LatencyProbe&& probe) {
    const TimeNs received_ns = panoptes::wall_now_ns();
    echo_.probe(std::move(probe));
    echo_.probe().padding().clear();
    echo_.received_ns(received_ns);
    echo_.padding().clear();
    const std::size_t size = pose_size_.load(std::memory_order_relaxed);
    const std::size_t bare = panoptes::msg::LatencyProbeEcho::getCdrSerializedSize(echo_);
    echo_.padding().resize(size > bare ? size - bare : 0);  // last member: one byte per octet
    echo_.publish_ns(panoptes::wall_now_ns());
    echo_writer_->write(echo_);
  }

  static constexpr TimeNs kFlushPeriodNs = 20'000'000;

  std::unique_ptr<panoptes::dds::Writer<panoptes::msg::LatencyProbeEcho>> echo_writer_;
  std::unique_ptr<panoptes::dds::Writer<panoptes::msg::LatencyTraces>> trace_writer_;
  std::atomic<std::size_t> pose_size_;
  panoptes::msg::LatencyProbeEcho echo_;  // listener thread
  panoptes::msg::LatencyTraces traces_;   // estimator thread
  TimeNs flushed_ns_ = 0;
  // Last: destroyed first, so no echo runs while the rest goes.
  std::unique_ptr<panoptes::dds::Reader<panoptes::msg::LatencyProbe>> probe_reader_;
};

}  // namespace panoptes::estimator_app
