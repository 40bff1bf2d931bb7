// SPDX-License-Identifier: Apache-2.0
#include "panoptes/session/log.h"

#include <cstdio>

namespace panoptes::session {

void log(const std::string& message) {
  std::fprintf(stderr, "estimator_node: %s\n", message.c_str());
}

}  // namespace panoptes::session
