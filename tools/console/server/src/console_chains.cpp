// SPDX-License-Identifier: Apache-2.0
// The console's articulated chains (rt/panoptes/chains, docs/articulated.md, docs/console.md
// "Chains"): each chain's latest state for the 3D view, its grab/release counts, and the samples
// dropped because a field cannot be drawn.
#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "panoptes/chain_definition.h"
#include "panoptes/console/scene_model.h"

namespace panoptes::console {

namespace {

using nlohmann::json;

constexpr std::size_t kMaxNameLength = 128;
constexpr std::size_t kMaxEventsPerSample = 64;

bool finite3(const std::array<double, 3>& value) {
  return std::all_of(value.begin(), value.end(), [](double v) { return std::isfinite(v); });
}

// Rounded to 0.1 mm: the view needs no more, and short numbers keep the snapshot small.
json point_json(const std::array<double, 3>& p) {
  const auto round = [](double v) { return std::round(v * 1e4) / 1e4; };
  return json::array({round(p[0]), round(p[1]), round(p[2])});
}

std::string chain_error(const ChainRecord& chain) {
  const std::string what = "chain '" + chain.name.substr(0, kMaxNameLength) + "'";
  if (chain.name.empty() || chain.name.size() > kMaxNameLength || chain.chain_id == 0)
    return what + ": name: empty or longer than " + std::to_string(kMaxNameLength) +
           " characters, or chain_id 0";
  if (!known(chain.status))
    return what + ": status " + std::to_string(static_cast<int>(chain.status)) +
           " is not tracking (0), ambiguous (1) or not identified (2)";
  if (chain.status != ChainStatus::kTracking) return {};
  const std::size_t markers = chain.markers.size();
  if (markers < static_cast<std::size_t>(kMinChainMarkers) ||
      markers > static_cast<std::size_t>(kMaxChainMarkers) || chain.marker_valid.size() != markers ||
      chain.angles.size() != markers - 2)
    return what + ": markers: " + std::to_string(markers) + " markers, " +
           std::to_string(chain.marker_valid.size()) + " valid flags and " +
           std::to_string(chain.angles.size()) + " angles (wants " + std::to_string(kMinChainMarkers) + ".." +
           std::to_string(kMaxChainMarkers) + " markers, one flag each, markers - 2 angles)";
  if (!std::all_of(chain.angles.begin(), chain.angles.end(), [](double a) { return std::isfinite(a); }))
    return what + ": angles: not finite";
  if (!std::all_of(chain.markers.begin(), chain.markers.end(), finite3))
    return what + ": markers: a position is not finite";
  if (!finite3(chain.tip) || !finite3(chain.predicted_tip))
    return what + ": tip or predicted_tip: not finite";
  if (chain.prediction_horizon_ns < 0) return what + ": prediction_horizon_ns: negative";
  return {};
}

}  // namespace

std::string chain_frame_error(const ChainFrameRecord& frame) {
  for (const ChainRecord& chain : frame.chains) {
    if (std::string error = chain_error(chain); !error.empty()) return error;
  }
  if (frame.events.size() > kMaxEventsPerSample)
    return "events: " + std::to_string(frame.events.size()) + " in one sample (at most " +
           std::to_string(kMaxEventsPerSample) + ")";
  for (std::size_t i = 0; i < frame.events.size(); ++i) {
    const ChainEventRecord& event = frame.events[i];
    const std::string what = "events[" + std::to_string(i) + "]";
    if (!known(event.kind))
      return what + ": kind " + std::to_string(static_cast<int>(event.kind)) +
             " is not grab (0) or release (1)";
    if (event.chain.empty() || event.chain.size() > kMaxNameLength)
      return what + ": chain: empty or too long";
    if (!finite3(event.tip) || !std::isfinite(event.bend)) return what + ": tip or bend: not finite";
  }
  return {};
}

bool SceneModel::on_chains(ChainFrameRecord frame, TimeNs now) {
  std::string error = chain_frame_error(frame);
  ++chain_samples_.received;
  if (error.empty()) {
    std::size_t unknown = 0;
    for (const ChainRecord& chain : frame.chains) unknown += chains_.count(chain.name) == 0 ? 1 : 0;
    if (chains_.size() + unknown > options_.max_chains)
      error = "chains: more than " + std::to_string(options_.max_chains) + " chain names";
  }
  if (!error.empty()) {
    ++chain_samples_.dropped;
    chain_samples_.last_error = std::move(error);
    return false;
  }
  for (ChainRecord& chain : frame.chains) {
    Chain& entry = chains_[chain.name];
    if (entry.first_seen_ns == 0 || now - entry.received_ns > options_.chain_timeout_ns)
      entry.first_seen_ns = now;
    entry.latest = std::move(chain);
    entry.received_ns = now;
  }
  for (ChainEventRecord& event : frame.events) {
    const auto found = chains_.find(event.chain);
    if (found == chains_.end()) continue;  // an event of a chain the sample does not carry
    ++(event.kind == ChainEventKind::kGrab ? found->second.grabs : found->second.releases);
    found->second.last_event = std::move(event);
  }
  return true;
}

// Per live chain: what the 3D view draws (markers only while tracking).
json SceneModel::chains_json(TimeNs now) const {
  json chains = json::array();
  for (const auto& [name, entry] : chains_) {
    if (now - entry.received_ns > options_.chain_timeout_ns) continue;
    const ChainRecord& c = entry.latest;
    json out = {{"name", name},         {"status", c.status},         {"grabbing", c.grabbing},
                {"grabs", entry.grabs}, {"releases", entry.releases}, {"stamp_ns", c.stamp_ns}};
    if (c.status == ChainStatus::kTracking) {
      json markers = json::array();
      for (const auto& marker : c.markers) markers.push_back(point_json(marker));
      out["markers"] = std::move(markers);
      out["valid"] = c.marker_valid;
      out["tip"] = point_json(c.tip);
      out["predicted_tip"] = point_json(c.predicted_tip);
      out["horizon_ms"] = static_cast<double>(c.prediction_horizon_ns) * 1e-6;
    }
    chains.push_back(std::move(out));
  }
  return chains;
}

json SceneModel::chain_details(const std::string& name, TimeNs now) const {
  const auto found = chains_.find(name);
  if (found == chains_.end() || now - found->second.received_ns > options_.chain_timeout_ns) return nullptr;
  const Chain& entry = found->second;
  const ChainRecord& c = entry.latest;
  const auto round = [](double value, double scale) { return std::round(value * scale) / scale; };
  json out = {{"kind", "chain"},
              {"name", name},
              {"status", c.status},
              {"grabbing", c.grabbing},
              {"grabs", entry.grabs},
              {"releases", entry.releases},
              {"age_s", round(static_cast<double>(now - entry.first_seen_ns) * 1e-9, 100)},
              {"since_update_ms", round(static_cast<double>(now - entry.received_ns) * 1e-6, 10)}};
  if (c.status == ChainStatus::kTracking) {
    json angles = json::array();
    for (const double angle : c.angles) angles.push_back(round(angle * 180 / M_PI, 100));
    out["joint_angles_deg"] = std::move(angles);
    double bend = 0;
    for (const double angle : c.angles) bend += angle;
    out["bend_deg"] = round(bend * 180 / M_PI, 100);
    out["tip_m"] = point_json(c.tip);
    out["predicted_tip_m"] = point_json(c.predicted_tip);
    out["horizon_ms"] = static_cast<double>(c.prediction_horizon_ns) * 1e-6;
    out["markers_valid"] = std::to_string(std::count(c.marker_valid.begin(), c.marker_valid.end(), true)) +
                           " of " + std::to_string(c.marker_valid.size());
  }
  if (entry.last_event) {
    const ChainEventRecord& event = *entry.last_event;
    out["last_event"] = std::string(to_string(event.kind)) + " at " + point_json(event.tip).dump() +
                        ", bend " + std::to_string(static_cast<int>(std::lround(event.bend * 180 / M_PI))) +
                        "°";
  }
  return out;
}

}  // namespace panoptes::console
