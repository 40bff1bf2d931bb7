// SPDX-License-Identifier: Apache-2.0
// CSV writers: marker trajectories (wide: one row per frame) and body poses (long: one row per
// body and frame, with the orientation as a quaternion). docs/recording.md, "Export".
#pragma once

#include <filesystem>

#include "panoptes/formats/marker_trajectories.h"
#include "panoptes/formats/resample.h"

namespace panoptes {

// frame,time_s,<name>_x,<name>_y,<name>_z,... in metres; empty fields where a marker is invalid.
void write_markers_csv(const std::filesystem::path& path, const MarkerTrajectories& data);

// frame,time_s,body,x,y,z,qx,qy,qz,qw (metres; unit quaternion, Hamilton, rotation world <- body);
// only valid samples are written. Throws ConfigError naming the file if it cannot be written.
void write_bodies_csv(const std::filesystem::path& path, const BodyTrajectories& data);

}  // namespace panoptes
