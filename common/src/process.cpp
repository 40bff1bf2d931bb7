// SPDX-License-Identifier: Apache-2.0
#include "panoptes/process.h"

#include <atomic>
#include <csignal>

namespace panoptes {
namespace {
std::atomic<bool> g_stop{false};  // the one global: a signal handler can reach nothing else
extern "C" void on_stop_signal(int /*signal*/) {
  g_stop.store(true);
}
}  // namespace

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool stop_requested() {
  return g_stop.load();
}
void request_stop() {
  g_stop.store(true);
}

}  // namespace panoptes
