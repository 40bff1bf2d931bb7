// SPDX-License-Identifier: Apache-2.0
// Decoding a serialized sample (CDR as on the wire, encapsulation header included) without a bus:
// what reading a recording offline needs (estimator_node --in-recording).
#pragma once

#include <cstdint>
#include <span>
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

}  // namespace panoptes::dds
