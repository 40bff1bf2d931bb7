// SPDX-License-Identifier: Apache-2.0
// The DDS messages of rt/panoptes/frames and rt/panoptes/body_descriptions as the public types of
// panoptes/client/client.h, with the checks that keep a malformed sample away from applications.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "panoptes/client/client.h"
#include "panoptes/up_axis.h"
#include "panoptes_msgs/chains.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/surface.h"

namespace panoptes::client::detail {

// A MocapFrame received at `receive_ns` (wall clock) as a Frame; nullopt with `error` saying what
// is wrong (the field, the body or marker) for a malformed sample.
std::optional<Frame> to_frame(const msg::MocapFrame& message, std::int64_t receive_ns, std::string& error);

// The latency figures of a frame from its stamps; 0 for what a missing (0) stamp leaves unknown.
Latency latency_of(const msg::MocapFrame& message, std::int64_t receive_ns);

// A BodyDescriptions sample as the body set; nullopt with `error` for a malformed one (an empty or
// duplicate name, a body without markers, a non-finite marker position).
std::optional<std::vector<BodyDescription>> to_descriptions(const msg::BodyDescriptions& message,
                                                            std::string& error);

// A MarkerLabels sample (rt/panoptes/labels): the subjects, and the names by track id.
struct LabelMap {
  std::vector<SubjectDescription> subjects;
  std::unordered_map<std::int64_t, std::pair<std::string, std::string>> names;  // track -> (subject, marker)
};
// nullopt with `error` for a malformed one (an empty or duplicate subject name, a track named twice,
// a name that is not one of its subject's markers).
std::optional<LabelMap> to_label_map(const msg::MarkerLabels& message, std::string& error);
// Gives every marker of `frame` whose track `map` names its subject and name.
void apply_names(Frame& frame, const LabelMap& map);

// A StrokeEvents sample as its strokes; nullopt with `error` for a malformed one (an unknown phase,
// stroke id 0, a non-finite number).
std::optional<std::vector<Stroke>> to_strokes(const msg::StrokeEvents& message, std::int64_t receive_ns,
                                              std::string& error);

// A ChainFrame sample as a ChainUpdate; nullopt with `error` naming the chain or event and the
// field for a malformed one (an unknown status or kind, chain id 0, a tracking chain whose markers,
// valid flags and angles do not agree in number, a non-finite number).
std::optional<ChainUpdate> to_chain_update(const msg::ChainFrame& message, std::int64_t receive_ns,
                                           std::string& error);

// The frame rate from frame stamps (any order; 0 with fewer than two distinct ones): `fixed`: 1 s
// over the shortest interval between consecutive distinct stamps (a fixed-rate grid: its period,
// whatever frames were skipped or lost); else the number of intervals over the span.
double rate_from_stamps(std::vector<std::int64_t> stamps, bool fixed);

// The timecode of a frame stamped `stamp_ns` in a stream of `rate` (panoptes/frame_grid.h): nullopt
// unless the rate is fixed and whole (within 0.01 Hz) and the stamp lies on its grid.
std::optional<Timecode> timecode_of(std::int64_t stamp_ns, const FrameRate& rate);

// ClientOptions::up_axis, else $PANOPTES_UP_AXIS, else z; a ConfigError naming the option or the
// variable for anything but z or y.
UpAxis choose_up_axis(const std::string& option);

// Every world quantity of a frame (marker positions, velocities, covariances; body positions,
// orientations, velocities, sigmas) or of a chain update (markers, tips) turned into `axis`.
void turn_to_up_axis(Frame& frame, UpAxis axis);
void turn_to_up_axis(ChainUpdate& update, UpAxis axis);

}  // namespace panoptes::client::detail
