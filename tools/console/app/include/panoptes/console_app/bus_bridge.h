// SPDX-License-Identifier: Apache-2.0
// panoptes_console on the bus: readers that copy what the console shows into the ConsoleState
// (camera_info, camera_status, features, calibration, estimator_status, tracks, bodies, chains,
// recorder_status) and the camera_command and recorder_command writers the server's checked commands go out
// through.
#pragma once

#include <memory>

#include "panoptes/console/command_gate.h"
#include "panoptes/console/console_state.h"
#include "panoptes/dds/bus.h"

namespace panoptes::console {

class BusBridge {
 public:
  BusBridge(dds::Bus& bus, ConsoleState& state);
  ~BusBridge();
  BusBridge(const BusBridge&) = delete;
  BusBridge& operator=(const BusBridge&) = delete;

  // Writes the command as panoptes_ctl does; false when no camera node listens.
  bool send(const CameraCommandRequest& command);
  // Creates a command writer for each camera seen since (call it from a thread of the console's,
  // not from a DDS listener).
  void poll();
  // Writes a RecorderCommand as panoptes_record --command does; false when no recorder listens.
  bool send(const RecorderCommandRequest& command);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace panoptes::console
