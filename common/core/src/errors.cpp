// SPDX-License-Identifier: Apache-2.0
#include "panoptes/errors.h"

namespace panoptes {

namespace {

std::string config_message(const std::string& file, const std::string& key, const std::string& reason) {
  if (key.empty()) return file + ": " + reason;
  return file + ": " + key + ": " + reason;
}

}  // namespace

ConfigError::ConfigError(const std::string& file, const std::string& key, const std::string& reason)
    : InputError(config_message(file, key, reason)), file_(file), key_(key) {}

}  // namespace panoptes
