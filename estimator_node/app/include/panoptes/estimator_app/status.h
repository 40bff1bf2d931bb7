// SPDX-License-Identifier: Apache-2.0
// EstimatorUsage (usage.h) as the rt/panoptes/estimator_status message (docs/protocol.md).
#pragma once

#include "panoptes/estimator/usage.h"
#include "panoptes_msgs/panoptes.h"

namespace panoptes::estimator_app {

msg::EstimatorStatus to_status_message(const estimator::EstimatorUsage& usage);

}  // namespace panoptes::estimator_app
