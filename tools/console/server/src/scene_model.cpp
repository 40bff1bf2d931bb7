// SPDX-License-Identifier: Apache-2.0
// The scene's tracks and bodies (the chains: console_chains.cpp).
#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "json_helpers.h"
#include "panoptes/console/scene_model.h"

namespace panoptes::console {

namespace {

using detail::round_to;
using nlohmann::json;

template <class Values>
json rounded(const Values& values, int decimals) {
  json out = json::array();
  for (const double value : values) out.push_back(round_to(value, decimals));
  return out;
}

}  // namespace

void SceneModel::on_tracks(std::vector<TrackPoint> tracks, TimeNs now) {
  std::map<std::int64_t, TimeNs> first_seen;
  for (const TrackPoint& track : tracks) {
    const auto known = track_first_seen_ns_.find(track.id);
    first_seen[track.id] = known == track_first_seen_ns_.end() ? now : known->second;
  }
  track_first_seen_ns_ = std::move(first_seen);  // ids no longer published are forgotten
  tracks_ = std::move(tracks);
  tracks_ns_ = now;
}

void SceneModel::on_body(BodyRecord body, TimeNs now) {
  const auto known = bodies_.find(body.name);
  if (known == bodies_.end() || now - known->second.second > options_.body_timeout_ns)
    body_first_seen_ns_[body.name] = now;
  std::string name = body.name;
  bodies_[std::move(name)] = {std::move(body), now};
}

json SceneModel::details(const std::string& kind, const std::string& key, TimeNs now) const {
  if (kind == "track") return track_details(key, now);
  if (kind == "chain") return chain_details(key, now);
  if (kind == "body") return body_details(key, now);
  return nullptr;
}

json SceneModel::track_details(const std::string& key, TimeNs now) const {
  if (now - tracks_ns_ > options_.track_timeout_ns) return nullptr;
  for (const TrackPoint& track : tracks_) {
    if (std::to_string(track.id) != key) continue;
    const auto& c = track.covariance;  // xx xy xz yy yz zz
    const std::array<double, 3> sigma = {std::sqrt(std::max(0.0, c[0])), std::sqrt(std::max(0.0, c[3])),
                                         std::sqrt(std::max(0.0, c[5]))};
    const auto first = track_first_seen_ns_.find(track.id);
    const auto& v = track.velocity;
    return {{"kind", "track"},
            {"id", track.id},
            {"status", to_string(track.status)},
            {"position_m", rounded(track.position, 4)},
            {"velocity_m_s", rounded(track.velocity, 3)},
            {"speed_m_s", round_to(std::hypot(v[0], v[1], v[2]), 3)},
            {"sigma_mm", rounded(std::array<double, 3>{1e3 * sigma[0], 1e3 * sigma[1], 1e3 * sigma[2]}, 2)},
            {"covariance_m2", track.covariance},
            {"cameras", track.cameras},
            {"age_s", detail::seconds(first == track_first_seen_ns_.end() ? 0 : now - first->second, 2)}};
  }
  return nullptr;
}

json SceneModel::body_details(const std::string& key, TimeNs now) const {
  const auto found = bodies_.find(key);
  if (found == bodies_.end() || now - found->second.second > options_.body_timeout_ns) return nullptr;
  const BodyRecord& body = found->second.first;
  const auto first = body_first_seen_ns_.find(key);
  const auto& v = body.linear_velocity;
  const auto& s = body.sigma;
  return {{"kind", "body"},
          {"name", body.name},
          // The stamp of the pose shown: a test or user compares the figures with the pose the
          // estimator published at that stamp, not with whichever pose is newest when it looks.
          {"stamp_ns", body.stamp_ns},
          {"position_m", rounded(body.pose.position, 4)},
          {"orientation_xyzw", rounded(body.pose.orientation, 5)},
          {"velocity_m_s", rounded(body.linear_velocity, 3)},
          {"speed_m_s", round_to(std::hypot(v[0], v[1], v[2]), 3)},
          {"angular_velocity_rad_s", rounded(body.angular_velocity, 3)},
          {"sigma_position_mm", rounded(std::array<double, 3>{1e3 * s[0], 1e3 * s[1], 1e3 * s[2]}, 2)},
          {"sigma_rotation_deg",
           rounded(std::array<double, 3>{s[3] * 180 / M_PI, s[4] * 180 / M_PI, s[5] * 180 / M_PI}, 3)},
          {"quality", round_to(body.quality, 3)},
          {"age_s", detail::seconds(first == body_first_seen_ns_.end() ? 0 : now - first->second, 2)},
          {"since_update_ms", round_to(static_cast<double>(now - found->second.second) * 1e-6, 1)}};
}

void SceneModel::on_labels(std::vector<SubjectLabelsRecord> subjects) {
  subjects_ = std::move(subjects);
}

json SceneModel::to_json(TimeNs now, bool full) const {
  json tracks = json::array();
  if (now - tracks_ns_ <= options_.track_timeout_ns) {
    for (const TrackPoint& track : tracks_) {
      tracks.push_back({track.id, round_to(track.position[0], 4), round_to(track.position[1], 4),
                        round_to(track.position[2], 4), static_cast<int>(track.status)});
    }
  }
  json bodies = json::array();
  for (const auto& [name, body] : bodies_) {
    if (now - body.second > options_.body_timeout_ns) continue;
    bodies.push_back(
        {{"name", name}, {"pose", detail::pose_json(body.first.pose)}, {"quality", body.first.quality}});
  }
  json subjects = json::array();
  for (const SubjectLabelsRecord& subject : subjects_) {
    json names = json::object();
    for (const auto& [track, name] : subject.names) names[std::to_string(track)] = name;
    subjects.push_back({{"name", subject.name}, {"sticks", subject.sticks}, {"names", std::move(names)}});
  }
  json out = {{"tracks", std::move(tracks)}, {"bodies", std::move(bodies)}, {"chains", chains_json(now)}};
  // Only with --subjects on the estimator: the page reads a missing list as none.
  if (!subjects.empty()) out["subjects"] = std::move(subjects);
  if (full) {
    out["chain_samples"] = {{"received", chain_samples_.received},
                            {"dropped", chain_samples_.dropped},
                            {"last_error", chain_samples_.last_error}};
  }
  return out;
}

}  // namespace panoptes::console
