// SPDX-License-Identifier: Apache-2.0
// The command-line options of DDS Security, the same in every program that joins the bus
// (docs/security.md). Header-only: programs that parse their command line with CLI11 include it.
#pragma once

#include <CLI/CLI.hpp>

#include "panoptes/dds/security.h"

namespace panoptes::dds {

inline void add_security_options(CLI::App& app, SecurityOptions& options) {
  app.add_option("--security-dir", options.directory,
                 "DDS Security: the studio directory made by deploy/security/panoptes-security (default: "
                 "$PANOPTES_SECURITY_DIR; none: unsecured unless the profile requires security)");
  app.add_option("--security-identity", options.identity,
                 "DDS Security: this node's identity, a directory under <security-dir>/identities (default: "
                 "$PANOPTES_SECURITY_IDENTITY)");
}

}  // namespace panoptes::dds
