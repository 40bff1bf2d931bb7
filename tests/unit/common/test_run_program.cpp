// SPDX-License-Identifier: Apache-2.0
// run_program: the exit code a main() returns is chosen by the type of the exception that escapes
// it (panoptes/errors.h), with one line "<program>: <what>" on stderr.
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include "panoptes/errors.h"
#include "panoptes/process.h"

namespace panoptes {
namespace {

// A library error that is not an InputError (like dds::DdsError): a run-time failure unless the
// program names it as bad input.
class LibraryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class DerivedConfigError : public ConfigError {  // like dds::SecurityError
 public:
  using ConfigError::ConfigError;
};

struct Outcome {
  int exit_code = -1;
  std::string stderr_text;
};

template <typename... BadInput, typename Body>
Outcome run(Body&& body) {
  testing::internal::CaptureStderr();
  const int exit_code = run_program<BadInput...>("panoptes_test", std::forward<Body>(body));
  return {exit_code, testing::internal::GetCapturedStderr()};
}

TEST(RunProgram, ReturnsTheBodysExitCodeAndPrintsNothing) {
  const Outcome ok = run([] { return kExitOk; });
  EXPECT_EQ(ok.exit_code, kExitOk);
  EXPECT_EQ(ok.stderr_text, "");
  EXPECT_EQ(run([] { return 7; }).exit_code, 7);
}

TEST(RunProgram, BadInputExitsTwoWithOneLineNamingTheProgram) {
  const Outcome config = run([]() -> int { throw ConfigError("room.yaml", "volume", "must not be empty"); });
  EXPECT_EQ(config.exit_code, kExitBadInput);
  EXPECT_EQ(config.stderr_text, "panoptes_test: room.yaml: volume: must not be empty\n");
  EXPECT_EQ(run([]() -> int { throw InputError("v4l2:/dev/video9: cannot open"); }).exit_code, kExitBadInput);
  EXPECT_EQ(run([]() -> int { throw DerivedConfigError("a.pem", "", "unreadable"); }).exit_code,
            kExitBadInput);
  EXPECT_EQ(run([]() -> int { throw std::invalid_argument("not a number"); }).exit_code, kExitBadInput);
}

TEST(RunProgram, OtherExceptionsAreRunTimeFailures) {
  const Outcome failure = run([]() -> int { throw std::runtime_error("disk full"); });
  EXPECT_EQ(failure.exit_code, kExitFailure);
  EXPECT_EQ(failure.stderr_text, "panoptes_test: disk full\n");
  EXPECT_EQ(run([]() -> int { throw LibraryError("cannot create DDS participant"); }).exit_code,
            kExitFailure);
  EXPECT_EQ(run([]() -> int { throw std::bad_alloc(); }).exit_code, kExitFailure);
  const Outcome unknown = run([]() -> int { throw 42; });
  EXPECT_EQ(unknown.exit_code, kExitFailure);
  EXPECT_EQ(unknown.stderr_text, "panoptes_test: unknown error\n");
}

TEST(RunProgram, NamedLibraryErrorsAreBadInput) {
  EXPECT_EQ(
      run<LibraryError>([]() -> int { throw LibraryError("'rt/x' is not a Panoptes topic"); }).exit_code,
      kExitBadInput);
  EXPECT_EQ(run<LibraryError>([]() -> int { throw std::runtime_error("disk full"); }).exit_code,
            kExitFailure);
}

TEST(AsInputError, TurnsAStepsFailuresIntoInputErrorsAndKeepsItsResult) {
  EXPECT_EQ(as_input_error([] { return 5; }), 5);
  auto moved = as_input_error([] { return std::make_unique<int>(3); });  // move-only results pass
  EXPECT_EQ(*moved, 3);
  try {
    as_input_error([]() -> int { throw std::runtime_error("features:none.jsonl: no such file"); });
    FAIL() << "no exception";
  } catch (const InputError& error) {
    EXPECT_STREQ(error.what(), "features:none.jsonl: no such file");
  }
  // An InputError keeps its own type (a ConfigError still names file and key).
  try {
    as_input_error([] { throw ConfigError("typo.yaml", "detector.treshold", "unknown key"); });
    FAIL() << "no exception";
  } catch (const ConfigError& error) {
    EXPECT_EQ(error.key(), "detector.treshold");
  }
  const Outcome outcome = run([] { return as_input_error([]() -> int { throw std::runtime_error("x"); }); });
  EXPECT_EQ(outcome.exit_code, kExitBadInput);
}

// A crash under run_program names the program and the signal and prints the call stack (frames as
// "binary(+offset) [address]"), then still ends the process by that signal: the exit status a test
// script sees (128 + 11) is unchanged.
TEST(RunProgramDeathTest, ACrashIsReportedWithItsCallStackAndEndsByItsSignal) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(run_program("panoptes_crash",
                          []() -> int {
                            std::raise(SIGSEGV);
                            return 0;
                          }),
              testing::KilledBySignal(SIGSEGV),
              "panoptes_crash: fatal signal SIGSEGV; call stack[^\n]*\n(.|\n)*\\[0x[0-9a-f]+\\]");
  EXPECT_EXIT(run_program("panoptes_abort", []() -> int { std::abort(); }), testing::KilledBySignal(SIGABRT),
              "panoptes_abort: fatal signal SIGABRT");
}

// end_within: a process still running past the limit (a stalled teardown) is ended with the code
// given, after one line naming what stalled and the call stack of the thread that armed it.
TEST(EndWithinDeathTest, AProcessStillRunningPastTheLimitEndsWithTheCodeGiven) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        end_within(std::chrono::milliseconds(200), kExitOk, "closing the test participant");
        for (;;) pause();
      },
      testing::ExitedWithCode(kExitOk),
      "panoptes[a-z_]*: closing the test participant has not finished 0.2 s after the work ended; ending "
      "now with exit code 0; where it stalled[^\n]*\n(.|\n)*\\[0x[0-9a-f]+\\]");
  EXPECT_EXIT(
      {
        end_within(std::chrono::milliseconds(100), 3, "the teardown");
        end_within(std::chrono::seconds(60), 4, "a second arming");  // does nothing
        for (;;) pause();
      },
      testing::ExitedWithCode(3), "the teardown has not finished 0.1 s");
}

TEST(EndWithinDeathTest, AProcessThatEndsInTimeKeepsItsOwnExitCode) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        end_within(std::chrono::seconds(30), 3, "the teardown");
        std::exit(5);
      },
      testing::ExitedWithCode(5), "");
}

}  // namespace
}  // namespace panoptes
