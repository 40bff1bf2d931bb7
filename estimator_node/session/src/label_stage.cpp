// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/label_stage.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <utility>

#include <nlohmann/json.hpp>

#include "panoptes/labelling_files/subject_model_file.h"

namespace panoptes::session {

namespace {

std::vector<std::string> subject_names(const std::vector<labelling::SubjectModel>& models) {
  std::vector<std::string> names;
  names.reserve(models.size());
  for (const auto& model : models) names.push_back(model.subject);
  return names;
}

}  // namespace

LabelStage::LabelStage(std::vector<labelling::SubjectModel> models, const labelling::LabellerOptions& options,
                       const std::string& out_path, TimeNs period_ns)
    : subjects_(subject_names(models)), labeller_(std::move(models), options), period_ns_(period_ns) {
  if (!out_path.empty()) out_.emplace(out_path);
}

LabelStage LabelStage::from_files(const std::vector<std::string>& subject_files,
                                  const labelling::LabellerOptions& options, const std::string& out_path,
                                  TimeNs period_ns) {
  std::vector<labelling::SubjectModel> models;
  models.reserve(subject_files.size());
  for (const auto& path : subject_files) models.push_back(labelling::load_subject_model(path));
  return LabelStage(std::move(models), options, out_path, period_ns);
}

void LabelStage::observe(const estimator::Tracker& tracker) {
  const TimeNs stamp = tracker.last_stamp_ns();
  if (stamp <= last_stamp_ns_) return;  // nothing new (a late frame refined an older instant)
  last_stamp_ns_ = stamp;
  points_.clear();
  for (const auto& track : tracker.current_tracks()) {
    if (track.status != TrackStatus::kConfirmed) continue;
    points_.push_back({static_cast<std::uint64_t>(track.id), track.p});
  }
  if (last_run_ns_ == 0 || stamp - last_run_ns_ >= period_ns_) {
    last_run_ns_ = stamp;
    const auto start = std::chrono::steady_clock::now();
    labeller_.update(points_, static_cast<double>(stamp) * 1e-9);
    const double us =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    const double per_subject = us / static_cast<double>(std::max<std::size_t>(subjects_.size(), 1));
    total_us_ += per_subject;
    worst_us_ = std::max(worst_us_, per_subject);
    ++frames_;
    update_map(stamp);
  }
  labels_.clear();
  for (const auto& point : points_) {
    const auto label = labeller_.label_of(point.track);
    if (!label) continue;
    labels_.push_back({static_cast<std::int64_t>(point.track), subjects_.at(label->subject), label->marker});
  }
  marker_frames_ += points_.size();
  labelled_marker_frames_ += labels_.size();
  if (!out_) return;
  // Every confirmed track with its position; "subject"/"marker" only on the labelled ones.
  nlohmann::json record{{"stamp_ns", stamp}, {"tracks", nlohmann::json::array()}};
  for (const auto& point : points_) {
    nlohmann::json entry{{"track", static_cast<std::int64_t>(point.track)},
                         {"p", {point.position_m.x(), point.position_m.y(), point.position_m.z()}}};
    if (const auto label = label_of(static_cast<std::int64_t>(point.track))) {
      entry["subject"] = label->subject;
      entry["marker"] = label->marker;
    }
    record["tracks"].push_back(std::move(entry));
  }
  out_->write_line(record.dump());
}

void LabelStage::update_map(TimeNs stamp) {
  std::vector<TrackLabel> map;
  for (const auto& [track, label] : labeller_.labels())
    map.push_back({static_cast<std::int64_t>(track), subjects_.at(label.subject), label.marker});
  const auto same = [](const TrackLabel& a, const TrackLabel& b) {
    return a.track == b.track && a.subject == b.subject && a.marker == b.marker;
  };
  if (generation_ != 0 && std::equal(map.begin(), map.end(), map_.begin(), map_.end(), same)) return;
  map_ = std::move(map);
  map_stamp_ns_ = stamp;
  ++generation_;
}

std::optional<TrackLabel> LabelStage::label_of(std::int64_t track) const {
  const auto found = std::find_if(labels_.begin(), labels_.end(),
                                  [track](const TrackLabel& label) { return label.track == track; });
  if (found == labels_.end()) return std::nullopt;
  return *found;
}

std::string LabelStage::summary() const {
  const double named = marker_frames_ == 0 ? 0.0
                                           : 100.0 * static_cast<double>(labelled_marker_frames_) /
                                                 static_cast<double>(marker_frames_);
  const double mean = frames_ == 0 ? 0.0 : total_us_ / static_cast<double>(frames_);
  char text[256];
  std::snprintf(text, sizeof text,
                "labels: %zu subject%s, %.2f %% of %llu confirmed marker-frames named, %.1f us per "
                "subject-frame (mean; worst %.0f us) over %llu labeller runs",
                subjects_.size(), subjects_.size() == 1 ? "" : "s", named,
                static_cast<unsigned long long>(marker_frames_), mean, worst_us_,
                static_cast<unsigned long long>(frames_));
  return text;
}

}  // namespace panoptes::session
