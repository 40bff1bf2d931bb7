// SPDX-License-Identifier: Apache-2.0
#include "conversion.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <string_view>
#include <utility>

#include "panoptes/frame_grid.h"

namespace panoptes::client::detail {
namespace {

constexpr std::uint8_t kTrackCoasting = 2;  // msg::Track::status
// A unit quaternion written as doubles is within 1e-9 of norm 1; this tolerates float-rounded
// writers while rejecting what is not a rotation.
constexpr double kQuaternionNormTolerance = 1e-3;

template <std::size_t N>
bool all_finite(const std::array<double, N>& values) {
  for (const double v : values)
    if (!std::isfinite(v)) return false;
  return true;
}

// The body's fields, or an error naming what is wrong with them.
std::optional<RigidBody> to_body(const msg::FrameBody& in, std::string& error) {
  RigidBody out;
  out.name = in.name();
  out.id = in.id();
  out.tracking_valid = in.tracking_valid();
  const std::string what = "body '" + in.name() + "'";
  if (out.name.empty()) {
    error = "a body without a name (id " + std::to_string(in.id()) + ")";
    return std::nullopt;
  }
  if (!out.tracking_valid) return out;  // the pose fields are zero: nothing to check or copy
  out.position = in.pose().position();
  out.orientation = in.pose().orientation();
  out.linear_velocity = in.linear_velocity();
  out.angular_velocity = in.angular_velocity();
  out.sigma = in.sigma();
  if (!all_finite(out.position) || !all_finite(out.orientation) || !all_finite(out.linear_velocity) ||
      !all_finite(out.angular_velocity)) {
    error = what + ": a non-finite pose or velocity while tracking_valid";
    return std::nullopt;
  }
  const auto& q = out.orientation;
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
    error = what + ": orientation is not a unit quaternion (norm " + std::to_string(norm) + ")";
    return std::nullopt;
  }
  out.quality = in.quality();
  out.mean_marker_error = in.mean_marker_error();
  out.prediction_horizon_ns = in.prediction_horizon_ns();
  out.cameras = in.cameras();
  return out;
}

std::optional<Marker> to_marker(const msg::FrameMarker& in, std::string& error) {
  const msg::Track& track = in.state();
  Marker out;
  out.id = track.id();
  out.position = track.position();
  out.velocity = track.velocity();
  out.covariance = track.covariance();
  out.cameras = track.cameras();
  out.occluded = track.status() == kTrackCoasting;
  out.body = in.body();
  out.body_marker = in.body().empty() ? -1 : in.body_marker();
  if (!all_finite(out.position) || !all_finite(out.velocity)) {
    error = "marker " + std::to_string(out.id) + ": a non-finite position or velocity";
    return std::nullopt;
  }
  if (!out.body.empty() && out.body_marker < 0) {
    error = "marker " + std::to_string(out.id) + ": labelled '" + out.body + "' without a body_marker index";
    return std::nullopt;
  }
  return out;
}

// A name that two bodies share, or nullptr. Without allocating for the usual handful of bodies:
// this runs for every frame on the delivery path.
const std::string* duplicate_name(const std::vector<RigidBody>& bodies) {
  constexpr std::size_t kLinearLimit = 32;
  if (bodies.size() <= kLinearLimit) {
    for (std::size_t i = 0; i < bodies.size(); ++i)
      for (std::size_t j = i + 1; j < bodies.size(); ++j)
        if (bodies[i].name == bodies[j].name) return &bodies[i].name;
    return nullptr;
  }
  std::set<std::string_view> names;
  for (const auto& body : bodies)
    if (!names.insert(body.name).second) return &body.name;
  return nullptr;
}

// b - a when both stamps are known (non-zero), else 0; 0 too when garbage stamps make the difference
// overflow (found by tests/fuzz/fuzz_messages.cpp).
std::int64_t span(std::int64_t a, std::int64_t b) {
  std::int64_t difference = 0;
  if (a == 0 || b == 0 || __builtin_sub_overflow(b, a, &difference)) return 0;
  return difference;
}

}  // namespace

