// SPDX-License-Identifier: Apache-2.0
// Live auto-labelling in a session (issue 33 item 2, docs/marker_sets.md "Live labelling"): after
// each camera frame the tracker processed, its confirmed point tracks go to a labelling::Labeller
// built from the subject models of --subjects (or `subjects:` in the settings YAML); a track then
// carries (subject, marker name) until it ends. With --out-labels, one JSONL record per processed
// frame lists the labelled tracks. Counts labelled marker-frames and the labelling cost.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/estimator/tracker.h"
#include "panoptes/jsonl.h"
#include "panoptes/labelling/labeller.h"
#include "panoptes/labelling/subject_model.h"

namespace panoptes::session {

// One labelled track of a frame.
struct TrackLabel {
  std::int64_t track = 0;
  std::string subject;
  std::string marker;
};

class LabelStage {
 public:
  // `out_path` empty: nothing is written. Throws if the file cannot be opened.
  // `period_ns` > 0: the labeller runs at most once per period (the processed frames between keep
  // the names their tracks have; a new track waits for the next run).
  LabelStage(std::vector<labelling::SubjectModel> models, const labelling::LabellerOptions& options,
             const std::string& out_path, TimeNs period_ns = 0);

  // Reads the subject model files (throws InputError/ConfigError naming the file).
  static LabelStage from_files(const std::vector<std::string>& subject_files,
                               const labelling::LabellerOptions& options, const std::string& out_path,
                               TimeNs period_ns = 0);

  // The tracker has just processed a frame: its confirmed tracks at that instant are labelled.
  void observe(const estimator::Tracker& tracker);

  // After observe(): the label of `track`, if any (the names the last observe() gave).
  std::optional<TrackLabel> label_of(std::int64_t track) const;
  const std::vector<TrackLabel>& labels() const { return labels_; }

  // The whole current map of names (rt/panoptes/labels, docs/marker_sets.md "Labels on the wire"):
  // every named track, sorted by track id, as of the newest labeller run, and a generation that
  // counts its changes (0: no run yet). A publisher writes the map when the generation moves.
  const std::vector<TrackLabel>& map() const { return map_; }
  std::uint64_t generation() const { return generation_; }
  TimeNs map_stamp_ns() const { return map_stamp_ns_; }
  // The subject models, in --subjects order (names, marker sets, markers and sticks).
  const labelling::SubjectModel& model(std::size_t subject) const { return labeller_.model(subject); }
  std::size_t subject_count() const { return subjects_.size(); }

  void flush() {
    if (out_) out_->flush();
  }

  // "labels: N subjects, X % of confirmed marker-frames named, C us per subject-frame (mean), ..."
  std::string summary() const;

 private:
  void update_map(TimeNs stamp);

  std::vector<std::string> subjects_;  // before labeller_: built from the models it takes
  labelling::Labeller labeller_;
  std::optional<JsonlWriter> out_;
  std::vector<TrackLabel> labels_;
  std::vector<TrackLabel> map_;
  std::uint64_t generation_ = 0;
  TimeNs map_stamp_ns_ = 0;
  std::vector<labelling::TrackPoint> points_;
  TimeNs period_ns_ = 0;
  TimeNs last_stamp_ns_ = 0;
  TimeNs last_run_ns_ = 0;
  std::uint64_t frames_ = 0;
  std::uint64_t marker_frames_ = 0;
  std::uint64_t labelled_marker_frames_ = 0;
  double total_us_ = 0.0;
  double worst_us_ = 0.0;
};

}  // namespace panoptes::session
