// SPDX-License-Identifier: Apache-2.0
// --inject-loss / --inject-jitter-ms: a lossy, jittery link emulated in the sender, for hosts whose
// kernel has no netem (docs/deployment.md). The network then sees fewer, later frames. The random
// draws are deterministic per seed (the node seeds with its camera id).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <random>
#include <utility>

#include "panoptes/time.h"

namespace panoptes::camera {

class FaultInjector {
 public:
  FaultInjector() = default;  // injects nothing
  FaultInjector(double loss, double jitter_ms, std::uint64_t seed)
      : loss_(loss), jitter_ns_(static_cast<TimeNs>(jitter_ms * 1e6)), random_(seed) {}

  bool active() const { return loss_ > 0 || jitter_ns_ > 0; }
  bool jitters() const { return jitter_ns_ > 0; }

  // The fate of the next message: nullopt = lost (counted), else its delay in ns, uniform in
  // [0, 2 · jitter] (0 without jitter).
  std::optional<TimeNs> next_delay() {
    if (loss_ > 0 && std::uniform_real_distribution<double>(0.0, 1.0)(random_) < loss_) {
      ++injected_losses_;
      return std::nullopt;
    }
    if (jitter_ns_ <= 0) return TimeNs{0};
    return std::uniform_int_distribution<TimeNs>(0, 2 * jitter_ns_)(random_);
  }

  std::uint64_t injected_losses() const { return injected_losses_; }

 private:
  double loss_ = 0;
  TimeNs jitter_ns_ = 0;
  std::mt19937_64 random_;
  std::uint64_t injected_losses_ = 0;
};

// Messages delayed by the injected jitter, sent when their time has come (in due order).
template <class Message>
class DelayLine {
 public:
  void push(TimeNs due_ns, Message message) { delayed_.emplace(due_ns, std::move(message)); }

  // Calls `write(const Message&)` for each message due at `now_ns`.
  template <class Write>
  void send_due(TimeNs now_ns, Write&& write) {
    while (!delayed_.empty() && delayed_.begin()->first <= now_ns) {
      write(delayed_.begin()->second);
      delayed_.erase(delayed_.begin());
    }
  }

  std::size_t size() const { return delayed_.size(); }

 private:
  std::multimap<TimeNs, Message> delayed_;
};

}  // namespace panoptes::camera
