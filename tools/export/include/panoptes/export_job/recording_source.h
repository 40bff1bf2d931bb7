// SPDX-License-Identifier: Apache-2.0
// The records of an MCAP recording as they were published live (docs/recording.md, "Export a
// recording"): every MocapFrame of /panoptes/frames gives one track record per marker (stamped with
// the frame's stamp, labelled with the body marker the estimator gave it) and one pose record per
// tracked body; nothing is recomputed. The body descriptions of /panoptes/body_descriptions give the
// bodies' order and layout sizes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "panoptes/formats/record_source.h"
#include "panoptes/time.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::export_job {

inline constexpr const char* kFramesChannel = "/panoptes/frames";
inline constexpr const char* kDescriptionsChannel = "/panoptes/body_descriptions";
inline constexpr const char* kLabelsChannel = "/panoptes/labels";

// The names of subjects' markers by track id, from the newest rt/panoptes/labels map.
using TrackNames = std::unordered_map<std::int64_t, std::pair<std::string, std::string>>;

// Appends the records of one MocapFrame: per marker a TrackRecord (stamp: the frame's) and its
// label; per body with tracking_valid a PoseRecord (stamp: the frame's, horizon_ns: the frame
// body's prediction_horizon_ns, so stamp + horizon is the instant the pose describes). A marker
// of no body takes its subject's name from `names` (the map in force when the frame was recorded).
void append_frame_records(const msg::MocapFrame& frame, ExportRecords& out, const TrackNames& names = {});

// What a recording held besides the records.
struct RecordingContents {
  std::uint64_t frames = 0;              // MocapFrames decoded
  std::uint64_t fixed_rate_frames = 0;   // of them published at a fixed rate (source_frame -1)
  std::uint64_t first_frame_number = 0;  // MocapFrame.frame_number of the first and last frame
  std::uint64_t last_frame_number = 0;
  std::vector<TimeNs> frame_stamps;                 // of every frame, in file order
  std::map<std::string, std::size_t> layout_sizes;  // markers per described body
};

class RecordingRecordSource final : public RecordSource {
 public:
  explicit RecordingRecordSource(std::filesystem::path path);
  // Throws ConfigError naming the file: not an MCAP file, no /panoptes/frames channel, no frame
  // that decodes. Undecodable messages, damaged chunks and labels outside a described layout are
  // counted in ExportRecords::skipped ("<file>: ...").
  ExportRecords read() override;
  std::string describe() const override;
  const RecordingContents& contents() const { return contents_; }

 private:
  std::filesystem::path path_;
  RecordingContents contents_;
};

// "<body>_<n>" for body marker n (its index in the body's layout, as MocapFrame's body_marker).
std::string body_marker_name(const std::string& body, int marker);

}  // namespace panoptes::export_job
