// SPDX-License-Identifier: Apache-2.0
// The estimator's log lines: "estimator_node: <message>" on stderr (integration tests grep them).
#pragma once

#include <string>

namespace panoptes::session {

void log(const std::string& message);

}  // namespace panoptes::session
