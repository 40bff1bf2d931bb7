// SPDX-License-Identifier: Apache-2.0
// Offline labelling (issue 33 item 3, docs/marker_sets.md "Offline labelling"): the whole trial is
// known, so the Labeller runs forward and backward over it and each track run takes the name the
// two passes held it under longest, no name on two runs at once. Maths only: the files are
// panoptes_label's.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "panoptes/labelling/labeller.h"
#include "panoptes/labelling/subject_model.h"

namespace panoptes::labelling {

// One track as the labeller sees it: a column of the input over contiguous valid frames
// [first, last). A column with a hole is two runs (a new track id after the hole).
struct TrackRun {
  std::size_t column = 0;
  std::size_t first = 0;
  std::size_t last = 0;
  std::size_t forward_frames = 0;   // frames the forward pass named it `label`
  std::size_t backward_frames = 0;  // the same, backward
  bool passes_disagreed = false;    // a pass held another name, or none, for part of it
  std::optional<MarkerLabel> label;
};

struct OfflineLabelling {
  std::vector<TrackRun> runs;
  std::size_t frames = 0;
  std::size_t run_frames = 0;               // marker-frames of the input (every run's length)
  std::size_t labelled_frames = 0;          // of those, carrying a name
  std::size_t forward_labelled_frames = 0;  // the forward pass alone (what live labelling gives)
  std::size_t disagreements = 0;            // runs where the passes differed
};

// The valid runs of every column of `tracks` (names are not read: columns are anonymous tracks).
std::vector<TrackRun> track_runs(const MarkerSamples& tracks);

// Forward pass, backward pass, then per run the name held longest over both passes, taken in order
// of frames held as long as no run overlapping it in time already has that name.
OfflineLabelling label_offline(const std::vector<SubjectModel>& models, const MarkerSamples& tracks,
                               const LabellerOptions& options);

// The labelled trajectories of subject `subject`: one column per tracked marker of the model, in
// the model's order (segments, then their markers), valid where a run with that name is.
MarkerSamples labelled_trajectories(const SubjectModel& model, std::size_t subject,
                                    const MarkerSamples& tracks, const OfflineLabelling& labelling);

}  // namespace panoptes::labelling
