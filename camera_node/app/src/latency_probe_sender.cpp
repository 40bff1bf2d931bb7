// SPDX-License-Identifier: Apache-2.0
#include "panoptes/camera_app/latency_probe_sender.h"

namespace panoptes::camera_app {

LatencyProbeSender::LatencyProbeSender(dds::Bus& bus) : writer_(bus.make_writer<msg::LatencyProbe>()) {}

void LatencyProbeSender::send(const msg::FeatureFrame& frame, TimeNs now_ns) {
  probe_.camera_id(frame.camera_id());
  probe_.frame(frame.frame());
  probe_.arrival_ns(frame.arrival_ns());
  probe_.processing_ns(frame.processing_ns());
  probe_.feature_publish_ns(frame.publish_ns());
  probe_.padding().clear();
  // The padding is last: each octet adds exactly one byte.
  const std::size_t size = msg::FeatureFrame::getCdrSerializedSize(frame);
  const std::size_t bare = msg::LatencyProbe::getCdrSerializedSize(probe_);
  probe_.padding().resize(size > bare ? size - bare : 0);
  probe_.publish_ns(now_ns);
  writer_->write(probe_);
}

}  // namespace panoptes::camera_app
