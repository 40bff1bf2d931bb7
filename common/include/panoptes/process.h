// SPDX-License-Identifier: Apache-2.0
// Small helpers every program shares: turning SIGINT/SIGTERM into a clean stop, and the one-line
// error convention for bad command lines.
#pragma once

#include <string>

namespace panoptes {

// Installs handlers for SIGINT and SIGTERM that set a flag (and nothing else).
void install_stop_handlers();
bool stop_requested();
void request_stop();

// Exit codes shared by every program.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;   // a run-time failure
inline constexpr int kExitBadInput = 2;  // bad arguments, config, calibration or input file

}  // namespace panoptes
