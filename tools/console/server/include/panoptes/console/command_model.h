// SPDX-License-Identifier: Apache-2.0
// The commands the browsers sent to cameras and recorders, waiting for a status to show them, and
// their outcomes until the server hands them to the browsers. Not thread-safe: ConsoleState guards it.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "panoptes/console/console_records.h"

namespace panoptes::console {

class CommandModel {
 public:
  explicit CommandModel(const StateOptions& options) : options_(options) {}

  // A command forwarded to a camera, with the counts of the camera's latest status (nullptr: none
  // yet) to compare later statuses with.
  void on_command_sent(PendingCommand command, const CameraStatusRecord* camera_status);
  void on_recorder_command_sent(PendingRecorderCommand command);
  // A camera status counts every command applied or rejected so far; pending commands of that
  // camera take those counts in the order they were sent (the camera applies them in order), each
  // count going to one command only.
  void on_camera_status(const std::string& camera, const CameraStatusRecord& status);
  // A recorder's status resolves the commands that asked for its recording state: applied, or
  // rejected with the status's error.
  void on_recorder_status(const std::string& recorder, const RecorderRecord& status);
  // An outcome that needs no status (a body made by the console's body maker): handed out by the
  // next take_outcomes.
  void on_outcome(CommandOutcome outcome) { outcomes_.push_back(std::move(outcome)); }
  // The outcomes since the last call; commands not resolved within ack_timeout_ns end as no_ack.
  std::vector<CommandOutcome> take_outcomes(TimeNs now);

  std::size_t pending() const { return pending_.size() + pending_recorder_.size(); }

 private:
  StateOptions options_;
  std::vector<PendingCommand> pending_;
  std::vector<PendingRecorderCommand> pending_recorder_;
  std::vector<CommandOutcome> outcomes_;
};

}  // namespace panoptes::console
