// SPDX-License-Identifier: Apache-2.0
// Auto-labelling (issue 33 item 2, docs/marker_sets.md "Labelling"): per instant, the unlabelled
// point tracks in, a map track id -> (subject, marker) kept. Maths only: no DDS, no files; the
// estimator session (live) and panoptes_label run (offline) feed it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "panoptes/labelling/subject_model.h"

namespace panoptes::labelling {

struct TrackPoint {
  std::uint64_t track = 0;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
};

struct MarkerLabel {
  std::size_t subject = 0;  // index into the labeller's models
  std::string marker;
};

struct LabellerOptions {
  // A marker-pair distance matches the model when |d - mean| <= tolerance + allowance_m +
  // allowance_fraction * mean: the static model's tolerances (2-3 mm) hold only 56-63 % of a
  // walk's distances, soft tissue moves the markers by 1-9 mm.
  double allowance_m = 0.010;
  double allowance_fraction = 0.06;
  // Segments that deform while moving (the torso: the shoulders), with this fraction instead.
  std::vector<std::string> soft_segments;
  double soft_fraction = 0.30;
  // A child segment is searched within reach_m + reach_fraction * |static offset| of where its
  // parent's pose puts its origin; a joint centre seen from both segments must agree within
  // joint_gate_m; a child turned more than max_relative_rotation_rad from its parent in the static
  // pose is refused (the mirrored, upside-down hypotheses).
  double reach_m = 0.10;
  double reach_fraction = 0.6;
  double joint_gate_m = 0.05;
  double max_relative_rotation_rad = 1.8;
  // A marker of a segment without a pose lies on a shell about its parent's marker nearest to it
  // in the static pose: |distance - static distance| <= shell_m + shell_fraction * static distance.
  double shell_m = 0.02;
  double shell_fraction = 0.15;
  // Two markers of a segment without a pose keep the static pose's handedness with their parent's
  // two nearest markers when its magnitude (normalised signed volume) is at least this.
  double min_handedness = 0.04;
  // A new track takes a waiting name when it lies within this of the name's prediction (the
  // segment's rigid fit from its other markers; `loose` when only a translation is known).
  double gate_m = 0.025;
  double loose_gate_m = 0.045;
  // The rigid gate widens per marker by residual_gate times its running distance from its
  // segment's fit (learned while it is seen, rate residual_rate per instant): soft tissue and
  // markers near joints (Rajagopal's knee and thigh markers) move away from the static layout.
  double residual_gate = 3.0;
  double residual_rate = 0.1;
  std::size_t root_hypotheses = 24;  // best-fitting root candidates grown over the tree
  std::size_t min_markers = 8;       // fewer markers found: the subject is not acquired
  // A track seen for fewer instants is not used to acquire a subject or a segment (false blobs
  // make short tracks); a waiting name may still go to it.
  int min_track_age = 3;
  // Live (update with a time): a named track missing from an instant keeps its name this long
  // before the name waits for another track; it keeps it for good if it comes back. The estimator
  // leaves a track out of an instant now and then (coasting, or not determined while one camera's
  // frames were processed alone): ending the name at once made every such blink a re-acquisition,
  // and a labeller run on every camera frame lost and mirrored most names (docs/marker_sets.md).
  double keep_absent_s = 0.25;
  // An acquired subject is searched afresh every revise_period_s (live; offline every
  // revise_period_instants updates) while at least revise_margin mature tracks are unnamed: the
  // whole tree, then each segment's subtree from its parent's pose; a hypothesis explaining
  // revise_margin more of the markers seen now than the names do replaces them (a subject acquired
  // wrongly while a marker was hidden, docs/marker_sets.md "Live labelling").
  double revise_period_s = 0.1;
  int revise_period_instants = 12;
  std::size_t revise_margin = 2;
  // Two named tracks of a rigid segment that exchanged their markers (the tracker swapped two close
  // markers: seen live under CPU contention, a foot's midfoot and toe) keep their names while the
  // segment's rigid fit worsens by their distance; no revision sees it (as many markers explained).
  // A rigid segment (not soft) whose fit RMS exceeds untangle_rms_m is refitted with each pair of
  // its named points exchanged, and an exchange whose RMS is below untangle_ratio of it moves the
  // two names.
  double untangle_rms_m = 0.010;
  double untangle_ratio = 0.5;
  // A rigid segment whose fit RMS exceeds release_rms_m and that no exchange of two names fits (the
  // tracker moved three of its tracks round, or one onto another segment's marker: seen live under
  // CPU contention, test_live_labels) releases the one name whose track leaving makes the rest fit
  // within untangle_rms_m, else all its names and its pose; they wait for the right tracks.
  double release_rms_m = 0.020;
};

// The tolerance of a marker-pair distance of `segment` while the subject moves (see allowance_m).
double moving_tolerance(const LabellerOptions& options, const std::string& segment,
                        const DistanceStatistics& distance);

class Labeller {
 public:
  explicit Labeller(std::vector<SubjectModel> models, LabellerOptions options = {});
  ~Labeller();
  Labeller(Labeller&&) noexcept;
  Labeller& operator=(Labeller&&) noexcept;

  // One instant: every track seen now (unique ids). Without a time (offline, every instant complete)
  // tracks absent since the last call have ended; with `time_s` (live) a named track absent for
  // longer than keep_absent_s has, and one absent for less keeps its name while it is away.
  void update(const std::vector<TrackPoint>& points, std::optional<double> time_s = std::nullopt);

  // Before the next update: `track` carries `label` (a name known from elsewhere: offline, the other
  // pass's names at the instant this pass starts from). The name leaves the track it was on, the
  // track its own name. An unknown subject or marker (or a calibration-only one) is ignored.
  void name_track(std::uint64_t track, const MarkerLabel& label);

  std::optional<MarkerLabel> label_of(std::uint64_t track) const;
  // Every named track (those briefly missing live too), by track id.
  std::vector<std::pair<std::uint64_t, MarkerLabel>> labels() const;
  const SubjectModel& model(std::size_t subject) const;
  // How many pairs of names untangle() has moved (LabellerOptions::untangle_rms_m) so far.
  std::uint64_t untangled() const;
  // How many names release_rms_m has taken from tracks so far.
  std::uint64_t released() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace panoptes::labelling
