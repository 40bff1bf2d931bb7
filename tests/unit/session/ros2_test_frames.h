// SPDX-License-Identifier: Apache-2.0
// What the tests of estimator_node's ROS 2 topics share: a frame to publish and a bus on the test
// process's own DDS domain.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>

#include "../dds_test_support.h"
#include "panoptes/dds/bus.h"
#include "panoptes/session/frame_output.h"

namespace panoptes::estimator_app {

// Two bodies and three tracks: "head" tracked with two labelled markers, "tool" not tracked, one
// unlabelled track.
inline session::FrameOutput test_frame(std::uint64_t frame_number, TimeNs stamp_ns) {
  session::FrameOutput frame;
  frame.frame_number = frame_number;
  frame.stamp_ns = stamp_ns;
  session::BodyOutput head;
  head.name = "head";
  head.id = 1;
  head.tracking_valid = true;
  head.pose.stamp_ns = stamp_ns;
  head.pose.body = "head";
  head.pose.p = {0.5, -1.25, 1.75};
  head.pose.q = {0.1, 0.2, 0.3, std::sqrt(1.0 - 0.14)};
  head.pose.v = {1.0, 2.0, 3.0};
  head.pose.w = {-0.1, -0.2, -0.3};
  frame.bodies.push_back(head);
  session::BodyOutput tool;
  tool.name = "tool";
  tool.id = 2;
  tool.pose.stamp_ns = stamp_ns;
  frame.bodies.push_back(tool);
  for (int marker = 0; marker < 2; ++marker) {
    session::MarkerOutput m;
    m.track.id = 10 + marker;
    m.track.p = {0.5 + 0.1 * marker, -1.25, 1.75};
    m.body = "head";
    m.body_marker = marker == 0 ? 3 : 0;
    frame.markers.push_back(m);
  }
  session::MarkerOutput loose;
  loose.track.id = 77;
  loose.track.p = {2.0, 2.5, 0.25};
  frame.markers.push_back(loose);
  return frame;
}

inline dds::BusOptions bus_options(const std::string& name) {
  dds::BusOptions o;
  o.domain_id = panoptes::test::dds_test_domain();  // one domain per test process
  o.participant_name = name;
  return o;
}

}  // namespace panoptes::estimator_app
