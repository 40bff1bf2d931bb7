// SPDX-License-Identifier: Apache-2.0
// The native application topics (docs/clients.md): a FrameOutput as rt/panoptes/frames' MocapFrame
// the bodies file as rt/panoptes/body_descriptions' BodyDescriptions, and the labelling stage's
// current names as rt/panoptes/labels' MarkerLabels (docs/marker_sets.md, "Labels on the wire").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/session/frame_output.h"
#include "panoptes/session/label_stage.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::estimator_app {

msg::MocapFrame to_frame_message(const session::FrameOutput& frame, TimeNs publish_ns);

// The bodies, then the inside-out rigs (kind "rig", docs/inside_out.md), then the subjects'
// segments (kind "segment", session::SegmentStage), each whose name nothing before it has.
msg::BodyDescriptions to_descriptions_message(const std::vector<BodyDefinition>& bodies,
                                              std::uint64_t generation, const std::string& source,
                                              TimeNs stamp_ns, const std::vector<BodyDefinition>& rigs = {},
                                              const std::vector<BodyDefinition>& segments = {});

// Every subject of `stage` in --subjects order: its marker set's tracked marker names, its sticks
// and the tracks named now (stage.map()); stamp and generation of the map.
msg::MarkerLabels to_labels_message(const session::LabelStage& stage);

}  // namespace panoptes::estimator_app
