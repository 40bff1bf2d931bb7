// SPDX-License-Identifier: Apache-2.0
// The time service of Panoptes over rt/panoptes/time_sync (architecture.md "Time"; seed 003
// §2.2.4.2): the estimator runs a TimeSyncServer that answers requests with its clock, each
// camera node runs a TimeSyncClient that asks, NTP-style, and fits offset and drift of its own
// clock with a ClockSync (panoptes/clock_sync.h).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "panoptes/clock_sync.h"
#include "panoptes/dds/bus.h"
#include "panoptes/time.h"

namespace panoptes::dds {

using ClockFunction = std::function<TimeNs()>;

// Answers every request on rt/panoptes/time_sync: t2 is read when the request reaches the
// listener, t3 just before the reply is written, both on `clock` (default: the wall clock, the
// common time base). Replies are written from the server's own thread, never from the DDS
// listener, in the DDS partition named by the request's client id (a writer per client, made at
// its first request; "*" until that writer has matched the client, and for clients beyond 256).
// The constructor throws DdsError if the topic cannot be joined.
class TimeSyncServer {
 public:
  explicit TimeSyncServer(Bus& bus, ClockFunction clock = wall_now_ns);
  ~TimeSyncServer();
  TimeSyncServer(const TimeSyncServer&) = delete;
  TimeSyncServer& operator=(const TimeSyncServer&) = delete;

  std::uint64_t answered() const;
  std::uint64_t answered_to_every_client() const;  // of answered(): written in partition "*"
  std::uint64_t dropped() const;                   // requests not answered because the reply queue was full

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct TimeSyncClientOptions {
  std::string client_id;                    // requests and replies carry it; usually the camera id
  ClockFunction local_clock = wall_now_ns;  // the clock being synchronised: t1 and t4
  // Requests go out fast until `fast_duration_ns` after the first reply (and again after the
  // estimate restarted), and for as long as the estimate wants more exchanges
  // (ClockSync::wants_more_exchanges), then slowly: a quick first estimate, then little traffic.
  double fast_rate_hz = 20;
  TimeNs fast_duration_ns = 2 * kNsPerSecond;
  double slow_rate_hz = 2;
  TimeNs reply_timeout_ns = kNsPerSecond;  // a request unanswered this long is counted lost
  ClockSyncOptions sync;
};

struct TimeSyncClientStatus {
  ClockEstimate estimate;
  std::uint64_t requests = 0;        // sent
  std::uint64_t replies = 0;         // matched to one of our requests
  std::uint64_t lost = 0;            // unanswered within reply_timeout_ns
  std::uint64_t kept = 0;            // replies kept by the estimator's interval filter
  std::uint64_t rejected = 0;        // invalid, too slow or contradicting the fit
  std::uint64_t unmatched = 0;       // replies to us that echo no pending request (seq and t1)
  std::uint64_t resets = 0;          // estimate restarted after a confirmed clock step
  TimeNs first_reply_local_ns = 0;   // 0 before the first reply
  TimeNs synchronised_local_ns = 0;  // local time of the first synchronised estimate (0: not yet)
  TimeNs round_trip_min_ns = 0;      // over every reply so far
  TimeNs round_trip_median_ns = 0;   // over the last replies (up to 1024)
  TimeNs round_trip_max_ns = 0;      // over the last replies
};

// Sends requests from its own thread (started by the constructor, joined by the destructor) and
// feeds the replies addressed to `client_id` into a ClockSync. Every accessor is thread-safe.
class TimeSyncClient {
 public:
  TimeSyncClient(Bus& bus, TimeSyncClientOptions options);
  ~TimeSyncClient();
  TimeSyncClient(const TimeSyncClient&) = delete;
  TimeSyncClient& operator=(const TimeSyncClient&) = delete;

  bool synchronised() const;
  ClockEstimate estimate() const;
  // The common time of a local stamp; nullopt until synchronised.
  std::optional<TimeNs> to_server(TimeNs local_ns) const;
  TimeSyncClientStatus status() const;
  // Blocks until synchronised or the timeout; returns synchronised().
  bool wait_synchronised(std::chrono::milliseconds timeout) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace panoptes::dds
