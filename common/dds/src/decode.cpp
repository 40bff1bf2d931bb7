// SPDX-License-Identifier: Apache-2.0
#include "panoptes/dds/decode.h"

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastcdr/exceptions/BadParamException.h>
#include <fastcdr/exceptions/NotEnoughMemoryException.h>

#include <new>
#include <stdexcept>

#include "panoptes_msgs/chains.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/ros2.h"
#include "panoptes_msgs/surface.h"

namespace panoptes::dds {

namespace {

constexpr std::size_t kEncapsulationBytes = 4;

// The types whose first member is a string (a camera, client or body id, a command's target).
template <class T>
constexpr bool kLeadingString = false;
template <>
constexpr bool kLeadingString<msg::CameraInfo> = true;
template <>
constexpr bool kLeadingString<msg::FeatureFrame> = true;
template <>
constexpr bool kLeadingString<msg::CameraStatus> = true;
template <>
constexpr bool kLeadingString<msg::CameraCommand> = true;
template <>
constexpr bool kLeadingString<msg::CameraPreview> = true;
template <>
constexpr bool kLeadingString<msg::Predictions> = true;
template <>
constexpr bool kLeadingString<msg::TimeSync> = true;
template <>
constexpr bool kLeadingString<msg::BodyPose> = true;
template <>
constexpr bool kLeadingString<msg::LatencyProbe> = true;
template <>
constexpr bool kLeadingString<msg::RecorderCommand> = true;
template <>
constexpr bool kLeadingString<msg::RecorderStatus> = true;

// True if the first string of a sample that decoded ends with its NUL. The padding after a string
// can absorb a missing NUL, so the size check of decode_sample does not see every one; this one
// sees it for the id that names the sender or addressee.
bool leading_string_terminated(const std::uint8_t* data, std::size_t size) {
  const bool little_endian = (data[1] & 1) != 0;
  std::uint32_t length = 0;
  for (int i = 0; i < 4; ++i) {
    const std::uint32_t byte = data[kEncapsulationBytes + (little_endian ? i : 3 - i)];
    length |= byte << (8 * i);
  }
  const std::size_t last = 2 * kEncapsulationBytes + length - 1;
  return length == 0 || (last < size && data[last] == 0);
}

}  // namespace

std::string_view decode_error_name(DecodeError error) {
  switch (error) {
    case DecodeError::kNone:
      return "";
    case DecodeError::kTruncated:
      return "cdr_truncated";
    case DecodeError::kBadEncapsulation:
      return "cdr_bad_encapsulation";
    case DecodeError::kUnterminatedString:
      return "cdr_unterminated_string";
    case DecodeError::kOutOfMemory:
      return "cdr_out_of_memory";
    case DecodeError::kOther:
      break;
  }
  return "cdr_error";
}

template <class T>
DecodeError decode_sample(const std::uint8_t* data, std::size_t size, T& message) {
  if (data == nullptr || size < kEncapsulationBytes) return DecodeError::kTruncated;
  // Fast CDR reads through a non-const pointer but does not write when deserialising.
  eprosima::fastcdr::FastBuffer buffer(const_cast<char*>(reinterpret_cast<const char*>(data)), size);
  eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
  try {
    cdr.read_encapsulation();
    message.deserialize(cdr);
  } catch (const eprosima::fastcdr::exception::NotEnoughMemoryException&) {
    return DecodeError::kTruncated;
  } catch (const eprosima::fastcdr::exception::BadParamException&) {
    return DecodeError::kBadEncapsulation;
  } catch (const std::bad_alloc&) {
    return DecodeError::kOutOfMemory;
  } catch (const std::length_error&) {
    return DecodeError::kOutOfMemory;
  } catch (...) {
    return DecodeError::kOther;
  }
  // Fast CDR accepts a string without its NUL; every other field takes at least its canonical size.
  if (T::getCdrSerializedSize(message) + kEncapsulationBytes > size) return DecodeError::kUnterminatedString;
  if constexpr (kLeadingString<T>) {
    if (!leading_string_terminated(data, size)) return DecodeError::kUnterminatedString;
  }
  return DecodeError::kNone;
}

template <class T>
std::vector<std::uint8_t> encode_sample(const T& message) {
  eprosima::fastcdr::FastBuffer buffer;  // grows as needed
  eprosima::fastcdr::Cdr cdr(buffer, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
  cdr.serialize_encapsulation();
  message.serialize(cdr);
  const auto* begin = reinterpret_cast<const std::uint8_t*>(buffer.getBuffer());
  return {begin, begin + cdr.getSerializedDataLength()};
}

void ReceiveCounters::note(std::string_view reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = counts_.find(reason); it != counts_.end()) {
    ++it->second;
  } else {
    counts_.emplace(std::string(reason), 1);
  }
}

std::map<std::string, std::uint64_t> ReceiveCounters::snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {counts_.begin(), counts_.end()};
}

// NOLINTBEGIN(bugprone-macro-parentheses): a type argument of a template cannot be parenthesised
#define PANOPTES_DECODE(Type)                                                        \
  template DecodeError decode_sample<Type>(const std::uint8_t*, std::size_t, Type&); \
  template std::vector<std::uint8_t> encode_sample<Type>(const Type&);
PANOPTES_DECODE(msg::CameraInfo)
PANOPTES_DECODE(msg::FeatureFrame)
PANOPTES_DECODE(msg::CameraStatus)
PANOPTES_DECODE(msg::CameraCommand)
PANOPTES_DECODE(msg::CameraPreview)
PANOPTES_DECODE(msg::Predictions)
PANOPTES_DECODE(msg::TimeSync)
PANOPTES_DECODE(msg::EstimatorStatus)
PANOPTES_DECODE(msg::TrackFrame)
PANOPTES_DECODE(msg::BodyPose)
PANOPTES_DECODE(msg::SystemCalibration)
PANOPTES_DECODE(msg::LatencyProbe)
PANOPTES_DECODE(msg::LatencyProbeEcho)
PANOPTES_DECODE(msg::LatencyTraces)
PANOPTES_DECODE(msg::MocapFrame)
PANOPTES_DECODE(msg::BodyDescriptions)
PANOPTES_DECODE(msg::MarkerLabels)
PANOPTES_DECODE(msg::RecorderCommand)
PANOPTES_DECODE(msg::RecorderStatus)
PANOPTES_DECODE(msg::StrokeEvents)
PANOPTES_DECODE(msg::ChainFrame)
PANOPTES_DECODE(geometry_msgs::msg::dds_::PoseStamped_)
PANOPTES_DECODE(geometry_msgs::msg::dds_::TwistStamped_)
PANOPTES_DECODE(tf2_msgs::msg::dds_::TFMessage_)
PANOPTES_DECODE(mocap4r2_msgs::msg::dds_::RigidBodies_)
PANOPTES_DECODE(mocap4r2_msgs::msg::dds_::Markers_)
#undef PANOPTES_DECODE
// NOLINTEND(bugprone-macro-parentheses)

}  // namespace panoptes::dds
