// SPDX-License-Identifier: Apache-2.0
#include "panoptes/dds/domain.h"

#include <stdlib.h>  // setenv (POSIX)
#include <cstdlib>
#include <string>

namespace panoptes::dds {

DomainError::DomainError(const std::string& source, std::string_view value)
    : ConfigError(source + "=" + std::string(value), "",
                  "not a DDS domain id (an integer 0.." + std::to_string(kMaxDomainId) + ")") {}

int parse_domain(std::string_view text, const std::string& source) {
  if (text.empty()) throw DomainError(source, text);
  int value = 0;
  for (const char c : text) {
    if (c < '0' || c > '9') throw DomainError(source, text);
    value = value * 10 + (c - '0');
    if (value > kMaxDomainId) throw DomainError(source, text);  // before it could overflow
  }
  return value;
}

int choose_domain(int requested, std::optional<std::string_view> variable) {
  if (requested >= 0) {
    if (requested > kMaxDomainId) throw DomainError("domain", std::to_string(requested));
    return requested;
  }
  if (!variable || variable->empty()) return 0;
  return parse_domain(*variable, kDomainVariable);
}

int resolve_domain(int requested) {
  const char* env = std::getenv(kDomainVariable);
  return choose_domain(requested, env == nullptr ? std::nullopt : std::optional<std::string_view>(env));
}

int use_domain(std::string_view text, const std::string& source) {
  const int domain = parse_domain(text, source);
  if (::setenv(kDomainVariable, std::to_string(domain).c_str(), 1) != 0)
    throw DomainError(source, text);  // only when the environment is out of memory
  return domain;
}

}  // namespace panoptes::dds