Latency latency_of(const msg::MocapFrame& message, std::int64_t receive_ns) {
  const msg::FrameStages& s = message.stages();
  Latency l;
  l.capture_to_publish_ns = span(message.stamp_ns(), message.publish_ns());
  l.publish_to_receive_ns = span(message.publish_ns(), receive_ns);
  l.capture_to_receive_ns = span(message.stamp_ns(), receive_ns);
  l.camera_ns = span(message.stamp_ns(), s.feature_publish_ns());
  l.network_ns = span(s.feature_publish_ns(), s.received_ns());
  l.queue_ns = span(s.received_ns(), s.dequeued_ns());
  l.update_ns = span(s.dequeued_ns(), s.updated_ns());
  l.output_ns = span(s.updated_ns(), message.publish_ns());
  return l;
}

std::optional<Frame> to_frame(const msg::MocapFrame& message, std::int64_t receive_ns, std::string& error) {
  if (message.frame_number() == 0) {
    error = "frame_number 0 (numbers start at 1)";
    return std::nullopt;
  }
  Frame frame;
  frame.frame_number = message.frame_number();
  frame.stamp_ns = message.stamp_ns();
  frame.publish_ns = message.publish_ns();
  frame.receive_ns = receive_ns;
  frame.source_camera = message.source_camera();
  frame.source_frame = message.source_frame();
  frame.latency = latency_of(message, receive_ns);
  frame.bodies.reserve(message.bodies().size());
  for (const auto& body : message.bodies()) {
    auto converted = to_body(body, error);
    if (!converted) return std::nullopt;
    frame.bodies.push_back(std::move(*converted));
  }
  if (const std::string* twice = duplicate_name(frame.bodies)) {
    error = "body '" + *twice + "' appears twice";
    return std::nullopt;
  }
  frame.markers.reserve(message.markers().size());
  for (const auto& marker : message.markers()) {
    auto converted = to_marker(marker, error);
    if (!converted) return std::nullopt;
    frame.markers.push_back(std::move(*converted));
  }
  return frame;
}

std::optional<std::vector<BodyDescription>> to_descriptions(const msg::BodyDescriptions& message,
                                                            std::string& error) {
  std::vector<BodyDescription> bodies;
  std::set<std::string> names;
  for (const auto& in : message.bodies()) {
    if (in.name().empty()) {
      error = "a body description without a name (id " + std::to_string(in.id()) + ")";
      return std::nullopt;
    }
    const std::string what = "body description '" + in.name() + "'";
    if (!names.insert(in.name()).second) {
      error = what + " appears twice";
      return std::nullopt;
    }
    if (in.markers().empty() && in.kind() != "rig") {  // a rig (inside-out) may carry none
      error = what + ": no markers";
      return std::nullopt;
    }
    BodyDescription out{in.name(), in.id(), in.kind(), {}};
    for (std::size_t i = 0; i < in.markers().size(); ++i) {
      const auto& position = in.markers()[i].position();
      if (!all_finite(position)) {
        error = what + ": markers[" + std::to_string(i) + "] is not finite";
        return std::nullopt;
      }
      out.markers.push_back(position);
    }
    bodies.push_back(std::move(out));
  }
  return bodies;
}

std::optional<std::vector<Stroke>> to_strokes(const msg::StrokeEvents& message, std::int64_t receive_ns,
                                              std::string& error) {
  std::vector<Stroke> strokes;
  strokes.reserve(message.events().size());
  const std::array<double, 2> size{message.surface_size()[0], message.surface_size()[1]};
  for (std::size_t i = 0; i < message.events().size(); ++i) {
    const msg::StrokeEvent& event = message.events()[i];
    const std::string what = "stroke event " + std::to_string(i);
    if (event.phase() > 2) {
      error =
          what + ": phase " + std::to_string(event.phase()) + " is not begin (0), continue (1) or end (2)";
      return std::nullopt;
    }
    if (event.stroke_id() == 0) {
      error = what + ": stroke_id 0";
      return std::nullopt;
    }
    Stroke stroke;
    stroke.phase = static_cast<StrokePhase>(event.phase());
    stroke.id = event.stroke_id();
    stroke.stamp_ns = event.stamp_ns();
    stroke.position = {event.position()[0], event.position()[1]};
    stroke.velocity = {event.velocity()[0], event.velocity()[1]};
    stroke.acceleration = {event.acceleration()[0], event.acceleration()[1]};
    stroke.cameras = event.cameras();
    stroke.surface_size = size;
    stroke.source_camera = message.source_camera();
    stroke.publish_ns = message.publish_ns();
    stroke.receive_ns = receive_ns;
    if (!all_finite(stroke.position) || !all_finite(stroke.velocity) || !all_finite(stroke.acceleration) ||
        !all_finite(size)) {
      error = what + " (stroke " + std::to_string(stroke.id) + "): a non-finite number";
      return std::nullopt;
    }
    strokes.push_back(std::move(stroke));
  }
  return strokes;
}

