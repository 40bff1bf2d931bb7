// SPDX-License-Identifier: Apache-2.0
#include "panoptes/formats/record_source.h"

#include "panoptes/jsonl.h"

namespace panoptes {

JsonlRecordSource::JsonlRecordSource(std::optional<std::filesystem::path> tracks,
                                     std::optional<std::filesystem::path> poses)
    : tracks_(std::move(tracks)), poses_(std::move(poses)) {}

ExportRecords JsonlRecordSource::read() {
  ExportRecords records;
  if (tracks_) records.tracks = read_tracks(*tracks_, &records.skipped);
  if (poses_) records.poses = read_poses(*poses_, &records.skipped);
  return records;
}

std::string JsonlRecordSource::describe() const {
  std::string text;
  if (tracks_) text += "tracks " + tracks_->string();
  if (poses_) text += std::string(text.empty() ? "" : ", ") + "poses " + poses_->string();
  return text;
}

}  // namespace panoptes
