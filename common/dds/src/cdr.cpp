// SPDX-License-Identifier: Apache-2.0
#include "panoptes/dds/cdr.h"

#include <cstring>
#include <exception>

#include "panoptes/dds/decode.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/panoptesPubSubTypes.h"

namespace panoptes::dds {

bool decode_cdr(std::span<const std::uint8_t> cdr, msg::FeatureFrame& out) {
  return decode_sample(cdr.data(), cdr.size(), out) == DecodeError::kNone;
}

bool decode_cdr(std::span<const std::uint8_t> cdr, msg::CameraInfo& out) {
  return decode_sample(cdr.data(), cdr.size(), out) == DecodeError::kNone;
}

bool shift_feature_frame_times(std::vector<std::uint8_t>& cdr, std::int64_t offset_ns) {
  msg::FeatureFrame frame;
  if (!decode_cdr(cdr, frame)) return false;
  frame.stamp_ns(frame.stamp_ns() + offset_ns);
  if (frame.arrival_ns() != 0) frame.arrival_ns(frame.arrival_ns() + offset_ns);
  if (frame.publish_ns() != 0) frame.publish_ns(frame.publish_ns() + offset_ns);
  cdr = encode_cdr(frame);
  return !cdr.empty();
}

std::vector<std::uint8_t> encode_cdr(const msg::FeatureFrame& frame) {
  msg::FeatureFramePubSubType type;
  auto& sample = const_cast<msg::FeatureFrame&>(frame);  // serialize() takes void*; it only reads
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&sample)());
  if (!type.serialize(&sample, &payload)) return {};
  return {payload.data, payload.data + payload.length};
}

}  // namespace panoptes::dds
