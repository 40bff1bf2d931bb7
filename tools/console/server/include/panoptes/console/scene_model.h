// SPDX-License-Identifier: Apache-2.0
// What the estimator sees in the room: its tracks, rigid bodies and articulated chains (with their
// grab/release counts and the chain samples dropped because a field cannot be drawn), and the
// details panel's figures of one of them. Not thread-safe: ConsoleState guards it; one lock for
// the three, so that a snapshot's tracks, bodies and chains are of the same moment.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "panoptes/console/console_records.h"

namespace panoptes::console {

// Why a chain sample cannot be shown (naming the chain or event and the field); empty when it can.
std::string chain_frame_error(const ChainFrameRecord& frame);

class SceneModel {
 public:
  explicit SceneModel(const StateOptions& options) : options_(options) {}

  void on_tracks(std::vector<TrackPoint> tracks, TimeNs now);
  void on_body(BodyRecord body, TimeNs now);
  // The newest map of names (rt/panoptes/labels): replaces the previous one.
  void on_labels(std::vector<SubjectLabelsRecord> subjects);
  // A chain sample: kept (latest state per chain, events counted) or, when chain_frame_error
  // names a fault or it names more than max_chains chains, counted as dropped with that reason.
  // False when dropped.
  bool on_chains(ChainFrameRecord frame, TimeNs now);

  struct ChainSampleCounts {
    std::uint64_t received = 0;
    std::uint64_t dropped = 0;
    std::string last_error;
  };
  const ChainSampleCounts& chain_samples() const { return chain_samples_; }

  // The figures of one track (`kind` "track", key its id), body ("body", key its name) or chain
  // ("chain", key its name) for the page's details panel; null when it is not (or no longer) live.
  nlohmann::json details(const std::string& kind, const std::string& key, TimeNs now) const;

  // The snapshot's "tracks" ([id, x, y, z, status number]), "bodies" and "chains" (live ones
  // only), "subjects" ({name, sticks, names: {track id: marker}}; docs/marker_sets.md), and when
  // `full` "chain_samples" (docs/console.md, "Protocol").
  nlohmann::json to_json(TimeNs now, bool full) const;

 private:
  struct Chain {
    ChainRecord latest;
    TimeNs received_ns = 0;
    TimeNs first_seen_ns = 0;
    std::uint64_t grabs = 0;
    std::uint64_t releases = 0;
    std::optional<ChainEventRecord> last_event;
  };

  nlohmann::json track_details(const std::string& key, TimeNs now) const;
  nlohmann::json body_details(const std::string& key, TimeNs now) const;
  nlohmann::json chain_details(const std::string& name, TimeNs now) const;
  nlohmann::json chains_json(TimeNs now) const;

  StateOptions options_;
  std::vector<TrackPoint> tracks_;
  TimeNs tracks_ns_ = 0;
  std::map<std::int64_t, TimeNs> track_first_seen_ns_;
  std::map<std::string, std::pair<BodyRecord, TimeNs>> bodies_;
  std::map<std::string, TimeNs> body_first_seen_ns_;
  std::map<std::string, Chain> chains_;
  ChainSampleCounts chain_samples_;
  std::vector<SubjectLabelsRecord> subjects_;
};

}  // namespace panoptes::console
