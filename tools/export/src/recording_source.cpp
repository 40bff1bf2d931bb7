// SPDX-License-Identifier: Apache-2.0
#include "panoptes/export_job/recording_source.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <string_view>
#include <utility>

#include "panoptes/dds/convert.h"
#include "panoptes/dds/decode.h"
#include "panoptes/errors.h"
#include "panoptes/recording/mcap_reader.h"

namespace panoptes::export_job {

namespace {

PoseRecord pose_of(const msg::FrameBody& body, TimeNs frame_stamp_ns) {
  PoseRecord pose;
  pose.stamp_ns = frame_stamp_ns;
  pose.body = body.name();
  const auto& p = body.pose().position();
  const auto& q = body.pose().orientation();
  const auto& v = body.linear_velocity();
  const auto& w = body.angular_velocity();
  pose.p = Eigen::Vector3d(p[0], p[1], p[2]);
  pose.q = Eigen::Vector4d(q[0], q[1], q[2], q[3]);
  pose.v = Eigen::Vector3d(v[0], v[1], v[2]);
  pose.w = Eigen::Vector3d(w[0], w[1], w[2]);
  pose.horizon_ns = body.prediction_horizon_ns();
  pose.quality = body.quality();
  pose.cameras = body.cameras();
  pose.sigma = body.sigma();
  return pose;
}

template <class Message>
std::string_view decode(const recording::MessageView& m, Message& out) {
  return dds::decode_error_name(dds::decode_sample(m.data.data(), m.data.size(), out));
}

// The channels a recording holds, for the error that says the frames are not among them.
std::string channel_list(const recording::McapReader& reader) {
  std::set<std::string> topics;
  for (const auto& [id, channel] : reader.channels()) topics.insert(channel.topic);
  std::string text;
  for (const auto& topic : topics) text += (text.empty() ? "" : ", ") + topic;
  return text.empty() ? "none" : text;
}

// Drops labels that name a body or marker the descriptions do not have (counted once per label).
void check_labels(ExportRecords& records, const RecordingContents& contents, const std::string& file) {
  if (contents.layout_sizes.empty()) return;
  std::set<std::pair<std::string, int>> reported;
  for (MarkerLabel& label : records.labels) {
    if (label.body.empty()) continue;
    const auto layout = contents.layout_sizes.find(label.body);
    if (layout != contents.layout_sizes.end() && label.marker >= 0 &&
        static_cast<std::size_t>(label.marker) < layout->second)
      continue;
    if (reported.emplace(label.body, label.marker).second)
      records.skipped.push_back(file + ": label " + body_marker_name(label.body, label.marker) +
                                " is not a marker of the recorded body descriptions: left unlabelled");
    label = MarkerLabel{};
  }
}

// FrameBody.quality is a float on the wire, the fraction seen / markers the estimator computed as
// a double (and wrote to --out-poses). With the body's marker count from the descriptions, that
// double is recovered exactly: the nearest fraction k / markers, when the float is that fraction.
void restore_quality(ExportRecords& records, const RecordingContents& contents) {
  for (PoseRecord& pose : records.poses) {
    const auto layout = contents.layout_sizes.find(pose.body);
    if (layout == contents.layout_sizes.end() || layout->second == 0) continue;
    const auto markers = static_cast<double>(layout->second);
    const double fraction = std::round(pose.quality * markers) / markers;
    if (static_cast<float>(fraction) == static_cast<float>(pose.quality)) pose.quality = fraction;
  }
}

// A MarkerLabels map: the names by track id and the subjects' marker order (a subject listed
// before keeps its place).
void use_labels(const msg::MarkerLabels& labels, TrackNames& names, std::vector<SubjectOrder>& order) {
  names.clear();
  for (const auto& subject : labels.subjects()) {
    for (const auto& label : subject.labels()) names[label.track_id()] = {subject.name(), label.marker()};
    const auto known = std::find_if(order.begin(), order.end(),
                                    [&](const SubjectOrder& o) { return o.subject == subject.name(); });
    SubjectOrder entry{subject.name(), {subject.markers().begin(), subject.markers().end()}};
    if (known == order.end()) {
      order.push_back(std::move(entry));
    } else {
      *known = std::move(entry);
    }
  }
}

}  // namespace

std::string body_marker_name(const std::string& body, int marker) {
  return body + "_" + std::to_string(marker);
}

void append_frame_records(const msg::MocapFrame& frame, ExportRecords& out, const TrackNames& names) {
  for (const auto& marker : frame.markers()) {
    out.tracks.push_back(dds::from_message(marker.state(), frame.stamp_ns()));
    MarkerLabel label;
    if (!marker.body().empty()) {
      label.body = marker.body();
      label.marker = marker.body_marker();
    } else if (const auto named = names.find(marker.state().id()); named != names.end()) {
      label.subject = named->second.first;
      label.name = named->second.second;
    }
    out.labels.push_back(std::move(label));
  }
  for (const auto& body : frame.bodies())
    if (body.tracking_valid()) out.poses.push_back(pose_of(body, frame.stamp_ns()));
}

RecordingRecordSource::RecordingRecordSource(std::filesystem::path path) : path_(std::move(path)) {}

std::string RecordingRecordSource::describe() const {
  return "recording " + path_.string();
}

ExportRecords RecordingRecordSource::read() {
  const std::string file = path_.string();
  auto reader = as_input_error([&] { return std::make_unique<recording::McapReader>(path_); });
  ExportRecords records;
  contents_ = RecordingContents{};
  std::uint64_t index = 0;
  TrackNames names;  // the newest map of names (rt/panoptes/labels) as the file goes
  const auto report = reader->read([&](const recording::MessageView& m) {
    ++index;
    if (m.channel->topic == kFramesChannel) {
      msg::MocapFrame frame;
      if (const auto error = decode(m, frame); !error.empty()) {
        records.skipped.push_back(file + ": message " + std::to_string(index) + " on " + kFramesChannel +
                                  ": cannot decode its CDR (" + std::string(error) + "): skipped");
        return;
      }
      if (contents_.frames++ == 0) contents_.first_frame_number = frame.frame_number();
      contents_.last_frame_number = frame.frame_number();
      contents_.frame_stamps.push_back(frame.stamp_ns());
      if (frame.source_frame() == -1 && frame.source_camera().empty()) ++contents_.fixed_rate_frames;
      append_frame_records(frame, records, names);
    } else if (m.channel->topic == kLabelsChannel) {
      msg::MarkerLabels labels;
      if (const auto error = decode(m, labels); !error.empty()) {  // the frames keep the last map's names
        records.skipped.push_back(file + ": message " + std::to_string(index) + " on " + kLabelsChannel +
                                  ": cannot decode its CDR (" + std::string(error) + "): skipped");
        return;
      }
      use_labels(labels, names, records.subject_order);
    } else if (m.channel->topic == kDescriptionsChannel) {
      msg::BodyDescriptions descriptions;
      if (const auto error = decode(m, descriptions); !error.empty()) {  // the frames still name the bodies
        records.skipped.push_back(file + ": message " + std::to_string(index) + " on " +
                                  kDescriptionsChannel + ": cannot decode its CDR (" + std::string(error) +
                                  "): skipped");
        return;
      }
      records.body_order.clear();
      contents_.layout_sizes.clear();
      for (const auto& body : descriptions.bodies()) {
        records.body_order.push_back(body.name());
        contents_.layout_sizes[body.name()] = body.markers().size();
      }
    }
  });
  for (const auto& problem : report.problems) records.skipped.push_back(problem);
  if (report.problem_count > report.problems.size())
    records.skipped.push_back(file + ": " + std::to_string(report.problem_count - report.problems.size()) +
                              " more problems (not listed)");
  const bool has_channel = std::any_of(reader->channels().begin(), reader->channels().end(),
                                       [](const auto& c) { return c.second.topic == kFramesChannel; });
  if (!has_channel)
    throw ConfigError(file, "",
                      std::string("no ") + kFramesChannel + " channel (the recording holds " +
                          channel_list(*reader) + "): record the estimator's frames to export them");
  if (contents_.frames == 0)
    throw ConfigError(file, "",
                      std::string("no MocapFrame on ") + kFramesChannel + " could be read" +
                          (report.problems.empty() ? "" : " (" + report.problems.front() + ")"));
  check_labels(records, contents_, file);
  restore_quality(records, contents_);
  return records;
}

}  // namespace panoptes::export_job
