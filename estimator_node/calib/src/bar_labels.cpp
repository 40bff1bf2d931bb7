// SPDX-License-Identifier: Apache-2.0
#include "panoptes/calib/bar_labels.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <utility>

#include <Eigen/Core>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "panoptes/union_find.h"

namespace panoptes::calib {

namespace {

// One camera's view of the bar's ends at one instant, normalised image coordinates.
struct EndsView {
  int node = 0;  // (camera, run)
  Eigen::Vector2d first, last;
};

struct PairSample {
  EndsView a, b;
};

struct Votes {
  int same = 0, flipped = 0;
};

// First-order geometric distance of a correspondence to the epipolar constraint x_b' E x_a = 0.
double sampson_distance(const Eigen::Matrix3d& E, const Eigen::Vector2d& xa, const Eigen::Vector2d& xb) {
  const Eigen::Vector3d a = xa.homogeneous(), b = xb.homogeneous();
  const Eigen::Vector3d Ea = E * a, Etb = E.transpose() * b;
  const double e = b.dot(Ea);
  const double denominator = Ea.head<2>().squaredNorm() + Etb.head<2>().squaredNorm();
  return denominator > 0 ? std::abs(e) / std::sqrt(denominator) : std::numeric_limits<double>::infinity();
}

std::optional<Eigen::Matrix3d> essential(const std::vector<cv::Point2d>& a, const std::vector<cv::Point2d>& b,
                                         double threshold) {
  if (a.size() < 8) return std::nullopt;
  cv::Mat mask;
  const cv::Mat E = cv::findEssentialMat(a, b, 1.0, cv::Point2d(0, 0), cv::RANSAC, 0.999, threshold, mask);
  if (E.rows < 3 || E.cols != 3 || cv::countNonZero(mask) < static_cast<int>(a.size()) / 2)
    return std::nullopt;
  Eigen::Matrix3d result;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) result(r, c) = E.at<double>(r, c);  // the first solution if several
  return result;
}

// Votes of one camera pair per pair of runs: does b's run label the ends as a's does, or reversed?
std::map<std::pair<int, int>, Votes> vote(const std::vector<PairSample>& samples, const Eigen::Matrix3d& E,
                                          double threshold, double ratio) {
  std::map<std::pair<int, int>, Votes> votes;
  for (const auto& s : samples) {
    const double same = sampson_distance(E, s.a.first, s.b.first) + sampson_distance(E, s.a.last, s.b.last);
    const double flipped =
        sampson_distance(E, s.a.first, s.b.last) + sampson_distance(E, s.a.last, s.b.first);
    const double better = std::min(same, flipped), worse = std::max(same, flipped);
    if (!(worse - better > threshold && worse > ratio * better)) continue;  // both labellings fit
    auto& v = votes[{s.a.node, s.b.node}];
    (same < flipped ? v.same : v.flipped) += 1;
  }
  return votes;
}

// One run of a camera's track: frames between two relabellings, with the ends labelled alike.
struct Run {
  int camera = 0;
  int label_run = 0;
  CameraWandTrack frames;
};

// Every camera's track cut into runs (the graph's nodes), and the span and fastest period of all.
struct RunSet {
  std::vector<Run> runs;
  std::vector<std::vector<int>> runs_of_camera;
  TimeNs first = std::numeric_limits<TimeNs>::max(), last = std::numeric_limits<TimeNs>::min();
  double period = std::numeric_limits<double>::infinity();
};

RunSet split_into_runs(const std::vector<CameraWandTrack>& tracks) {
  RunSet set;
  auto& runs = set.runs;
  auto& runs_of_camera = set.runs_of_camera;
  runs_of_camera.resize(tracks.size());
  for (std::size_t c = 0; c < tracks.size(); ++c) {
    const auto& track = tracks[c];
    for (const auto& frame : track.frames) {
      if (runs_of_camera[c].empty() ||
          runs[static_cast<std::size_t>(runs_of_camera[c].back())].label_run != frame.label_run) {
        runs_of_camera[c].push_back(static_cast<int>(runs.size()));
        Run run;
        run.camera = static_cast<int>(c);
        run.label_run = frame.label_run;
        run.frames.camera_id = track.camera_id;
        run.frames.frame_period_s = track.frame_period_s;
        runs.push_back(std::move(run));
      }
      runs[static_cast<std::size_t>(runs_of_camera[c].back())].frames.frames.push_back(frame);
    }
    if (!track.frames.empty()) {
      set.first = std::min(set.first, track.frames.front().stamp_ns);
      set.last = std::max(set.last, track.frames.back().stamp_ns);
      if (track.frame_period_s > 0) set.period = std::min(set.period, track.frame_period_s);
    }
  }
  return set;
}

// Every camera's view of the ends on a common grid of instants, interpolated within its run,
// gathered per camera pair.
std::map<std::pair<int, int>, std::vector<PairSample>> sample_camera_pairs(
    const RunSet& set, const std::vector<CameraIntrinsics>& intrinsics, const BarLabelOptions& options) {
  const auto& runs = set.runs;
  const auto& runs_of_camera = set.runs_of_camera;
  const std::size_t cameras = runs_of_camera.size();
  const double rate = options.sample_rate_hz > 0 ? options.sample_rate_hz : 1.0 / set.period;
  const auto step = static_cast<TimeNs>(std::llround(1e9 / rate));
  std::vector<CameraModel> models;
  models.reserve(intrinsics.size());
  for (const auto& k : intrinsics) models.emplace_back(k, RigidTransform{});
  std::map<std::pair<int, int>, std::vector<PairSample>> pairs;
  std::vector<std::size_t> cursor(cameras, 0);
  for (TimeNs t = set.first + step / 2; t < set.last; t += step) {
    std::vector<std::pair<int, EndsView>> views;
    for (std::size_t c = 0; c < cameras; ++c) {
      auto& k = cursor[c];
      const auto& list = runs_of_camera[c];
      while (k < list.size() && runs[static_cast<std::size_t>(list[k])].frames.frames.back().stamp_ns <= t)
        ++k;
      if (k == list.size()) continue;
      const Run& run = runs[static_cast<std::size_t>(list[k])];
      const auto segment = find_segment(run.frames, t, options.max_gap_frames * run.frames.frame_period_s);
      if (!segment) continue;
      const std::size_t markers = segment->p0.size();
      EndsView view;
      view.node = list[k];
      view.first = models[c].pixel_to_normalized(evaluate_segment(*segment, 0, 0.0));
      view.last = models[c].pixel_to_normalized(evaluate_segment(*segment, markers - 1, 0.0));
      views.emplace_back(static_cast<int>(c), view);
    }
    for (std::size_t i = 0; i < views.size(); ++i)
      for (std::size_t j = i + 1; j < views.size(); ++j)
        pairs[{views[i].first, views[j].first}].push_back({views[i].second, views[j].second});
  }
  return pairs;
}

// One camera pair's votes: first from an essential matrix of the midpoints, then again from one of
// the ends labelled by those votes. Nothing when the pair has too few samples or no geometry.
std::optional<std::map<std::pair<int, int>, Votes>> camera_pair_votes(const std::vector<PairSample>& samples,
                                                                      const BarLabelOptions& options) {
  if (static_cast<int>(samples.size()) < options.min_pair_samples) return std::nullopt;
  const std::size_t stride =
      std::max<std::size_t>(1, samples.size() / static_cast<std::size_t>(options.max_pair_samples));
  std::vector<cv::Point2d> mid_a, mid_b;
  for (std::size_t s = 0; s < samples.size(); s += stride) {
    const Eigen::Vector2d a = 0.5 * (samples[s].a.first + samples[s].a.last);
    const Eigen::Vector2d b = 0.5 * (samples[s].b.first + samples[s].b.last);
    mid_a.emplace_back(a.x(), a.y());
    mid_b.emplace_back(b.x(), b.y());
  }
  auto E = essential(mid_a, mid_b, options.midpoint_threshold);
  if (!E) return std::nullopt;
  auto pair_votes = vote(samples, *E, options.midpoint_threshold, options.decisive_ratio);
  std::vector<cv::Point2d> ends_a, ends_b;
  for (std::size_t s = 0; s < samples.size(); s += stride) {
    const auto found = pair_votes.find({samples[s].a.node, samples[s].b.node});
    if (found == pair_votes.end() || std::abs(found->second.same - found->second.flipped) < options.min_votes)
      continue;
    const bool flipped = found->second.flipped > found->second.same;
    const auto& a = samples[s].a;
    const auto& b = samples[s].b;
    ends_a.emplace_back(a.first.x(), a.first.y());
    ends_a.emplace_back(a.last.x(), a.last.y());
    const Eigen::Vector2d& b_first = flipped ? b.last : b.first;
    const Eigen::Vector2d& b_last = flipped ? b.first : b.last;
    ends_b.emplace_back(b_first.x(), b_first.y());
    ends_b.emplace_back(b_last.x(), b_last.y());
  }
  if (auto refined = essential(ends_a, ends_b, options.midpoint_threshold / 4)) {
    E = refined;
    pair_votes = vote(samples, *E, options.midpoint_threshold / 4, options.decisive_ratio);
  }
  return pair_votes;
}

}  // namespace

