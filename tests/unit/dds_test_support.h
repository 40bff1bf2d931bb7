// SPDX-License-Identifier: Apache-2.0
// For unit tests that open DDS participants (docs/testing.md, "DDS domains"): a domain no other
// test process on this machine uses at the same time, and a bounded wait on a condition.
#pragma once

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

namespace panoptes::test {

// Unit tests take their DDS domains from 200..232, above the integration tests' ranges (1..99 and
// their empty domains 101..199, given by tests/CMakeLists.txt). A test process claims the first
// domain whose lock file (/tmp/panoptes-test-domain-<id>.lock) it can lock, and holds it until it
// exits: ctest runs each TEST as its own process, several at a time, and two of them on one domain
// would receive each other's samples. Another checkout's suite running at the same time claims
// through the same files.
inline int dds_test_domain() {
  static const int claimed = [] {
    constexpr int kFirst = 200;
    constexpr int kLast = 232;  // Fast DDS's port formula (7400 + 250 * domain + ...) ends here
    for (int domain = kFirst; domain <= kLast; ++domain) {
      const std::string path = "/tmp/panoptes-test-domain-" + std::to_string(domain) + ".lock";
      const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
      if (fd < 0) continue;
      if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return domain;  // fd stays open: the claim
      ::close(fd);
    }
    throw std::runtime_error(
        "no free DDS test domain in 200..232: every /tmp/panoptes-test-domain-*.lock is held");
  }();
  return claimed;
}

// Polls `condition` every 5 ms until it holds (true) or `timeout` has passed (false): generous,
// as the two cores are shared with other tests; a passing test never waits it out.
template <class Condition>
bool wait_until(Condition condition, std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace panoptes::test