namespace {

constexpr std::size_t kMaxChainMarkers = 16;  // the core allows 3..5; more is not a chain

// One chain of a ChainFrame, or an error naming its field.
std::optional<Chain> to_chain(const msg::ChainState& in, std::string& error) {
  const std::string what = "chain '" + in.name() + "'";
  if (in.status() > 2) {
    error = what + ": status " + std::to_string(in.status()) +
            " is not tracking (0), ambiguous (1) or not identified (2)";
    return std::nullopt;
  }
  if (in.name().empty() || in.chain_id() == 0) {
    error = what + ": an empty name or chain_id 0";
    return std::nullopt;
  }
  Chain out;
  out.name = in.name();
  out.id = static_cast<int>(in.chain_id());
  out.status = static_cast<ChainStatus>(in.status());
  out.stamp_ns = in.stamp_ns();
  out.grabbing = in.grabbing();
  if (out.status != ChainStatus::kTracking) return out;
  const std::size_t markers = in.markers().size();
  if (markers < 3 || markers > kMaxChainMarkers || in.marker_valid().size() != markers ||
      in.angles().size() != markers - 2) {
    error = what + ": " + std::to_string(markers) + " markers, " + std::to_string(in.marker_valid().size()) +
            " valid flags and " + std::to_string(in.angles().size()) + " angles (wants 3.." +
            std::to_string(kMaxChainMarkers) + " markers, one flag each, markers - 2 angles)";
    return std::nullopt;
  }
  for (const double angle : in.angles()) {
    if (!std::isfinite(angle)) {
      error = what + ": a non-finite joint angle";
      return std::nullopt;
    }
    out.joint_angles.push_back(angle);
  }
  for (const auto& marker : in.markers()) {
    if (!all_finite(marker.position())) {
      error = what + ": a non-finite marker position";
      return std::nullopt;
    }
    out.markers.push_back(marker.position());
  }
  out.marker_valid.assign(in.marker_valid().begin(), in.marker_valid().end());
  out.tip = in.tip();
  out.predicted_tip = in.predicted_tip();
  out.prediction_horizon_ns = in.prediction_horizon_ns();
  if (!all_finite(out.tip) || !all_finite(out.predicted_tip) || out.prediction_horizon_ns < 0) {
    error = what + ": a non-finite tip or a negative prediction horizon";
    return std::nullopt;
  }
  return out;
}

}  // namespace

std::optional<ChainUpdate> to_chain_update(const msg::ChainFrame& message, std::int64_t receive_ns,
                                           std::string& error) {
  ChainUpdate update;
  update.stamp_ns = message.stamp_ns();
  update.publish_ns = message.publish_ns();
  update.receive_ns = receive_ns;
  update.source_camera = message.source_camera();
  update.source_frame = message.source_frame();
  update.chains.reserve(message.chains().size());
  for (const auto& state : message.chains()) {
    auto chain = to_chain(state, error);
    if (!chain) return std::nullopt;
    update.chains.push_back(std::move(*chain));
  }
  for (std::size_t i = 0; i < message.events().size(); ++i) {
    const msg::ChainEvent& in = message.events()[i];
    const std::string what = "chain event " + std::to_string(i) + " ('" + in.chain() + "')";
    if (in.kind() > 1) {
      error = what + ": kind " + std::to_string(in.kind()) + " is not grab (0) or release (1)";
      return std::nullopt;
    }
    if (in.chain().empty() || !all_finite(in.tip()) || !std::isfinite(in.bend())) {
      error = what + ": an empty chain name, or a non-finite tip or bend";
      return std::nullopt;
    }
    GrabEvent event;
    event.kind = static_cast<GrabKind>(in.kind());
    event.chain = in.chain();
    event.chain_id = static_cast<int>(in.chain_id());
    event.stamp_ns = in.stamp_ns();
    event.tip = in.tip();
    event.bend = in.bend();
    event.publish_ns = message.publish_ns();
    event.receive_ns = receive_ns;
    update.events.push_back(std::move(event));
  }
  return update;
}

