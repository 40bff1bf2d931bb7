// SPDX-License-Identifier: Apache-2.0
// --domain N on a program's command line (CLI11), the same flag in every program that opens DDS.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "panoptes/dds/domain.h"

namespace panoptes::dds {

// Adds --domain N to `app`. The value is checked as it is parsed (use_domain: a bad id throws
// DomainError, exit 2 naming --domain) and becomes $PANOPTES_DOMAIN for the rest of the program.
inline CLI::Option* add_domain_option(CLI::App& app) {
  return app
      .add_option_function<std::string>(
          "--domain", [](const std::string& text) { use_domain(text, "--domain"); }, kDomainFlagHelp)
      ->type_name("N");
}

}  // namespace panoptes::dds
