// SPDX-License-Identifier: Apache-2.0
// --latency-probe (tests/bench/bench_latency.cpp): right after each FeatureFrame, a LatencyProbe of
// the same serialized size, which estimator_node --latency-probe echoes at once. The bench so
// measures the raw DDS hops through the pipeline's own processes, under the same load, beside the
// pipeline (docs/protocol.md, "Latency probes").
#pragma once

#include <memory>

#include "panoptes/dds/bus.h"
#include "panoptes/time.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::camera_app {

class LatencyProbeSender {
 public:
  explicit LatencyProbeSender(dds::Bus& bus);
  // `frame` was written just now; `now_ns` is on the common time base.
  void send(const msg::FeatureFrame& frame, TimeNs now_ns);

 private:
  std::unique_ptr<dds::Writer<msg::LatencyProbe>> writer_;
  msg::LatencyProbe probe_;  // reused: no allocation per frame once the padding has grown
};

}  // namespace panoptes::camera_app
