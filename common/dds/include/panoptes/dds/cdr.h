// SPDX-License-Identifier: Apache-2.0
// Decoding a serialized sample (CDR as on the wire, encapsulation header included) without a bus:
// what reading a recording offline needs (estimator_node --in-recording).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "panoptes_msgs/panoptes.h"

namespace panoptes::dds {

// True and `out` filled if `cdr` decodes; false for malformed data (never throws).
bool decode_cdr(std::span<const std::uint8_t> cdr, msg::FeatureFrame& out);
bool decode_cdr(std::span<const std::uint8_t> cdr, msg::CameraInfo& out);
// The CDR of a FeatureFrame as a writer sends it (encapsulation header included).
std::vector<std::uint8_t> encode_cdr(const msg::FeatureFrame& frame);

// Moves a serialized FeatureFrame's times (stamp_ns, arrival_ns, publish_ns) by `offset_ns`, so a
// replayed frame carries times of the live clock (panoptes_replay). False if it does not decode.
bool shift_feature_frame_times(std::vector<std::uint8_t>& cdr, std::int64_t offset_ns);

// Moves every absolute time of a serialized sample of the recorded Panoptes topic `topic` (DDS name,
// "rt/panoptes/frames") by `offset_ns`, so that a whole replayed session carries times of the live
// clock consistently: stamps, publish times, MocapFrame's stage times, EstimatorStatus's cameras'
// last stamps, TimeSync's t1..t3. Durations (processing, prediction horizons, latencies, clock
// offsets) are unchanged, and so is a time of 0 ("unknown"), except FeatureFrame.stamp_ns. True for
// a topic without times (the sample unchanged); false if the sample does not decode.
bool shift_sample_times(const std::string& topic, std::vector<std::uint8_t>& cdr, std::int64_t offset_ns);

}  // namespace panoptes::dds
