// SPDX-License-Identifier: Apache-2.0
#include "panoptes/camera_app/dds_feature_sink.h"

#include <utility>

#include "panoptes/dds/convert.h"

namespace panoptes::camera_app {

DdsFeatureSink::DdsFeatureSink(const camera::StampCorrection& stamps, dds::Writer<msg::FeatureFrame>& writer,
                               JsonlWriter* out, const camera::NodeLog& log)
    : stamps_(stamps), writer_(writer), out_(out), hold_(stamps.sync(), log) {}

void DdsFeatureSink::add(FeatureFrame&& frame) {
  hold_.add(std::move(frame), wall_now_ns(),
            [this](const FeatureFrame& held, const ClockEstimate* estimate) { publish(held, estimate); });
}

void DdsFeatureSink::poll() {
  hold_.release(false, wall_now_ns(),
                [this](const FeatureFrame& held, const ClockEstimate* estimate) { publish(held, estimate); });
  send_due();
}

void DdsFeatureSink::finish() {
  hold_.release(true, wall_now_ns(),
                [this](const FeatureFrame& held, const ClockEstimate* estimate) { publish(held, estimate); });
}

void DdsFeatureSink::publish(const FeatureFrame& frame, const ClockEstimate* estimate) {
  auto message = dds::to_message(frame);
  const TimeNs now = stamps_.clock().now();
  message.publish_ns(estimate != nullptr ? estimate->to_server(now) : now);
  send(std::move(message));
  if (out_ != nullptr) out_->write(frame);
}

void DdsFeatureSink::send(msg::FeatureFrame message) {
  if (!faults_.active()) {
    write(message);
    return;
  }
  const std::optional<TimeNs> delay = faults_.next_delay();
  if (!delay) return;  // an injected loss
  if (!faults_.jitters()) {
    write(message);
    return;
  }
  delayed_.push(wall_now_ns() + *delay, std::move(message));
  send_due();
}

void DdsFeatureSink::send_due() {
  delayed_.send_due(wall_now_ns(), [this](const msg::FeatureFrame& message) { write(message); });
}

void DdsFeatureSink::write(const msg::FeatureFrame& message) {
  writer_.write(message);
  if (probe_ != nullptr) probe_->send(message, stamps_.to_common(stamps_.clock().now()));
}

}  // namespace panoptes::camera_app
