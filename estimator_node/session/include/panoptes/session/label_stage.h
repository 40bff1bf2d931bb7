// SPDX-License-Identifier: Apache-2.0
// Live auto-labelling in a session (issue 33 item 2, docs/marker_sets.md "Live labelling"): after
// each camera frame the tracker processed, its confirmed point tracks go to a labelling::Labeller
// built from the subject models of --subjects (or `subjects:` in the settings YAML); a track then
// carries (subject, marker name) until it ends. With --out-labels, one JSONL record per processed
// frame lists the labelled tracks. Counts labelled marker-frames and the labelling cost.
#pragma once

#include <cstdint>
#include <memory>
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

// The whole current map of names (rt/panoptes/labels, docs/marker_sets.md "Labels on the wire"):
// every named track, sorted by track id, as of the newest labeller run, and a generation that
// counts its changes (0: no run yet). A publisher writes the map when the generation moves.
struct LabelMap {
  std::vector<TrackLabel> labels;
  std::uint64_t generation = 0;
  TimeNs stamp_ns = 0;
};

class LabelStage {
 public:
  // `out_path` empty: nothing is written. Throws if the file cannot be opened.
  // `period_ns` > 0: the labeller runs at most once per period (the processed frames between keep
  // the names their tracks have; a new track waits for the next run).
  LabelStage(std::vector<labelling::SubjectModel> models, const labelling::LabellerOptions& options,
             const std::string& out_path, TimeNs period_ns = 0);
  ~LabelStage();
  LabelStage(LabelStage&&) noexcept;
  LabelStage& operator=(LabelStage&&) noexcept;
  LabelStage(const LabelStage&) = delete;
  LabelStage& operator=(const LabelStage&) = delete;

  // Reads the subject model files (throws InputError/ConfigError naming the file).
  static LabelStage from_files(const std::vector<std::string>& subject_files,
                               const labelling::LabellerOptions& options, const std::string& out_path,
                               TimeNs period_ns = 0);

  // Live (docs/marker_sets.md, "Off the frame path"): from now on the labeller runs on a thread of
  // its own. observe() hands it the confirmed tracks when a run is due and returns at once (a run
  // still busy is not waited for: the newest tracks replace a job not yet started), so a revision
  // search of milliseconds delays no frame; the names come from the newest finished run. Unless
  // that run is more than max_lag_ns() older than the frame (the worker got no CPU while the frame
  // path caught up a backlog: seen 110 frames, 299 ms of stamps, on a loaded 2-core machine): then
  // the frame waits for the run just posted (counted in summary()). Offline replays do not call it:
  // there every run finishes before observe() returns (reproducible).
  void run_in_background();
  // Waits until the background run under way, and the job waiting, if any, are done (at once when
  // not in the background).
  void drain();

  // The tracker has just processed a frame: its confirmed tracks at that instant are labelled.
  void observe(const estimator::Tracker& tracker);
  // The same with the tracker's current_tracks() the caller already has (the live path needs them
  // for the frame anyway: no second copy).
  void observe(const estimator::Tracker& tracker, const std::vector<TrackRecord>& current_tracks);

  // How far behind a frame's stamp its names' run may be live: 4 labeller periods, at least 20 ms
  // (33 ms at the default 120 Hz), unless set (0: every due frame waits for its own run, so the
  // names are the inline stage's).
  TimeNs max_lag_ns() const { return max_lag_ns_; }
  void set_max_lag_ns(TimeNs lag) { max_lag_ns_ = lag; }

  // After observe(): the label of `track`, if any (in the map the last observe() saw).
  std::optional<TrackLabel> label_of(std::int64_t track) const;

  // The newest map (never null; generation 0 before the first run). Safe from any thread.
  std::shared_ptr<const LabelMap> map() const;
  // The subject models, in --subjects order (names, marker sets, markers and sticks).
  const labelling::SubjectModel& model(std::size_t subject) const;
  std::size_t subject_count() const;

  void flush() {
    if (out_) out_->flush();
  }

  // "labels: N subjects, X % of confirmed marker-frames (at the labeller's runs) named, C us per
  // subject-frame (mean), ..."
  std::string summary() const;

 private:
  struct Core;  // the labeller, its map and its worker thread (fixed in memory: moves keep it)

  std::unique_ptr<Core> core_;
  std::optional<JsonlWriter> out_;
  const TrackLabel* find(std::int64_t track) const;  // in names_, sorted by track

  std::shared_ptr<const LabelMap> names_;  // the map the last observe() saw
  std::vector<labelling::TrackPoint> points_;
  TimeNs period_ns_ = 0;
  TimeNs max_lag_ns_ = 0;
  TimeNs last_stamp_ns_ = 0;
  TimeNs last_run_ns_ = 0;
  std::uint64_t marker_frames_ = 0;
  std::uint64_t labelled_marker_frames_ = 0;
  std::uint64_t waits_ = 0;  // frames that waited for a run (max_lag_ns)
};

}  // namespace panoptes::session
