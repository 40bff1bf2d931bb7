// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console/command_model.h"

#include <map>

namespace panoptes::console {

namespace {

std::uint64_t counter(const CameraStatusRecord& status, const std::string& name) {
  const auto found = status.counters.find(name);
  return found == status.counters.end() ? 0 : found->second;
}

// Moves every entry of `pending` that `outcome_of` resolves (a nullopt leaves it waiting).
template <class Pending, class OutcomeOf>
void resolve(std::vector<Pending>& pending, std::vector<CommandOutcome>& outcomes,
             const OutcomeOf& outcome_of) {
  for (auto it = pending.begin(); it != pending.end();) {
    if (std::optional<CommandOutcome> outcome = outcome_of(*it)) {
      outcomes.push_back(std::move(*outcome));
      it = pending.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace

void CommandModel::on_command_sent(PendingCommand command, const CameraStatusRecord* camera_status) {
  if (camera_status) {
    command.applied_before = counter(*camera_status, "command_" + command.command);
    command.rejected_before = counter(*camera_status, "bad_command");
  }
  pending_.push_back(std::move(command));
}

void CommandModel::on_recorder_command_sent(PendingRecorderCommand command) {
  pending_recorder_.push_back(std::move(command));
}

void CommandModel::on_camera_status(const std::string& camera, const CameraStatusRecord& status) {
  std::map<std::string, std::uint64_t> applied_taken;
  std::uint64_t rejected_taken = 0;
  resolve(pending_, outcomes_, [&](const PendingCommand& command) -> std::optional<CommandOutcome> {
    if (command.camera != camera) return std::nullopt;
    const std::string name = "command_" + command.command;
    if (counter(status, name) > command.applied_before + applied_taken[name]) {
      ++applied_taken[name];
      return CommandOutcome{command.client, command.request, CommandResult::kApplied, ""};
    }
    if (counter(status, "bad_command") > command.rejected_before + rejected_taken) {
      ++rejected_taken;
      return CommandOutcome{command.client, command.request, CommandResult::kRejected, status.last_error};
    }
    return std::nullopt;
  });
}

void CommandModel::on_recorder_status(const std::string& recorder, const RecorderRecord& status) {
  resolve(pending_recorder_, outcomes_,
          [&](const PendingRecorderCommand& command) -> std::optional<CommandOutcome> {
            if (command.recorder != recorder || command.want_recording != status.recording)
              return std::nullopt;
            return CommandOutcome{command.client, command.request,
                                  status.error.empty() ? CommandResult::kApplied : CommandResult::kRejected,
                                  status.error};
          });
}

std::vector<CommandOutcome> CommandModel::take_outcomes(TimeNs now) {
  const auto timed_out = [&](const auto& command, const char* reason) -> std::optional<CommandOutcome> {
    if (now - command.sent_ns <= options_.ack_timeout_ns) return std::nullopt;
    return CommandOutcome{command.client, command.request, CommandResult::kNoAck, reason};
  };
  resolve(pending_, outcomes_, [&](const PendingCommand& command) {
    return timed_out(command, "the camera's status did not count the command");
  });
  resolve(pending_recorder_, outcomes_, [&](const PendingRecorderCommand& command) {
    return timed_out(command, "the recorder's status did not show the change");
  });
  std::vector<CommandOutcome> out;
  out.swap(outcomes_);
  return out;
}

}  // namespace panoptes::console
