// SPDX-License-Identifier: Apache-2.0
// Small helpers every program shares: turning SIGINT/SIGTERM into a clean stop, child processes,
// and run_program, which gives every main() the same error lines and exit codes.
#pragma once

#include <chrono>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "panoptes/errors.h"

namespace panoptes {

// Installs handlers for SIGINT and SIGTERM that set a flag (and nothing else).
void install_stop_handlers();
bool stop_requested();
void request_stop();

// CPU time this process has used (all threads, user + system), seconds.
double process_cpu_seconds();

// For a program whose work is done and whose output files are complete, before it tears down
// what can stall: if the process is still running `limit` later, prints one line "<program>:
// <what> has not finished <limit> after the work ended; ending now with exit code <exit_code>",
// the calling thread's call stack (where it stalled), and ends the process with `exit_code`
// (_exit: no destructor runs). Call it from the main thread; the first call arms it, later calls
// do nothing. The estimator
// arms it before closing its DDS participant: Fast DDS 2.9 can deadlock deleting a secured one
// (CI met one such hang in test_security; docs/architecture.md, "Configuration and errors").
void end_within(std::chrono::milliseconds limit, int exit_code, const std::string& what);

// A child process started with posix_spawn, stdout and stderr to `log_file`, stdin from
// /dev/null; stopped (SIGINT, then SIGKILL after 5 s) when destroyed. Used by the demo and the
// benchmarks that run the nodes.
class ChildProcess {
 public:
  // Throws std::runtime_error naming argv[0] if it cannot be started.
  ChildProcess(std::string name, std::vector<std::string> argv, const std::filesystem::path& log_file);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool running();
  // SIGINT (a clean stop), then SIGKILL after the timeout. Returns the exit code (-1 if killed).
  int stop(std::chrono::milliseconds timeout = std::chrono::seconds(5));
  const std::string& name() const { return name_; }
  // Exit code once the process has ended (-1 if it was killed by a signal).
  int exit_code() const;

 private:
  std::string name_;
  int pid_ = -1;
  int exit_status_ = 0;
};

// Exit codes shared by every program (docs/architecture.md, "Configuration and errors").
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;   // a run-time failure
inline constexpr int kExitBadInput = 2;  // bad arguments, config, calibration or input file

namespace detail {
void report_program_error(const char* program, const char* what);
// A fatal signal (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT) prints "<program>: fatal signal <name>"
// and the thread's call stack to stderr, then ends the process by that signal as before (its exit
// status and core dump unchanged): a crash in a test under CI leaves more than an exit status.
void install_crash_report(const char* program);

template <typename Body, typename BadInput, typename... More>
int run_catching_bad_input(const char* program, Body& body) {
  try {
    if constexpr (sizeof...(More) == 0) {
      return body();
    } else {
      return run_catching_bad_input<Body, More...>(program, body);
    }
  } catch (const BadInput& error) {
    report_program_error(program, error.what());
    return kExitBadInput;
  }
}
}  // namespace detail

// Every program's main():
//   int main(int argc, char** argv) {
//     return panoptes::run_program("panoptes_x", [&] { return run(argc, argv); });
//   }
// runs `body` (which parses its command line with parse_command_line and returns the exit code)
// and turns an exception that escapes it into one line "<program>: <what>" on stderr and an exit
// code chosen by its type (panoptes/errors.h): kExitBadInput for an InputError (ConfigError among
// them), a std::invalid_argument and the `BadInput` types given, kExitFailure for any other
// exception, never an abort. A crash (a fatal signal) is reported with its call stack
// (install_crash_report). `BadInput` is for a library's error type that, in this program, can
// only mean bad input (panoptes_replay only reads, so every RecordingError is its input's).
template <typename... BadInput, typename Body>
int run_program(const char* program, Body&& body) {
  detail::install_crash_report(program);
  try {
    return detail::run_catching_bad_input<Body, InputError, std::invalid_argument, BadInput...>(program,
                                                                                                body);
  } catch (const std::exception& error) {
    detail::report_program_error(program, error.what());
  } catch (...) {
    detail::report_program_error(program, "unknown error");
  }
  return kExitFailure;
}

}  // namespace panoptes
