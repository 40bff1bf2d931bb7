// SPDX-License-Identifier: Apache-2.0
// The error a bad file, key or value raises. It lives in the core so that code which validates
// definitions (bodies, options) can name the file and key without linking any file reader.
#pragma once

#include <stdexcept>
#include <string>

namespace panoptes {

// A bad file, key or value. what() reads "<file>: <key>: <reason>" ("<file>: <reason>" without a key).
class ConfigError : public std::runtime_error {
 public:
  ConfigError(const std::string& file, const std::string& key, const std::string& reason);
  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }

 private:
  std::string file_;
  std::string key_;
};

}  // namespace panoptes
