// SPDX-License-Identifier: Apache-2.0
// Articulated chains on the bus (docs/articulated.md, docs/protocol.md): what a session's
// ChainStage holds after one camera frame as the rt/panoptes/chains ChainFrame.
#pragma once

#include "panoptes/records.h"
#include "panoptes/session/chain_stage.h"
#include "panoptes_msgs/chains.h"

namespace panoptes::estimator_app {

// Every chain of `chains` (its outputs, predicted tips and events of the frame it last observed),
// for `frame`; publish_ns is left 0 for the writer to stamp.
msg::ChainFrame to_chain_message(const session::ChainStage& chains, const FeatureFrame& frame);

}  // namespace panoptes::estimator_app
