// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/marker_labels.h"

#include <cstddef>
#include <map>
#include <string>

#include <Eigen/Geometry>

#include "panoptes/estimator/assignment.h"

namespace panoptes::estimator {

namespace {

// A row of the assignment: one marker of one tracked body, at its predicted world position.
struct PredictedMarker {
  int body = 0;
  int marker = 0;
  Eigen::Vector3d p;
};

std::vector<PredictedMarker> predicted_markers(const std::vector<PoseRecord>& poses,
                                               const std::vector<BodyDefinition>& definitions) {
  std::map<std::string, int> index;
  for (std::size_t i = 0; i < definitions.size(); ++i)
    index.emplace(definitions[i].name, static_cast<int>(i));
  std::vector<PredictedMarker> rows;
  for (const auto& pose : poses) {
    const auto it = index.find(pose.body);
    if (it == index.end()) continue;
    const Eigen::Quaterniond q(pose.q.w(), pose.q.x(), pose.q.y(), pose.q.z());
    const auto& layout = definitions[static_cast<std::size_t>(it->second)].markers;
    for (std::size_t m = 0; m < layout.size(); ++m)
      rows.push_back({it->second, static_cast<int>(m), pose.p + q.normalized() * layout[m]});
  }
  return rows;
}

}  // namespace

MarkerLabelling label_markers(const std::vector<TrackRecord>& tracks, const std::vector<PoseRecord>& poses,
                              const std::vector<BodyDefinition>& definitions, double max_distance_m) {
  MarkerLabelling result;
  result.labels.assign(tracks.size(), MarkerLabel{});
  result.mean_error_m.assign(definitions.size(), 0.0);
  result.labelled_markers.assign(definitions.size(), 0);
  const std::vector<PredictedMarker> rows = predicted_markers(poses, definitions);
  if (rows.empty() || tracks.empty()) return result;

  const double max_distance2 = max_distance_m * max_distance_m;
  std::vector<GatedPair> pairs;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (std::size_t c = 0; c < tracks.size(); ++c) {
      const double d2 = (tracks[c].p - rows[r].p).squaredNorm();
      if (d2 < max_distance2) pairs.push_back({r, c, d2});
    }
  }
  std::vector<double> error_sum(definitions.size(), 0.0);
  for (const auto& [r, c] : assign_gated(pairs, max_distance2)) {
    const PredictedMarker& row = rows[r];
    result.labels[c] = {row.body, row.marker};
    const auto body = static_cast<std::size_t>(row.body);
    error_sum[body] += (tracks[c].p - row.p).norm();
    ++result.labelled_markers[body];
  }
  for (std::size_t b = 0; b < definitions.size(); ++b) {
    if (result.labelled_markers[b] > 0) result.mean_error_m[b] = error_sum[b] / result.labelled_markers[b];
  }
  return result;
}

}  // namespace panoptes::estimator
