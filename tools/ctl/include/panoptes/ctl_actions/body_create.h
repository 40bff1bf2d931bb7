// SPDX-License-Identifier: Apache-2.0
// A rigid body made from markers in the volume (docs/bodies.md, "Bodies from markers"; issue 34
// item 3): the tracks chosen by id or within a radius of a point, their averaged positions as the
// body's layout about a pivot, appended to the bodies file that a live estimator reloads. The
// pure parts, testable without DDS; panoptes_ctl body create adds the bus (ctl_actions.h).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "panoptes/calibration.h"

namespace panoptes::ctl {

// Averaged world positions of the confirmed tracks, by track id.
using TrackPositions = std::map<std::int64_t, Eigen::Vector3d>;

struct BodyRequest {
  std::string name;
  std::vector<std::int64_t> tracks;     // by id (--tracks), or empty with `near`
  std::optional<Eigen::Vector3d> near;  // every track within `radius_m` of this point (--near)
  double radius_m = 0.1;                // --radius
  std::optional<std::int64_t> pivot;    // the body origin at this track; nullopt: the centroid
  std::filesystem::path bodies_file;    // --bodies: appended to (created when missing)
};

// The ids of `request`: its tracks, or those within the radius of its point (nearest first).
// Throws ConfigError (key "--tracks" or "--near") naming the missing ids and the ids seen when a
// track is not among `seen`, for a repeated id, fewer than 3 tracks, or a pivot not among them.
std::vector<std::int64_t> select_tracks(const BodyRequest& request, const TrackPositions& seen);

// The body: markers in the order of `ids`, relative to the pivot (or the centroid), axes along the
// world's (so its pose is the identity rotation at the moment of creation). Validated as the
// estimator validates bodies (3 markers, 1 mm apart, not on one line): ConfigError naming it.
BodyDefinition make_body(const BodyRequest& request, const std::vector<std::int64_t>& ids,
                         const TrackPositions& seen);

// Appends `body` to the bodies file (a new file when missing), keeping every other entry (bodies
// and chains; comments are not kept). Refuses a name already in the file. Written to a temporary
// file, read back as the estimator reads it, then renamed over the file, so a running estimator
// reloads either the old or the complete new file. Writers take `<file>.lock` (flock) for the
// whole read-append-replace, so creations at the same moment each keep their body (a writer waits
// up to 10 s). Throws ConfigError naming the file.
void append_body(const std::filesystem::path& bodies_file, const BodyDefinition& body);
// Before the tracks are collected: ConfigError (naming the file) when the bodies file is not one
// or already defines `name` (append_body checks again under the file's lock).
void check_body_name(const std::filesystem::path& bodies_file, const std::string& name);

}  // namespace panoptes::ctl
