// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <tuple>

#include <nlohmann/json.hpp>

#include "panoptes/simulator.h"

namespace panoptes::estimator {

Evaluation evaluate(const Scene& scene, const std::vector<TrackRecord>& tracks,
                    const EvaluationOptions& options) {
  std::vector<const TrackRecord*> sorted;
  sorted.reserve(tracks.size());
  for (const auto& t : tracks) sorted.push_back(&t);
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const TrackRecord* a, const TrackRecord* b) { return a->stamp_ns < b->stamp_ns; });

  const auto& names = scene.marker_names();
  Evaluation result;
  result.markers.resize(names.size());
  for (std::size_t m = 0; m < names.size(); ++m) result.markers[m].name = names[m];
  std::vector<double> sum2(names.size(), 0.0);
  std::vector<std::int64_t> last_id(names.size(), 0);
  std::map<std::int64_t, std::pair<int, int>> track_matches;  // id -> (samples, matched)
  double total_sum2 = 0;
  std::size_t total_matched = 0;

  for (std::size_t begin = 0; begin < sorted.size();) {
    std::size_t end = begin;
    while (end < sorted.size() && sorted[end]->stamp_ns == sorted[begin]->stamp_ns) ++end;
    const TimeNs scene_time = sorted[begin]->stamp_ns - options.epoch_ns;
    if (scene_time < options.warmup_ns || scene_time > scene.duration_ns()) {
      begin = end;
      continue;
    }
    ++result.instants;
    const auto truth = scene.markers_at(scene_time);

    // Greedy nearest pairs within the match distance, each marker and track used once.
    std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
    for (std::size_t m = 0; m < truth.size(); ++m) {
      if (!truth[m].valid) continue;
      for (std::size_t k = begin; k < end; ++k) {
        const double d = (sorted[k]->p - truth[m].p).norm();
        if (d < options.match_distance_m) pairs.emplace_back(d, m, k);
      }
    }
    std::sort(pairs.begin(), pairs.end());
    std::vector<bool> marker_taken(truth.size(), false);
    std::vector<bool> track_taken(end - begin, false);
    for (const auto& [d, m, k] : pairs) {
      if (marker_taken[m] || track_taken[k - begin]) continue;
      marker_taken[m] = true;
      track_taken[k - begin] = true;
      auto& marker = result.markers[m];
      ++marker.tracked;
      sum2[m] += d * d;
      total_sum2 += d * d;
      ++total_matched;
      marker.max_error_m = std::max(marker.max_error_m, d);
      const std::int64_t id = sorted[k]->id;
      if (last_id[m] != 0 && last_id[m] != id)
        marker.id_switches.push_back({sorted[k]->stamp_ns, last_id[m], id});
      last_id[m] = id;
    }
    for (std::size_t m = 0; m < truth.size(); ++m) {
      if (truth[m].valid) ++result.markers[m].steps;
    }
    for (std::size_t k = begin; k < end; ++k) {
      auto& counts = track_matches[sorted[k]->id];
      ++counts.first;
      if (track_taken[k - begin]) ++counts.second;
    }
    begin = end;
  }

  result.min_tracked_fraction = result.markers.empty() ? 0.0 : 1.0;
  for (std::size_t m = 0; m < result.markers.size(); ++m) {
    auto& marker = result.markers[m];
    marker.rmse_m = marker.tracked == 0 ? 0.0 : std::sqrt(sum2[m] / static_cast<double>(marker.tracked));
    result.worst_marker_rmse_m = std::max(result.worst_marker_rmse_m, marker.rmse_m);
    result.min_tracked_fraction = std::min(result.min_tracked_fraction, marker.tracked_fraction());
    result.id_switch_count += marker.id_switches.size();
  }
  result.rmse_m = total_matched == 0 ? 0.0 : std::sqrt(total_sum2 / static_cast<double>(total_matched));
  result.track_ids = track_matches.size();
  for (const auto& [id, counts] : track_matches) {
    if (counts.first >= options.false_track_min_samples && 2 * counts.second < counts.first) {
      result.false_tracks.push_back(id);
    }
  }
  return result;
}

std::string Evaluation::to_json() const {
  nlohmann::json j;
  j["instants"] = instants;
  j["track_ids"] = track_ids;
  j["rmse_mm"] = rmse_m * 1e3;
  j["worst_marker_rmse_mm"] = worst_marker_rmse_m * 1e3;
  j["min_tracked_fraction"] = min_tracked_fraction;
  j["id_switches"] = id_switch_count;
  j["false_tracks"] = false_tracks;
  j["markers"] = nlohmann::json::array();
  for (const auto& marker : markers) {
    nlohmann::json m;
    m["name"] = marker.name;
    m["rmse_mm"] = marker.rmse_m * 1e3;
    m["max_error_mm"] = marker.max_error_m * 1e3;
    m["tracked_fraction"] = marker.tracked_fraction();
    m["steps"] = marker.steps;
    m["id_switches"] = nlohmann::json::array();
    for (const auto& s : marker.id_switches) {
      m["id_switches"].push_back({{"stamp_ns", s.stamp_ns}, {"from", s.from_id}, {"to", s.to_id}});
    }
    j["markers"].push_back(m);
  }
  return j.dump(2);
}

std::string Evaluation::summary() const {
  std::ostringstream out;
  char line[256];
  std::snprintf(line, sizeof line, "%-24s %10s %10s %9s %10s\n", "marker", "RMSE mm", "max mm", "tracked",
                "ID switch");
  out << line;
  for (const auto& marker : markers) {
    std::snprintf(line, sizeof line, "%-24s %10.3f %10.3f %8.1f%% %10zu\n", marker.name.c_str(),
                  marker.rmse_m * 1e3, marker.max_error_m * 1e3, 100.0 * marker.tracked_fraction(),
                  marker.id_switches.size());
    out << line;
  }
  std::snprintf(
      line, sizeof line,
      "all: RMSE %.3f mm, worst marker %.3f mm, min tracked %.1f%%, ID switches %zu, false tracks %zu, "
      "instants %zu\n",
      rmse_m * 1e3, worst_marker_rmse_m * 1e3, 100.0 * min_tracked_fraction, id_switch_count,
      false_tracks.size(), instants);
  out << line;
  return out.str();
}

}  // namespace panoptes::estimator
