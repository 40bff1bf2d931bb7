// SPDX-License-Identifier: Apache-2.0
// The native application topics (docs/clients.md): a FrameOutput as rt/panoptes/frames' MocapFrame
// and the bodies file as rt/panoptes/body_descriptions' BodyDescriptions.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "panoptes/calibration.h"
#include "panoptes/session/frame_output.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::estimator_app {

msg::MocapFrame to_frame_message(const session::FrameOutput& frame, TimeNs publish_ns);

// The bodies, then the inside-out rigs (kind "rig", docs/inside_out.md) whose names no body has.
msg::BodyDescriptions to_descriptions_message(const std::vector<BodyDefinition>& bodies,
                                              std::uint64_t generation, const std::string& source,
                                              TimeNs stamp_ns, const std::vector<BodyDefinition>& rigs = {});

}  // namespace panoptes::estimator_app
