// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/chain_stage.h"

#include <algorithm>
#include <utility>

#include <nlohmann/json.hpp>

#include "panoptes/time.h"

namespace panoptes::session {

namespace est = panoptes::estimator;

namespace {

nlohmann::ordered_json xyz(const Eigen::Vector3d& p) {
  return nlohmann::ordered_json::array({p.x(), p.y(), p.z()});
}

const char* status_name(est::ChainStatus status) {
  switch (status) {
    case est::ChainStatus::kTracking:
      return "tracking";
    case est::ChainStatus::kAmbiguous:
      return "ambiguous";
    case est::ChainStatus::kNotIdentified:
      break;
  }
  return "not_identified";
}

// `predicted`: the same chain prediction_horizon_ns ahead (nullptr: no prediction, the record
// carries the tip as predicted_tip with horizon 0, as the ChainFrame does).
nlohmann::ordered_json chain_record(const est::ChainOutput& output, const est::ChainOutput* predicted,
                                    TimeNs prediction_horizon_ns, TimeNs frame_stamp_ns, int joint_count) {
  nlohmann::ordered_json line{{"type", "chain"},
                              {"stamp_ns", frame_stamp_ns},
                              {"chain", output.name},
                              {"status", status_name(output.status)}};
  if (output.status != est::ChainStatus::kTracking) return line;
  line["stamp_ns"] = output.stamp_ns;
  line["angles"] = std::vector<double>(output.pose.angles.data(), output.pose.angles.data() + joint_count);
  nlohmann::ordered_json markers = nlohmann::ordered_json::array();
  for (const auto& marker : output.pose.markers) markers.push_back(xyz(marker));
  line["markers"] = std::move(markers);
  line["marker_valid"] = output.marker_valid;
  line["tip"] = xyz(output.pose.tip);
  line["predicted_tip"] = xyz(predicted ? predicted->pose.tip : output.pose.tip);
  line["prediction_horizon_ns"] = predicted ? prediction_horizon_ns : 0;
  line["grabbing"] = output.grabbing;
  return line;
}

std::vector<std::string> names_of(const std::vector<ChainDefinition>& chains) {
  std::vector<std::string> names;
  names.reserve(chains.size());
  for (const auto& chain : chains) names.push_back(chain.name);
  return names;
}

}  // namespace

ChainStage::ChainStage(std::vector<ChainDefinition> chains, const SystemCalibration& calibration,
                       const std::string& out_path, const est::ChainTrackerOptions& options)
    : names_(names_of(chains)), tracker_(std::move(chains), options) {
  for (const auto& camera : calibration.cameras) add_camera(camera);
  if (!out_path.empty()) out_.emplace(out_path);
  for (const auto& name : names_) counts_[name];
}

void ChainStage::add_camera(const CameraCalibration& camera) {
  // A moving camera's T_world_cam is its mount on a rig (docs/inside_out.md): not a fixed view.
  if (camera.T_world_cam && !camera.moving) cameras_.emplace(camera.id, camera.model());
}

bool ChainStage::observe(const FeatureFrame& frame, const est::Tracker& tracker) {
  const auto camera = cameras_.find(frame.camera_id);
  if (camera == cameras_.end() || frame.stamp_ns < last_stamp_ns_) {
    ++frames_skipped_;
    return false;
  }
  last_stamp_ns_ = frame.stamp_ns;
  if (!all_tracking_) {
    std::vector<Eigen::Vector3d> points;
    for (const auto& track : tracker.current_tracks()) {
      if (track.status == TrackStatus::kConfirmed) points.push_back(track.p);
    }
    tracker_.identify(frame.stamp_ns, points);
  }
  std::vector<Eigen::Vector2d> blobs;
  blobs.reserve(frame.blobs.size());
  for (const auto& blob : frame.blobs) blobs.emplace_back(blob.x, blob.y);
  tracker_.process(camera->second, frame.stamp_ns, blobs);

  outputs_ = tracker_.outputs();
  events_ = tracker_.take_events();
  if (prediction_horizon_s_ > 0.0) predicted_ = tracker_.outputs(prediction_horizon_s_);
  const auto& outputs = outputs_;
  const auto& events = events_;
  all_tracking_ = std::all_of(outputs.begin(), outputs.end(), [](const auto& output) {
    return output.status == est::ChainStatus::kTracking;
  });
  for (const auto& output : outputs) {
    Counts& counts = counts_[output.name];
    if (output.status == est::ChainStatus::kTracking) ++counts.tracking;
    if (output.status == est::ChainStatus::kAmbiguous) ++counts.ambiguous;
    if (output.status == est::ChainStatus::kNotIdentified) ++counts.not_identified;
  }
  for (const auto& named : events) {
    Counts& counts = counts_[named.chain];
    ++(named.event.kind == est::GrabEventKind::kGrab ? counts.grabs : counts.releases);
  }
  if (out_) write(outputs, events);
  return true;
}

void ChainStage::write(const std::vector<est::ChainOutput>& outputs,
                       const std::vector<est::NamedGrabEvent>& events) {
  const TimeNs horizon_ns = seconds_to_ns(prediction_horizon_s_);
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const est::ChainOutput& output = outputs[i];
    const est::ChainOutput* ahead = i < predicted_.size() ? &predicted_[i] : nullptr;
    const int joint_count = static_cast<int>(output.marker_valid.size()) - 2;
    out_->write_line(chain_record(output, ahead, horizon_ns, last_stamp_ns_, joint_count).dump());
    ++records_;
  }
  for (const auto& named : events) {
    const nlohmann::ordered_json line{
        {"type", named.event.kind == est::GrabEventKind::kGrab ? "grab" : "release"},
        {"stamp_ns", named.event.stamp_ns},
        {"chain", named.chain},
        {"tip", xyz(named.event.tip)},
        {"bend", named.event.bend_rad}};
    out_->write_line(line.dump());
    ++records_;
  }
}

std::string ChainStage::summary() const {
  // Appended piece by piece: `" " + name + ...` trips a GCC 12 -Wrestrict false positive.
  std::string text = "chains (camera frames by status):";
  for (const auto& name : names_) {
    const Counts& c = counts_.at(name);
    text.append(" ").append(name);
    text.append(" tracking ").append(std::to_string(c.tracking));
    text.append(", ambiguous ").append(std::to_string(c.ambiguous));
    text.append(", not identified ").append(std::to_string(c.not_identified));
    text.append(", ").append(std::to_string(c.grabs)).append(" grabs, ");
    text.append(std::to_string(c.releases)).append(" releases;");
  }
  text.append(" ").append(std::to_string(frames_skipped_)).append(" frames skipped (late or uncalibrated)");
  if (out_) text.append("; wrote ").append(std::to_string(records_)).append(" chain records");
  return text;
}

}  // namespace panoptes::session