std::optional<LabelMap> to_label_map(const msg::MarkerLabels& message, std::string& error) {
  LabelMap map;
  std::set<std::string> subject_names;
  for (const msg::SubjectLabels& subject : message.subjects()) {
    if (subject.name().empty() || !subject_names.insert(subject.name()).second) {
      error = "subject '" + subject.name() + "': empty or duplicate name";
      return std::nullopt;
    }
    SubjectDescription description;
    description.name = subject.name();
    description.marker_set = subject.marker_set();
    description.markers.assign(subject.markers().begin(), subject.markers().end());
    const std::set<std::string> known(description.markers.begin(), description.markers.end());
    for (const msg::LabelStick& stick : subject.sticks()) {
      if (known.count(stick.from()) == 0 || known.count(stick.to()) == 0) {
        error = "subject '" + subject.name() + "': stick " + stick.from() + "-" + stick.to() +
                " names a marker the subject does not have";
        return std::nullopt;
      }
      description.sticks.emplace_back(stick.from(), stick.to());
    }
    for (const msg::TrackLabel& label : subject.labels()) {
      if (known.count(label.marker()) == 0) {
        error = "subject '" + subject.name() + "': track " + std::to_string(label.track_id()) + " named '" +
                label.marker() + "', not one of its markers";
        return std::nullopt;
      }
      if (!map.names.emplace(label.track_id(), std::make_pair(subject.name(), label.marker())).second) {
        error = "track " + std::to_string(label.track_id()) + " named twice";
        return std::nullopt;
      }
    }
    map.subjects.push_back(std::move(description));
  }
  return map;
}

void apply_names(Frame& frame, const LabelMap& map) {
  if (map.names.empty()) return;
  for (Marker& marker : frame.markers) {
    const auto found = map.names.find(marker.id);
    if (found == map.names.end()) continue;
    marker.subject = found->second.first;
    marker.name = found->second.second;
  }
}

double rate_from_stamps(std::vector<std::int64_t> stamps, bool fixed) {
  std::sort(stamps.begin(), stamps.end());
  stamps.erase(std::unique(stamps.begin(), stamps.end()), stamps.end());
  if (stamps.size() < 2) return 0.0;
  if (!fixed) {
    return static_cast<double>(stamps.size() - 1) * 1e9 / static_cast<double>(stamps.back() - stamps.front());
  }
  // A skipped or lost frame only lengthens an interval (to whole periods): the shortest one is the
  // period. The median was not (the third frame of a run whose second period was skipped: 2P and P,
  // the upper of the two taken: half the rate, and that frame got no timecode; test_fixed_rate).
  std::int64_t shortest = stamps[1] - stamps[0];
  for (std::size_t i = 2; i < stamps.size(); ++i) shortest = std::min(shortest, stamps[i] - stamps[i - 1]);
  return 1e9 / static_cast<double>(shortest);
}

std::optional<Timecode> timecode_of(std::int64_t stamp_ns, const FrameRate& rate) {
  if (!rate.fixed) return std::nullopt;
  const double whole = std::round(rate.hz);
  if (whole < 1 || whole > FrameGrid::kMaxRateHz || std::abs(rate.hz - whole) > 0.01) return std::nullopt;
  const FrameGrid grid(static_cast<int>(whole));
  if (grid.instant(grid.index_at(stamp_ns)) != stamp_ns) return std::nullopt;
  const ::panoptes::Timecode tc = grid.timecode(stamp_ns);
  return Timecode{tc.hours, tc.minutes, tc.seconds, tc.frames, grid.rate_hz(), to_string(tc, grid.rate_hz())};
}

}  // namespace panoptes::client::detail
