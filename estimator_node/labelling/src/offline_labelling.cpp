// SPDX-License-Identifier: Apache-2.0
#include "panoptes/labelling/offline_labelling.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace panoptes::labelling {

namespace {

using Name = std::pair<std::size_t, std::string>;  // subject, marker

struct Held {
  std::size_t forward = 0;  // frames held by the forward pass
  std::size_t backward = 0;
  double weight = 0.0;  // the frames held, each by how well the name fits the pass's others then
};
using Votes = std::map<Name, Held>;

// A frame where a name has no other name of its segment to be checked against counts this much.
constexpr double kUncheckedWeight = 0.5;

// Per subject and marker: the model's distances to the other markers of its segment.
struct PairRule {
  std::string other;
  double mean_m = 0.0;
  double tolerance_m = 0.0;
};
using Rules = std::vector<std::map<std::string, std::vector<PairRule>>>;

Rules make_rules(const std::vector<SubjectModel>& models, const LabellerOptions& options) {
  Rules rules(models.size());
  for (std::size_t s = 0; s < models.size(); ++s) {
    for (const auto& segment : models[s].segments) {
      for (const auto& d : segment.distances) {
        const double tolerance = moving_tolerance(options, segment.name, d);
        rules[s][d.markers[0]].push_back({d.markers[1], d.mean_m, tolerance});
        rules[s][d.markers[1]].push_back({d.markers[0], d.mean_m, tolerance});
      }
    }
  }
  return rules;
}

// How well a name fits a pass's other names of its segment seen now: the fraction of the model's
// distances to them within the moving tolerance (kUncheckedWeight when none is seen). A pass that
// acquired a subject wrongly holds names whose distances do not fit.
double frame_weight(const Rules& rules, const Name& name, const Eigen::Vector3d& at,
                    const std::map<Name, Eigen::Vector3d>& named) {
  const auto found = rules[name.first].find(name.second);
  if (found == rules[name.first].end()) return kUncheckedWeight;
  double checked = 0.0;
  double fit = 0.0;
  for (const auto& rule : found->second) {
    const auto other = named.find({name.first, rule.other});
    if (other == named.end()) continue;
    checked += 1.0;
    fit += std::abs((other->second - at).norm() - rule.mean_m) <= rule.tolerance_m ? 1.0 : 0.0;
  }
  return checked == 0.0 ? kUncheckedWeight : fit / checked;
}

// The runs valid at each frame: the labeller's points (track id = run index + 1).
std::vector<std::vector<std::size_t>> runs_by_frame(const std::vector<TrackRun>& runs, std::size_t frames) {
  std::vector<std::vector<std::size_t>> by_frame(frames);
  for (std::size_t r = 0; r < runs.size(); ++r) {
    for (std::size_t f = runs[r].first; f < runs[r].last; ++f) by_frame[f].push_back(r);
  }
  return by_frame;
}

// One pass of the labeller over the frames, forward or backward; every frame a run holds a name is
// a vote for it, weighted by frame_weight.
// `seeds` name runs before the first instant; returns the names held at the last instant.
std::map<std::size_t, MarkerLabel> run_pass(const std::vector<SubjectModel>& models,
                                            const LabellerOptions& options, const MarkerSamples& tracks,
                                            const std::vector<TrackRun>& runs,
                                            const std::vector<std::vector<std::size_t>>& by_frame,
                                            bool backward, const std::map<std::size_t, MarkerLabel>& seeds,
                                            std::vector<Votes>& votes) {
  Labeller labeller(models, options);
  for (const auto& [run, label] : seeds) labeller.name_track(run + 1, label);
  std::map<std::size_t, MarkerLabel> last;
  const Rules rules = make_rules(models, options);
  const std::size_t frames = by_frame.size();
  std::vector<TrackPoint> points;
  std::map<Name, Eigen::Vector3d> named;
  for (std::size_t i = 0; i < frames; ++i) {
    const std::size_t f = backward ? frames - 1 - i : i;
    points.clear();
    for (std::size_t r : by_frame[f]) points.push_back({r + 1, tracks.position(f, runs[r].column)});
    labeller.update(points);
    named.clear();
    for (std::size_t r : by_frame[f]) {
      if (const auto label = labeller.label_of(r + 1))
        named[{label->subject, label->marker}] = tracks.position(f, runs[r].column);
    }
    for (std::size_t r : by_frame[f]) {
      const auto label = labeller.label_of(r + 1);
      if (!label) continue;
      const Name name{label->subject, label->marker};
      if (i + 1 == frames) last[r] = *label;
      Held& held = votes[r][name];
      ++(backward ? held.backward : held.forward);
      held.weight += frame_weight(rules, name, tracks.position(f, runs[r].column), named);
    }
  }
  return last;
}

struct Candidate {
  std::size_t run;
  Name name;
  double weight;
};

// Runs take names in order of frames held; a name is on one run at a time.
void assign(const std::vector<Votes>& votes, std::vector<TrackRun>& runs) {
  std::vector<Candidate> candidates;
  for (std::size_t r = 0; r < votes.size(); ++r) {
    for (const auto& [name, held] : votes[r]) candidates.push_back({r, name, held.weight});
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.weight > b.weight; });
  std::map<Name, std::vector<std::size_t>> holders;  // runs given each name
  for (const auto& candidate : candidates) {
    TrackRun& run = runs[candidate.run];
    if (run.label) continue;
    auto& taken = holders[candidate.name];
    const bool overlaps = std::any_of(taken.begin(), taken.end(), [&](std::size_t other) {
      return runs[other].first < run.last && run.first < runs[other].last;
    });
    if (overlaps) continue;
    taken.push_back(candidate.run);
    run.label = MarkerLabel{candidate.name.first, candidate.name.second};
    const auto& held = votes[candidate.run].at(candidate.name);
    run.forward_frames = held.forward;
    run.backward_frames = held.backward;
    run.passes_disagreed = votes[candidate.run].size() > 1;
  }
}

}  // namespace

