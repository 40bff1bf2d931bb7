// SPDX-License-Identifier: Apache-2.0
// The planner's room file (docs/planner.md, "Describing a room"): errors name the file and key.
#pragma once

#include <cstdint>
#include <filesystem>

#include "panoptes/planner/metric.h"

namespace panoptes::planner {

struct RoomFile {
  Room room;
  OccluderModel occluders;
  MetricOptions metric;
  TrackerModel tracker;  // keys subject and tracker: the predicted tracker RMSE
  // Key objective (q | tracker_rmse): what the search minimises; tracker_rmse by default, measured
  // to plan better (docs/planner.md, "Objectives").
  Objective objective = Objective::kTrackerRmse;
  int sample_points = 2000;
  int sample_directions = 32;
  std::uint64_t sample_seed = 1;
};

// Throws ConfigError naming the file and key on a missing or unknown key or an invalid value.
RoomFile load_room(const std::filesystem::path& path);

}  // namespace panoptes::planner
