// SPDX-License-Identifier: Apache-2.0
#include "panoptes/camera/node_log.h"

#include <cstdio>

namespace panoptes::camera {

void NodeLog::operator()(const std::string& message) const {
  std::fprintf(stderr, "%s: %s\n", name_.c_str(), message.c_str());
}

void NodeCounters::count(const std::string& reason, const std::string& message) {
  const std::uint64_t n = ++counts_[reason];
  last_error_ = message;
  if (n <= 3 || n % 1000 == 0) log_(message + " (" + reason + " #" + std::to_string(n) + ")");
}

}  // namespace panoptes::camera