std::vector<TrackRun> track_runs(const MarkerSamples& tracks) {
  std::vector<TrackRun> runs;
  const std::size_t frames = tracks.frame_count();
  for (std::size_t c = 0; c < tracks.point_count(); ++c) {
    std::size_t f = 0;
    while (f < frames) {
      if (!tracks.is_valid(f, c)) {
        ++f;
        continue;
      }
      TrackRun run;
      run.column = c;
      run.first = f;
      while (f < frames && tracks.is_valid(f, c)) ++f;
      run.last = f;
      runs.push_back(run);
    }
  }
  return runs;
}

OfflineLabelling label_offline(const std::vector<SubjectModel>& models, const MarkerSamples& tracks,
                               const LabellerOptions& options) {
  OfflineLabelling out;
  out.frames = tracks.frame_count();
  out.runs = track_runs(tracks);
  const auto by_frame = runs_by_frame(out.runs, out.frames);
  std::vector<Votes> votes(out.runs.size());
  // The backward pass starts from the forward pass's names at the end: it carries them back to the
  // frames before they were found (the start of the trial, a marker's return after a gap).
  const auto at_end = run_pass(models, options, tracks, out.runs, by_frame, false, {}, votes);
  run_pass(models, options, tracks, out.runs, by_frame, true, at_end, votes);
  assign(votes, out.runs);
  for (std::size_t r = 0; r < out.runs.size(); ++r) {
    const TrackRun& run = out.runs[r];
    out.run_frames += run.last - run.first;
    if (run.label) out.labelled_frames += run.last - run.first;
    for (const auto& [name, held] : votes[r]) out.forward_labelled_frames += held.forward;
    if (run.passes_disagreed) ++out.disagreements;
  }
  return out;
}

MarkerSamples labelled_trajectories(const SubjectModel& model, std::size_t subject,
                                    const MarkerSamples& tracks, const OfflineLabelling& labelling) {
  MarkerSamples out;
  out.source = tracks.source;
  out.rate_hz = tracks.rate_hz;
  std::map<std::string, std::size_t> column_of;
  for (const auto& segment : model.segments) {
    for (const auto& name : segment.tracked_marker_names()) {
      column_of[name] = out.names.size();
      out.names.push_back(name);
    }
  }
  const std::size_t frames = tracks.frame_count();
  out.positions.assign(frames * out.names.size(), Eigen::Vector3d::Zero());
  out.valid.assign(frames * out.names.size(), 0);
  for (const auto& run : labelling.runs) {
    if (!run.label || run.label->subject != subject) continue;
    const auto column = column_of.find(run.label->marker);
    if (column == column_of.end()) continue;
    for (std::size_t f = run.first; f < run.last; ++f) {
      out.positions[f * out.names.size() + column->second] = tracks.position(f, run.column);
      out.valid[f * out.names.size() + column->second] = 1;
    }
  }
  return out;
}

}  // namespace panoptes::labelling
