// SPDX-License-Identifier: Apache-2.0
#include "panoptes/dds/cdr.h"

#include <cstring>
#include <exception>

#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/panoptesPubSubTypes.h"

namespace panoptes::dds {

namespace {

template <class PubSubType, class T>
bool decode_with(std::span<const std::uint8_t> cdr, T& out) {
  if (cdr.size() < 4 || cdr.size() > UINT32_MAX) return false;
  try {
    eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(cdr.size()));
    std::memcpy(payload.data, cdr.data(), cdr.size());
    payload.length = static_cast<std::uint32_t>(cdr.size());
    PubSubType type;
    return type.deserialize(&payload, &out);
  } catch (const std::exception&) {  // a corrupted length asking for more memory than exists
    return false;
  }
}

}  // namespace

bool decode_cdr(std::span<const std::uint8_t> cdr, msg::FeatureFrame& out) {
  return decode_with<msg::FeatureFramePubSubType>(cdr, out);
}

bool decode_cdr(std::span<const std::uint8_t> cdr, msg::CameraInfo& out) {
  return decode_with<msg::CameraInfoPubSubType>(cdr, out);
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
