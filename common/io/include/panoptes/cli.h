// SPDX-License-Identifier: Apache-2.0
// The command-line convention of every Panoptes program: --help prints and exits 0; a bad argument
// prints one line naming the program and the reason, and exits 2. Include only from main files.
#pragma once

#include <cstdio>
#include <functional>
#include <iostream>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "panoptes/process.h"

namespace panoptes {

// Parses; `validate` may throw CLI::ValidationError for checks across options. Returns the exit
// code to leave with, or nullopt to carry on.
inline std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv,
                                             const std::function<void()>& validate = {}) {
  try {
    app.parse(argc, argv);
    if (validate) validate();
  } catch (const CLI::CallForHelp&) {
    std::cout << app.help();
    return kExitOk;
  } catch (const CLI::ParseError& error) {
    std::fprintf(stderr, "%s: %s (see --help)\n", app.get_name().c_str(), error.what());
    return kExitBadInput;
  }
  return std::nullopt;
}

// CLI11's own PositiveNumber prints the whole double range in its message.
inline CLI::Validator positive_number() {
  return CLI::Validator(
      [](std::string& text) {
        try {
          std::size_t used = 0;
          if (std::stod(text, &used) > 0.0 && used == text.size()) return std::string();
        } catch (const std::exception&) {
        }
        return "expected a positive number, got '" + text + "'";
      },
      "POSITIVE");
}

}  // namespace panoptes
