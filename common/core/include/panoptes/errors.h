// SPDX-License-Identifier: Apache-2.0
// The errors whose type chooses a program's exit code (run_program, panoptes/process.h). They live
// in the core so that code which validates definitions (bodies, options) can name the file and key
// without linking any file reader.
//
//   InputError             exit 2: what the program was given cannot be used: an argument, an
//   |                      environment variable, a device or file it names, or a file's contents.
//   |                      Running again with the input fixed succeeds.
//   +- ConfigError         a bad file, key or value; what() names them
//      +- dds::SecurityError (DDS Security files), dds::DomainError (a bad PANOPTES_DOMAIN)
//   std::invalid_argument  exit 2 as well: a value a parser or constructor refused
//   any other exception    exit 1: a run-time failure (a device or disk failing, DDS refusing an
//                          entity, out of memory)
//
// Command-line errors never get that far: parse_command_line (panoptes/cli.h) prints them and
// exits 2, and --help exits 0. Library code throws the most specific error it can tell; a program
// that knows that every failure of one step is the input's (opening the source it was told to
// open) says so with as_input_error().
#pragma once

#include <exception>
#include <stdexcept>
#include <string>
#include <utility>

namespace panoptes {

// What the program was given cannot be used; what() says what and why.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A bad file, key or value. what() reads "<file>: <key>: <reason>" ("<file>: <reason>" without a key).
class ConfigError : public InputError {
 public:
  ConfigError(const std::string& file, const std::string& key, const std::string& reason);
  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }

 private:
  std::string file_;
  std::string key_;
};

// Runs `step` and returns what it returns; any exception it throws that is not already an
// InputError becomes one with the same message. For a step whose every failure is the input's
// fault: opening a device or file the user named, reading the settings they gave.
template <typename Step>
decltype(auto) as_input_error(Step&& step) {
  try {
    return std::forward<Step>(step)();
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& error) {
    throw InputError(error.what());
  }
}

}  // namespace panoptes
