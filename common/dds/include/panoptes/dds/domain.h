// SPDX-License-Identifier: Apache-2.0
// The DDS domain a program joins: $PANOPTES_DOMAIN or an explicit id, checked in one place
// (docs/deployment.md, "Domains"). Plain parsing, no Fast DDS: the client library and every main
// may use it before any participant exists.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "panoptes/errors.h"

namespace panoptes::dds {

// The largest domain id whose ports fit Fast DDS's default RTPS port mapping (7400 + 250 x domain
// + offsets <= 65535); Fast DDS itself exits the process for a larger one.
inline constexpr int kMaxDomainId = 232;
inline constexpr const char* kDomainVariable = "PANOPTES_DOMAIN";

// A domain id that is not an integer in 0..kMaxDomainId. what() reads
// "PANOPTES_DOMAIN=abc: not a DDS domain id (an integer 0..232)"; programs exit 2 on it (a
// ConfigError, panoptes/process.h).
class DomainError : public ConfigError {
 public:
  // `source`: where the value came from ("PANOPTES_DOMAIN", "--domain", "domain").
  DomainError(const std::string& source, std::string_view value);
};

// `text` as a domain id: decimal digits only (no sign, no spaces), at most kMaxDomainId.
// DomainError naming `source` and the text otherwise.
int parse_domain(std::string_view text, const std::string& source);

// The domain for an explicit request and the environment's value: `requested` >= 0 is checked and
// wins; otherwise `variable` (the value of PANOPTES_DOMAIN, nullopt when unset), empty or unset
// meaning 0. Pure: resolve_domain reads the environment for it.
int choose_domain(int requested, std::optional<std::string_view> variable);

// choose_domain(requested, $PANOPTES_DOMAIN). Programs call it first (before parsing their command
// line), so that a bad $PANOPTES_DOMAIN is a usage error (exit 2) wherever the bus is opened later.
int resolve_domain(int requested = -1);

// The help text of every program's --domain flag (docs/deployment.md, "Domains").
inline constexpr const char* kDomainFlagHelp = "DDS domain, 0..232 (default: $PANOPTES_DOMAIN, else 0)";

// A --domain value: checked like $PANOPTES_DOMAIN (parse_domain; a typo is a DomainError naming
// `source`, exit 2, never domain 0), then put into $PANOPTES_DOMAIN for this process and the
// programs it starts, so that every bus it opens later joins that domain. Returns the id.
int use_domain(std::string_view text, const std::string& source = "--domain");

}  // namespace panoptes::dds
