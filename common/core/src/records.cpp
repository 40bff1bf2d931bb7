// SPDX-License-Identifier: Apache-2.0
#include "panoptes/records.h"

namespace panoptes {

std::string_view to_string(TrackStatus status) {
  switch (status) {
    case TrackStatus::kTentative:
      return "tentative";
    case TrackStatus::kConfirmed:
      return "confirmed";
    case TrackStatus::kCoasting:
      return "coasting";
  }
  return "unknown";
}

}  // namespace panoptes
