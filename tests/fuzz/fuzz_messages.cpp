// SPDX-License-Identifier: Apache-2.0
// libFuzzer target (docs/hostile_input.md, "Fuzzing"): every conversion a node applies to a
// received sample, from the bytes on the wire on. The first byte picks the message type, the rest
// is its CDR payload (encapsulation header included). Each input goes through decode_sample (what
// every Bus reader runs) and, if it decodes, through the from_message-style conversion and the
// check that follows it in the node: FeatureFrame -> from_message -> FrameScreen, TrackFrame ->
// from_message per track, BodyPose -> from_message, CameraInfo -> camera_info_problem and
// calibration_from, MocapFrame -> the client library's to_frame, BodyDescriptions -> its
// to_descriptions, StrokeEvents -> its to_strokes, ChainFrame -> its to_chain_update. Any crash, sanitizer
// report or leak is a finding.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "conversion.h"  // the client library's (common/client/src)
#include "panoptes/dds/convert.h"
#include "panoptes/dds/decode.h"
#include "panoptes/estimator/frame_screen.h"
#include "panoptes_msgs/chains.h"
#include "panoptes_msgs/panoptes.h"

namespace {

namespace dds = panoptes::dds;
namespace msg = panoptes::msg;

template <class T>
bool decode(const std::uint8_t* data, std::size_t size, T& message) {
  return dds::decode_sample(data, size, message) == dds::DecodeError::kNone;
}

void feature_frame(const std::uint8_t* data, std::size_t size) {
  msg::FeatureFrame message;
  if (!decode(data, size, message)) return;
  panoptes::FeatureFrame frame = dds::from_message(message);
  panoptes::estimator::FrameScreen screen;
  constexpr panoptes::TimeNs kWallNs = 1'800'000'000'000'000'000;  // 2027: a plausible wall clock
  screen.screen_live(frame, kWallNs);
  screen.screen(frame, frame.stamp_ns);
}

void track_frame(const std::uint8_t* data, std::size_t size) {
  msg::TrackFrame message;
  if (!decode(data, size, message)) return;
  for (const msg::Track& track : message.tracks()) (void)dds::from_message(track, message.stamp_ns());
}

void body_pose(const std::uint8_t* data, std::size_t size) {
  msg::BodyPose message;
  if (decode(data, size, message)) (void)dds::from_message(message);
}

void camera_info(const std::uint8_t* data, std::size_t size) {
  msg::CameraInfo message;
  if (!decode(data, size, message)) return;
  (void)dds::camera_info_problem(message);
  (void)dds::calibration_from(message);
}

void mocap_frame(const std::uint8_t* data, std::size_t size) {
  msg::MocapFrame message;
  if (!decode(data, size, message)) return;
  std::string error;
  (void)panoptes::client::detail::to_frame(message, 0, error);
  (void)panoptes::client::detail::latency_of(message, 0);
}

void body_descriptions(const std::uint8_t* data, std::size_t size) {
  msg::BodyDescriptions message;
  std::string error;
  if (decode(data, size, message)) (void)panoptes::client::detail::to_descriptions(message, error);
}

void stroke_events(const std::uint8_t* data, std::size_t size) {
  msg::StrokeEvents message;
  std::string error;
  if (decode(data, size, message)) (void)panoptes::client::detail::to_strokes(message, 0, error);
}

void chain_frame(const std::uint8_t* data, std::size_t size) {
  msg::ChainFrame message;
  std::string error;
  if (decode(data, size, message)) (void)panoptes::client::detail::to_chain_update(message, 0, error);
}

// The other types a node reads: decoding is all that happens before the node's own checks.
template <class T>
void decode_only(const std::uint8_t* data, std::size_t size) {
  T message;
  (void)decode(data, size, message);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::uint8_t* payload = data + 1;
  const std::size_t n = size - 1;
  switch (data[0] % 12) {
    case 0:
      feature_frame(payload, n);
      break;
    case 1:
      track_frame(payload, n);
      break;
    case 2:
      body_pose(payload, n);
      break;
    case 3:
      camera_info(payload, n);
      break;
    case 4:
      decode_only<msg::CameraCommand>(payload, n);
      break;
    case 5:
      decode_only<msg::Predictions>(payload, n);
      break;
    case 6:
      decode_only<msg::TimeSync>(payload, n);
      break;
    case 7:
      mocap_frame(payload, n);
      break;
    case 8:
      body_descriptions(payload, n);
      break;
    case 9:
      stroke_events(payload, n);
      break;
    case 10:
      chain_frame(payload, n);
      break;
    default:
      decode_only<msg::EstimatorStatus>(payload, n);
      break;
  }
  return 0;
}
