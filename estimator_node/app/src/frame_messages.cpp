// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator_app/frame_messages.h"

#include <algorithm>
#include <set>

#include "panoptes/dds/convert.h"

namespace panoptes::estimator_app {

namespace {

// `frame_stamp_ns`: the MocapFrame's stamp; a smoothed pose (stamped before it) gets a negative horizon.
msg::FrameBody to_body_message(const session::BodyOutput& body, TimeNs frame_stamp_ns) {
  msg::FrameBody out;
  out.name(body.name);
  out.id(body.id);
  out.tracking_valid(body.tracking_valid);
  if (body.tracking_valid) {
    const PoseRecord& pose = body.pose;
    out.pose().position({pose.p.x(), pose.p.y(), pose.p.z()});
    out.pose().orientation({pose.q.x(), pose.q.y(), pose.q.z(), pose.q.w()});
    out.linear_velocity({pose.v.x(), pose.v.y(), pose.v.z()});
    out.angular_velocity({pose.w.x(), pose.w.y(), pose.w.z()});
    out.sigma(pose.sigma);
    out.quality(static_cast<float>(pose.quality));
    out.prediction_horizon_ns(pose.stamp_ns + pose.horizon_ns - frame_stamp_ns);
    out.cameras(static_cast<std::uint16_t>(std::clamp(pose.cameras, 0, 65535)));
  } else {
    out.pose().orientation({0.0, 0.0, 0.0, 1.0});
  }
  out.mean_marker_error(body.mean_marker_error_m);
  return out;
}

}  // namespace

msg::MocapFrame to_frame_message(const session::FrameOutput& frame, TimeNs publish_ns) {
  msg::MocapFrame message;
  message.frame_number(frame.frame_number);
  message.stamp_ns(frame.stamp_ns);
  message.publish_ns(publish_ns);
  message.source_camera(frame.source_camera);
  message.source_frame(frame.source_frame);
  msg::FrameStages& stages = message.stages();
  stages.camera_arrival_ns(frame.stages.camera_arrival_ns);
  stages.camera_processing_ns(frame.stages.camera_processing_ns);
  stages.feature_publish_ns(frame.stages.feature_publish_ns);
  stages.received_ns(frame.stages.received_ns);
  stages.dequeued_ns(frame.stages.dequeued_ns);
  stages.updated_ns(frame.stages.updated_ns);
  message.bodies().reserve(frame.bodies.size());
  for (const auto& body : frame.bodies) message.bodies().push_back(to_body_message(body, frame.stamp_ns));
  message.markers().reserve(frame.markers.size());
  for (const auto& marker : frame.markers) {
    msg::FrameMarker m;
    m.state(dds::to_message(marker.track));
    m.body(marker.body);
    m.body_marker(marker.body_marker);
    message.markers().push_back(std::move(m));
  }
  return message;
}

msg::BodyDescriptions to_descriptions_message(const std::vector<BodyDefinition>& bodies,
                                              std::uint64_t generation, const std::string& source,
                                              TimeNs stamp_ns, const std::vector<BodyDefinition>& rigs,
                                              const std::vector<BodyDefinition>& segments) {
  msg::BodyDescriptions message;
  message.stamp_ns(stamp_ns);
  message.generation(generation);
  message.source(source);
  int id = 0;
  std::vector<const BodyDefinition*> listed;
  std::set<std::string> names;
  for (const auto& body : bodies)
    if (names.insert(body.name).second) listed.push_back(&body);
  const std::size_t body_count = listed.size();
  // A rig named like a body would make the set malformed for clients (a name twice): left out.
  for (const auto& rig : rigs)
    if (names.insert(rig.name).second) listed.push_back(&rig);
  const std::size_t rig_end = listed.size();
  for (const auto& segment : segments)
    if (names.insert(segment.name).second) listed.push_back(&segment);
  for (std::size_t i = 0; i < listed.size(); ++i) {
    const BodyDefinition& body = *listed[i];
    msg::BodyDescription description;
    description.name(body.name);
    description.id(++id);
    description.kind(i >= rig_end                   ? "segment"
                     : i >= body_count              ? "rig"
                     : body.kind == BodyKind::kLed7 ? "led7"
                                                    : "passive");
    for (const auto& marker : body.markers) {
      msg::MarkerPosition position;
      position.position({marker.x(), marker.y(), marker.z()});
      description.markers().push_back(position);
    }
    message.bodies().push_back(std::move(description));
  }
  return message;
}

msg::MarkerLabels to_labels_message(const session::LabelStage& stage) {
  msg::MarkerLabels message;
  const std::shared_ptr<const session::LabelMap> map = stage.map();  // one consistent map
  message.stamp_ns(map->stamp_ns);
  message.generation(map->generation);
  for (std::size_t i = 0; i < stage.subject_count(); ++i) {
    const labelling::SubjectModel& model = stage.model(i);
    msg::SubjectLabels subject;
    subject.name(model.subject);
    subject.marker_set(model.marker_set);
    for (const auto& segment : model.segments) {
      for (const auto& name : segment.tracked_marker_names()) subject.markers().push_back(name);
    }
    for (const auto& [from, to] : model.sticks) {
      msg::LabelStick stick;
      stick.from(from);
      stick.to(to);
      subject.sticks().push_back(std::move(stick));
    }
    for (const auto& label : map->labels) {
      if (label.subject != model.subject) continue;
      msg::TrackLabel named;
      named.track_id(label.track);
      named.marker(label.marker);
      subject.labels().push_back(std::move(named));
    }
    message.subjects().push_back(std::move(subject));
  }
  return message;
}

}  // namespace panoptes::estimator_app