BarLabelReport resolve_bar_labels(std::vector<CameraWandTrack>& tracks,
                                  const std::vector<CameraIntrinsics>& intrinsics,
                                  const BarLabelOptions& options) {
  BarLabelReport report;
  // Nodes: every (camera, run), each with a sub-track of its frames to interpolate within.
  const RunSet set = split_into_runs(tracks);
  const auto& runs = set.runs;
  const auto& runs_of_camera = set.runs_of_camera;
  report.runs = static_cast<int>(runs.size());
  if (runs.empty() || set.first >= set.last || !std::isfinite(set.period)) return report;

  const auto pairs = sample_camera_pairs(set, intrinsics, options);
  std::map<std::pair<int, int>, Votes> votes;
  for (const auto& [key, samples] : pairs) {
    const auto pair_votes = camera_pair_votes(samples, options);
    if (!pair_votes) continue;
    ++report.camera_pairs;
    for (const auto& [nodes, v] : *pair_votes) {
      auto& total = votes[nodes];
      total.same += v.same;
      total.flipped += v.flipped;
    }
  }

  // Two-colouring by a maximum-weight spanning tree: the clearest majorities decide first, and a
  // run pair that disagrees with what is already decided cannot overturn it.
  std::vector<std::pair<std::pair<int, int>, Votes>> edges(votes.begin(), votes.end());
  const auto margin = [](const Votes& v) { return std::abs(v.same - v.flipped); };
  std::sort(edges.begin(), edges.end(),
            [&](const auto& x, const auto& y) { return margin(x.second) > margin(y.second); });
  // Runs joined with their parity (ends reversed or not) relative to the group's root.
  UnionFind forest(runs.size());
  for (const auto& [nodes, v] : edges) {
    if (margin(v) < options.min_votes) break;
    forest.unite(static_cast<std::size_t>(nodes.first), static_cast<std::size_t>(nodes.second),
                 v.flipped > v.same ? 1 : 0);
  }
  // The largest group (by frames) is kept; a run outside it has no known relation to it.
  std::map<int, std::size_t> frames_of_root;
  for (std::size_t r = 0; r < runs.size(); ++r)
    frames_of_root[static_cast<int>(forest.find(r))] += runs[r].frames.frames.size();
  const int main_root =
      std::max_element(frames_of_root.begin(), frames_of_root.end(), [](const auto& x, const auto& y) {
        return x.second < y.second;
      })->first;
  std::vector<int> parity(runs.size(), 0);
  std::vector<bool> kept(runs.size(), false);
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const int root = static_cast<int>(forest.find(r));
    const int p = forest.parity(r);
    kept[r] = root == main_root;
    parity[r] = p;
    if (!kept[r]) {
      ++report.dropped_runs;
      report.dropped_frames += static_cast<int>(runs[r].frames.frames.size());
    } else if (p == 1) {
      ++report.flipped_runs;
    }
  }
  for (const auto& [nodes, v] : votes) {
    const auto [a, b] = nodes;
    if (!kept[static_cast<std::size_t>(a)] || !kept[static_cast<std::size_t>(b)]) continue;
    report.votes += v.same + v.flipped;
    report.conflicting_votes +=
        (parity[static_cast<std::size_t>(a)] ^ parity[static_cast<std::size_t>(b)]) != 0 ? v.same : v.flipped;
  }
  // Apply: reverse the flipped runs, remove the unrelated ones.
  for (std::size_t c = 0; c < tracks.size(); ++c) {
    std::vector<WandFrame> frames;
    for (int r : runs_of_camera[c]) {
      if (!kept[static_cast<std::size_t>(r)]) continue;
      for (auto frame : runs[static_cast<std::size_t>(r)].frames.frames) {
        if (parity[static_cast<std::size_t>(r)] == 1) std::reverse(frame.pixels.begin(), frame.pixels.end());
        frames.push_back(std::move(frame));
      }
    }
    tracks[c].frames = std::move(frames);
  }
  return report;
}

}  // namespace panoptes::calib
