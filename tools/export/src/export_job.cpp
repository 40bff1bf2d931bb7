// SPDX-License-Identifier: Apache-2.0
#include "panoptes/export_job/export_job.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "panoptes/errors.h"
#include "panoptes/export_job/recording_source.h"
#include "panoptes/formats/c3d.h"
#include "panoptes/formats/csv.h"
#include "panoptes/formats/record_source.h"
#include "panoptes/formats/resample.h"
#include "panoptes/formats/trc.h"
#include "panoptes/jsonl.h"

namespace fs = std::filesystem;

namespace panoptes::export_job {
namespace {

struct Exported {
  MarkerTrajectories markers;
  BodyTrajectories bodies;
  std::size_t skipped = 0;
  std::size_t recorded_frames = 0;
  std::size_t labelled_markers = 0;
};

// The tracks of the marker files: a track labelled as a body marker in a record becomes, for that
// record, the point "<body>_<n>" (ids below every track id, in the bodies' order, then by marker);
// unlabelled records stay their track. Returns the names of the labelled points by id.
// A subject's marker (rt/panoptes/labels) becomes the point of its name ("R.ASIS"; "s1:R.ASIS" when
// the recording names several subjects), after the bodies, in the marker set's order.
std::map<std::int64_t, std::string> label_tracks(const ExportRecords& records,
                                                 std::vector<TrackRecord>& tracks) {
  // Bodies in the descriptions' order, then any other labelled body as first met; then subjects.
  std::map<std::string, std::size_t> rank;
  for (const std::string& body : records.body_order) rank.emplace(body, rank.size());
  for (const MarkerLabel& label : records.labels)
    if (!label.body.empty()) rank.emplace(label.body, rank.size());
  std::map<std::string, std::size_t> subject_rank;
  std::map<std::pair<std::string, std::string>, std::int64_t> marker_index;
  for (const SubjectOrder& subject : records.subject_order) {
    subject_rank.emplace(subject.subject, rank.size() + subject_rank.size());
    for (std::size_t i = 0; i < subject.markers.size(); ++i)
      marker_index.emplace(std::make_pair(subject.subject, subject.markers[i]), static_cast<std::int64_t>(i));
  }
  const bool several_subjects = subject_rank.size() > 1;
  constexpr std::int64_t kFirstLabelId = std::numeric_limits<std::int64_t>::min() / 2;
  constexpr std::int64_t kMarkersPerBody = 1 << 20;
  const auto id_of = [&](const MarkerLabel& label) {
    return kFirstLabelId + static_cast<std::int64_t>(rank.at(label.body)) * kMarkersPerBody +
           std::clamp<std::int64_t>(label.marker, 0, kMarkersPerBody - 1);
  };
  std::map<std::int64_t, std::string> names;
  tracks = records.tracks;
  for (std::size_t i = 0; i < records.labels.size() && i < tracks.size(); ++i) {
    const MarkerLabel& label = records.labels[i];
    if (!label.body.empty()) {
      tracks[i].id = id_of(label);
      names.emplace(tracks[i].id, body_marker_name(label.body, label.marker));
      continue;
    }
    const auto subject = subject_rank.find(label.subject);
    const auto index = marker_index.find({label.subject, label.name});
    if (label.name.empty() || subject == subject_rank.end() || index == marker_index.end()) continue;
    tracks[i].id = kFirstLabelId + static_cast<std::int64_t>(subject->second) * kMarkersPerBody +
                   std::clamp<std::int64_t>(index->second, 0, kMarkersPerBody - 1);
    names.emplace(tracks[i].id, several_subjects ? label.subject + ":" + label.name : label.name);
  }
  return names;
}

// The clock of a recording made only of fixed-rate frames (docs/frames.md): its rate (whole Hz,
// from the median interval between the frames' stamps) and its first and last instants (frames
// without a track or body included).
struct RecordedClock {
  int rate_hz = 0;
  TimeNs first_ns = 0;
  TimeNs last_ns = 0;
};

std::optional<RecordedClock> recorded_clock(const RecordingContents& contents) {
  if (contents.frames < 2 || contents.fixed_rate_frames != contents.frames) return std::nullopt;
  std::vector<TimeNs> stamps = contents.frame_stamps;
  std::sort(stamps.begin(), stamps.end());
  stamps.erase(std::unique(stamps.begin(), stamps.end()), stamps.end());
  std::vector<TimeNs> intervals;
  for (std::size_t i = 1; i < stamps.size(); ++i) intervals.push_back(stamps[i] - stamps[i - 1]);
  if (intervals.empty()) return std::nullopt;
  const auto middle = intervals.begin() + static_cast<std::ptrdiff_t>(intervals.size() / 2);
  std::nth_element(intervals.begin(), middle, intervals.end());
  const auto rate = std::llround(1e9 / static_cast<double>(*middle));
  if (rate < 1 || rate > 10000) return std::nullopt;
  return RecordedClock{static_cast<int>(rate), stamps.front(), stamps.back()};
}

void write_records(const ExportOptions& options, const ExportRecords& records) {
  if (!options.out_tracks.empty()) {
    JsonlWriter writer(options.out_tracks);
    for (const TrackRecord& track : records.tracks) writer.write(track);
    writer.flush();
  }
  if (!options.out_poses.empty()) {
    JsonlWriter writer(options.out_poses);
    for (const PoseRecord& pose : records.poses) writer.write(pose);
    writer.flush();
  }
}

Exported from_records(const ExportOptions& options) {
  std::unique_ptr<RecordSource> source;
  RecordingRecordSource* recording = nullptr;
  if (!options.in_recording.empty()) {
    auto owned = std::make_unique<RecordingRecordSource>(options.in_recording);
    recording = owned.get();
    source = std::move(owned);
  } else {
    source = std::make_unique<JsonlRecordSource>(
        options.tracks.empty() ? std::nullopt : std::optional<fs::path>(options.tracks),
        options.poses.empty() ? std::nullopt : std::optional<fs::path>(options.poses));
  }
  ExportRecords records = source->read();
  for (const std::string& error : records.skipped) std::fprintf(stderr, "skipped %s\n", error.c_str());
  if (records.tracks.empty() && records.poses.empty()) {
    throw ConfigError(source->describe(), "", "no track or pose records to export");
  }
  write_records(options, records);
  ResampleOptions resample;
  resample.rate_hz = options.rate_hz;
  resample.max_gap_ns = static_cast<TimeNs>(options.max_gap_ms * 1e6);
  resample.include_tentative = options.include_tentative;
  std::vector<TrackRecord> labelled;
  resample.marker_names = label_tracks(records, labelled);
  SampleGrid grid = make_grid(records.tracks, records.poses, resample);
  if (recording != nullptr && !options.rate_given) {
    if (const auto clock = recorded_clock(recording->contents()))
      grid = fixed_rate_grid(clock->first_ns, clock->last_ns, clock->rate_hz);
  }
  Exported out;
  out.markers = resample_tracks(labelled, grid, resample);
  out.bodies = resample_poses(records.poses, grid, resample);
  if (!options.no_body_points) append_body_origins(out.markers, out.bodies);
  out.skipped = records.skipped.size();
  out.recorded_frames = recording != nullptr ? recording->contents().frames : 0;
  std::set<std::string> labelled_names;
  for (const auto& [id, name] : resample.marker_names) labelled_names.insert(name);
  for (const std::string& name : out.markers.marker_names) out.labelled_markers += labelled_names.count(name);
  return out;
}

}  // namespace

std::optional<OptionsProblem> find_problem(const ExportOptions& options) {
  const bool records = !options.tracks.empty() || !options.poses.empty();
  const int inputs =
      (records ? 1 : 0) + (options.markers.empty() ? 0 : 1) + (options.in_recording.empty() ? 0 : 1);
  if (inputs != 1)
    return OptionsProblem{"input", "give --tracks and/or --poses, --markers, or --in-recording"};
  if (options.c3d.empty() && options.trc.empty() && options.csv.empty() && options.bodies_csv.empty() &&
      options.out_tracks.empty() && options.out_poses.empty())
    return OptionsProblem{
        "output", "give at least one of --out, --c3d, --trc, --csv, --bodies-csv, --out-tracks, --out-poses"};
  if (!options.markers.empty() && !options.bodies_csv.empty())
    return OptionsProblem{"--bodies-csv", "needs --poses or --in-recording"};
  if (options.in_recording.empty() && !options.out_tracks.empty())
    return OptionsProblem{"--out-tracks", "needs --in-recording"};
  if (options.in_recording.empty() && !options.out_poses.empty())
    return OptionsProblem{"--out-poses", "needs --in-recording"};
  return std::nullopt;
}

namespace {
std::string lower_extension(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}
}  // namespace

bool set_output(ExportOptions& options, const std::string& path) {
  const std::string extension = lower_extension(path);
  std::string* target = extension == ".c3d"   ? &options.c3d
                        : extension == ".trc" ? &options.trc
                        : extension == ".csv" ? &options.csv
                                              : nullptr;
  if (target == nullptr) return false;
  *target = path;
  return true;
}

bool set_poses_output(ExportOptions& options, const std::string& path) {
  const std::string extension = lower_extension(path);
  if (extension == ".jsonl") {
    options.out_poses = path;
  } else if (extension == ".csv") {
    options.bodies_csv = path;
  } else {
    return false;
  }
  return true;
}

namespace {

// Markers and body poses turned from the recorded z-up world into `axis`.
void turn_to_up_axis(Exported& data, UpAxis axis) {
  if (axis == UpAxis::kZ) return;
  for (auto& p : data.markers.positions) {
    const auto turned = vector_to_up_axis(axis, {p.x(), p.y(), p.z()});
    p = Eigen::Vector3d(turned[0], turned[1], turned[2]);
  }
  for (auto& p : data.bodies.positions) {
    const auto turned = vector_to_up_axis(axis, {p.x(), p.y(), p.z()});
    p = Eigen::Vector3d(turned[0], turned[1], turned[2]);
  }
  for (auto& q : data.bodies.quaternions) {
    const auto turned = orientation_to_up_axis(axis, {q[0], q[1], q[2], q[3]});
    q = Eigen::Vector4d(turned[0], turned[1], turned[2], turned[3]);
  }
}

}  // namespace

MarkerFileFormat marker_file_format(const std::string& path) {
  return lower_extension(path) == ".c3d" ? MarkerFileFormat::kC3d : MarkerFileFormat::kTrc;
}

ExportSummary run_export(const ExportOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  Exported data;
  if (!options.markers.empty()) {
    data.markers = marker_file_format(options.markers) == MarkerFileFormat::kC3d ? load_c3d(options.markers)
                                                                                 : load_trc(options.markers);
  } else {
    data = from_records(options);
  }
  data.markers.units = options.units;
  turn_to_up_axis(data, options.up_axis);
  const bool any_markers = data.markers.marker_count() > 0;
  if (!any_markers && (!options.c3d.empty() || !options.trc.empty() || !options.csv.empty())) {
    throw ConfigError(!options.in_recording.empty() ? options.in_recording
                      : options.tracks.empty()      ? options.poses
                                                    : options.tracks,
                      "", "no confirmed tracks or bodies to write as markers");
  }
  if (!options.c3d.empty())
    write_c3d(options.c3d, data.markers, C3dWriteOptions{options.units, "panoptes_export"});
  if (!options.trc.empty()) write_trc(options.trc, data.markers);
  if (!options.csv.empty()) write_markers_csv(options.csv, data.markers);
  if (!options.bodies_csv.empty()) write_bodies_csv(options.bodies_csv, data.bodies);
  ExportSummary summary;
  summary.frames = data.markers.frame_count();
  summary.markers = data.markers.marker_count();
  summary.bodies = data.bodies.body_count();
  summary.rate_hz = data.markers.data_rate_hz;
  summary.skipped_records = data.skipped;
  summary.recorded_frames = data.recorded_frames;
  summary.labelled_markers = data.labelled_markers;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

std::string summary_line(const ExportSummary& summary) {
  char line[320];
  std::snprintf(
      line, sizeof line,
      "{\"frames\": %zu, \"markers\": %zu, \"bodies\": %zu, \"rate_hz\": %.6g, \"skipped_records\": "
      "%zu, \"seconds\": %.3f",
      summary.frames, summary.markers, summary.bodies, summary.rate_hz, summary.skipped_records,
      summary.seconds);
  std::string text = line;
  if (summary.recorded_frames > 0) {
    std::snprintf(line, sizeof line, ", \"recorded_frames\": %zu, \"labelled_markers\": %zu",
                  summary.recorded_frames, summary.labelled_markers);
    text += line;
  }
  return text + "}";
}

}  // namespace panoptes::export_job
