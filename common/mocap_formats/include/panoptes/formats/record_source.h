// SPDX-License-Identifier: Apache-2.0
// Where an export reads the estimator's records from. Today: the offline JSON Lines outputs
// (estimator_node --out-tracks / --out-poses) here; the MCAP recording reader
// (panoptes_export_job's RecordingRecordSource) implements the same interface.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/records.h"

namespace panoptes {

// The body marker a track was labelled as when it was published (MocapFrame's FrameMarker), or the
// subject's marker name it carried (rt/panoptes/labels, docs/marker_sets.md).
struct MarkerLabel {
  std::string body;     // "" : not a body's marker
  int marker = -1;      // index in the body's layout (BodyDescription.markers)
  std::string subject;  // "" : not a subject's marker
  std::string name;     // its marker-set name, e.g. "R.ASIS"
};

// A labelled subject: its name and its marker set's names in order.
struct SubjectOrder {
  std::string subject;
  std::vector<std::string> markers;
};

struct ExportRecords {
  std::vector<TrackRecord> tracks;
  std::vector<PoseRecord> poses;
  // Empty (the JSON Lines carry no labels), or one per track: its label in that record.
  std::vector<MarkerLabel> labels;
  // The bodies in the order of their descriptions (the bodies file), when the source knows it.
  std::vector<std::string> body_order;
  // The labelled subjects (rt/panoptes/labels), when the source knows them.
  std::vector<SubjectOrder> subject_order;
  // Records that could not be read, skipped and counted: "<file>:<line or offset>: <reason>".
  std::vector<std::string> skipped;
};

class RecordSource {
 public:
  virtual ~RecordSource() = default;
  // Throws ConfigError (or std::runtime_error) naming the file when it cannot be read at all.
  virtual ExportRecords read() = 0;
  virtual std::string describe() const = 0;
};

class JsonlRecordSource final : public RecordSource {
 public:
  JsonlRecordSource(std::optional<std::filesystem::path> tracks, std::optional<std::filesystem::path> poses);
  ExportRecords read() override;
  std::string describe() const override;

 private:
  std::optional<std::filesystem::path> tracks_;
  std::optional<std::filesystem::path> poses_;
};

}  // namespace panoptes
