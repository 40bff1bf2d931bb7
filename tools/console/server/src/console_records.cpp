// SPDX-License-Identifier: Apache-2.0
#include "panoptes/console/console_records.h"

#include <nlohmann/json.hpp>

namespace panoptes::console {

std::string_view to_string(Light light) {
  switch (light) {
    case Light::kGreen:
      return "green";
    case Light::kAmber:
      return "amber";
    case Light::kRed:
      break;
  }
  return "red";
}

std::string_view to_string(CommandResult result) {
  switch (result) {
    case CommandResult::kApplied:
      return "applied";
    case CommandResult::kRejected:
      return "rejected";
    case CommandResult::kNoAck:
      break;
  }
  return "no_ack";
}

std::string_view to_string(ChainStatus status) {
  switch (status) {
    case ChainStatus::kTracking:
      return "tracking";
    case ChainStatus::kAmbiguous:
      return "ambiguous";
    case ChainStatus::kNotIdentified:
      break;
  }
  return "not_identified";
}

std::string_view to_string(ChainEventKind kind) {
  return kind == ChainEventKind::kGrab ? "grab" : "release";
}

void to_json(nlohmann::json& out, Light light) {
  out = to_string(light);
}

void to_json(nlohmann::json& out, CommandResult result) {
  out = to_string(result);
}

void to_json(nlohmann::json& out, ChainStatus status) {
  out = to_string(status);
}

void to_json(nlohmann::json& out, ChainEventKind kind) {
  out = to_string(kind);
}

void to_json(nlohmann::json& out, const CommandOutcome& outcome) {
  out = {{"type", "command_result"},
         {"id", outcome.request},
         {"result", outcome.result},
         {"reason", outcome.reason}};
}

}  // namespace panoptes::console
