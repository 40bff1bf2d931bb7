// SPDX-License-Identifier: Apache-2.0
#include "panoptes/dds/time_sync.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "panoptes_msgs/panoptes.h"

namespace panoptes::dds {

// ---------------------------------------------------------------------------------------------
// Server

struct TimeSyncServer::Impl {
  // A writer called from inside a DDS listener can deliver to a reader of this same process on
  // the same thread (intra-process delivery) and re-enter the Bus's listener lock: replies are
  // therefore written from this thread, fed by the listener through `requests`.
  static constexpr std::size_t kQueueCapacity = 256;
  // Beyond this many clients, replies to the others go to every client's partition ("*").
  static constexpr std::size_t kMaxClientWriters = 256;

  Bus* bus = nullptr;
  ClockFunction clock;
  std::unique_ptr<Writer<msg::TimeSync>> writer;  // partition "*": every client
  // A writer per client in the client's partition (docs/security.md, "Camera-scoped permissions"),
  // so a camera reads only its own replies; null where DDS refused it. Only this thread touches it.
  std::map<std::string, std::unique_ptr<Writer<msg::TimeSync>>> client_writers;
  std::unique_ptr<Reader<msg::TimeSync>> reader;
  std::mutex mutex;
  std::condition_variable wake;
  std::deque<msg::TimeSync> requests;  // t2 filled in
  bool stopping = false;
  std::thread thread;
  std::atomic<std::uint64_t> answered{0};
  std::atomic<std::uint64_t> answered_to_every_client{0};
  std::atomic<std::uint64_t> dropped{0};

  // The writer in the client's own partition once it has matched the client's reader; until then
  // (discovery of a new writer takes a moment, and no exchange should wait for it), and for a
  // client id that cannot name one partition or a writer DDS refused, the one in "*".
  Writer<msg::TimeSync>& writer_for(const std::string& client_id) {
    auto found = client_writers.find(client_id);
    if (found == client_writers.end() && names_one_partition(client_id) &&
        client_writers.size() < kMaxClientWriters) {
      std::unique_ptr<Writer<msg::TimeSync>> client_writer;
      try {
        client_writer = bus->make_writer<msg::TimeSync>(Qos::kDefault, {}, client_id);
      } catch (const DdsError&) {  // DDS refused the writer
        // Kept empty: this client's replies go to "*", and the writer is not tried again.
      }
      found = client_writers.emplace(client_id, std::move(client_writer)).first;
    }
    if (found != client_writers.end() && found->second && found->second->matched_readers() > 0)
      return *found->second;
    answered_to_every_client.fetch_add(1);
    return *writer;
  }

  void on_sample(msg::TimeSync&& message) {
    if (message.is_reply()) return;
    message.t2_ns(clock());
    {
      std::lock_guard lock(mutex);
      if (requests.size() >= kQueueCapacity) {
        requests.pop_front();
        dropped.fetch_add(1);
      }
      requests.push_back(std::move(message));
    }
    wake.notify_one();
  }

  void run() {
    std::unique_lock lock(mutex);
    while (true) {
      wake.wait(lock, [this] { return stopping || !requests.empty(); });
      if (stopping) return;
      msg::TimeSync reply = std::move(requests.front());
      requests.pop_front();
      lock.unlock();
      reply.is_reply(true);
      Writer<msg::TimeSync>& reply_writer = writer_for(reply.client_id());
      reply.t3_ns(clock());
      reply_writer.write(reply);
      answered.fetch_add(1);
      lock.lock();
    }
  }
};

TimeSyncServer::TimeSyncServer(Bus& bus, ClockFunction clock) : impl_(std::make_unique<Impl>()) {
  impl_->bus = &bus;
  impl_->clock = std::move(clock);
  impl_->writer = bus.make_writer<msg::TimeSync>();
  Impl* impl = impl_.get();
  // Best effort, like the clients' replies: a repaired request reaches the server too late and
  // would only make a long round trip that the client rejects; a lost exchange is simply retried.
  impl_->reader = bus.make_reader<msg::TimeSync>(
      [impl](msg::TimeSync&& message) { impl->on_sample(std::move(message)); }, Qos::kBestEffort);
  impl_->thread = std::thread([impl] { impl->run(); });
}

TimeSyncServer::~TimeSyncServer() {
  impl_->reader.reset();  // no listener call runs or will run after this
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->wake.notify_all();
  impl_->thread.join();
  impl_->client_writers.clear();
  impl_->writer.reset();
}

std::uint64_t TimeSyncServer::answered() const {
  return impl_->answered.load();
}

std::uint64_t TimeSyncServer::answered_to_every_client() const {
  return impl_->answered_to_every_client.load();
}

std::uint64_t TimeSyncServer::dropped() const {
  return impl_->dropped.load();
}

// ---------------------------------------------------------------------------------------------
// Client

struct TimeSyncClient::Impl {
  static constexpr std::size_t kRoundTripHistory = 1024;

  explicit Impl(TimeSyncClientOptions client_options)
      : options(std::move(client_options)), sync(options.sync) {}

  TimeSyncClientOptions options;
  std::unique_ptr<Writer<msg::TimeSync>> writer;
  std::unique_ptr<Reader<msg::TimeSync>> reader;

  mutable std::mutex mutex;
  mutable std::condition_variable changed;  // a reply was fitted, or stop
  ClockSync sync;
  std::map<std::uint64_t, TimeNs> pending;  // seq → t1
  std::uint64_t next_seq = 1;
  TimeSyncClientStatus counts;  // everything but the estimate and the round-trip statistics
  std::deque<TimeNs> round_trips;
  TimeNs fast_until_local_ns = 0;
  bool stopping = false;
  std::thread thread;

  void on_sample(msg::TimeSync&& message) {
    const TimeNs t4 = options.local_clock();
    if (!message.is_reply() || message.client_id() != options.client_id) return;
    {
      std::lock_guard lock(mutex);
      const auto request = pending.find(message.seq());
      // The echoed t1 must be ours too: a reply to an earlier process with the same id is not.
      if (request == pending.end() || request->second != message.t1_ns()) {
        ++counts.unmatched;
        return;
      }
      pending.erase(request);
      const ClockExchange exchange{message.t1_ns(), message.t2_ns(), message.t3_ns(), t4};
      ++counts.replies;
      const TimeNs round_trip = exchange.round_trip_ns();
      if (counts.replies == 1 || round_trip < counts.round_trip_min_ns) counts.round_trip_min_ns = round_trip;
      round_trips.push_back(round_trip);
      if (round_trips.size() > kRoundTripHistory) round_trips.pop_front();
      if (counts.first_reply_local_ns == 0) {
        counts.first_reply_local_ns = t4;
        fast_until_local_ns = t4 + options.fast_duration_ns;
      }
      switch (sync.add(exchange)) {
        case ClockSync::Verdict::kKept:
          ++counts.kept;
          break;
        case ClockSync::Verdict::kNotKept:
          break;
        case ClockSync::Verdict::kStepped:
          ++counts.resets;
          fast_until_local_ns = t4 + options.fast_duration_ns;  // re-converge quickly
          break;
        case ClockSync::Verdict::kInvalid:
        case ClockSync::Verdict::kTooSlow:
        case ClockSync::Verdict::kStepSuspected:
          ++counts.rejected;
          break;
      }
      if (counts.synchronised_local_ns == 0 && sync.estimate().synchronised)
        counts.synchronised_local_ns = t4;
    }
    changed.notify_all();
  }

  void run() {
    std::unique_lock lock(mutex);
    while (!stopping) {
      const TimeNs now = options.local_clock();
      for (auto it = pending.begin(); it != pending.end();) {
        if (now - it->second > options.reply_timeout_ns) {
          ++counts.lost;
          it = pending.erase(it);
        } else {
          ++it;
        }
      }
      const bool fast =
          counts.first_reply_local_ns == 0 || now < fast_until_local_ns || sync.wants_more_exchanges();
      const double rate_hz = fast ? options.fast_rate_hz : options.slow_rate_hz;
      const std::uint64_t seq = next_seq++;
      lock.unlock();

      msg::TimeSync request;
      request.client_id(options.client_id);
      request.seq(seq);
      request.is_reply(false);
      const TimeNs t1 = options.local_clock();
      request.t1_ns(t1);
      lock.lock();
      pending.emplace(seq, t1);
      ++counts.requests;
      lock.unlock();
      writer->write(request);
      lock.lock();

      const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / std::max(rate_hz, 0.01)));
      changed.wait_for(lock, period, [this] { return stopping; });
    }
  }
};

TimeSyncClient::TimeSyncClient(Bus& bus, TimeSyncClientOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {
  impl_->writer = bus.make_writer<msg::TimeSync>(Qos::kDefault, {}, impl_->options.client_id);
  Impl* impl = impl_.get();
  // Only the exchanges of this client: the server replies through a writer in this client's
  // partition, and the filter drops what its writer for every client sends to the others. Best effort: a
  // repaired reply arrives too late to time anything (it would be rejected), and a reliable reader costs
  // every writer on the topic heartbeats and gaps for it, which with N cameras is N² control messages (32
  // cameras lost half their frames to it).
  impl_->reader =
      bus.make_reader<msg::TimeSync>([impl](msg::TimeSync&& message) { impl->on_sample(std::move(message)); },
                                     Qos::kBestEffort, impl_->options.client_id);
  impl_->thread = std::thread([impl] { impl->run(); });
}

TimeSyncClient::~TimeSyncClient() {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->changed.notify_all();
  impl_->thread.join();
  impl_->reader.reset();
  impl_->writer.reset();
}

bool TimeSyncClient::synchronised() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->sync.estimate().synchronised;
}

ClockEstimate TimeSyncClient::estimate() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->sync.estimate();
}

std::optional<TimeNs> TimeSyncClient::to_server(TimeNs local_ns) const {
  std::lock_guard lock(impl_->mutex);
  const ClockEstimate& estimate = impl_->sync.estimate();
  if (!estimate.synchronised) return std::nullopt;
  return estimate.to_server(local_ns);
}

TimeSyncClientStatus TimeSyncClient::status() const {
  std::vector<TimeNs> round_trips;
  TimeSyncClientStatus status;
  {
    std::lock_guard lock(impl_->mutex);
    status = impl_->counts;
    status.estimate = impl_->sync.estimate();
    round_trips.assign(impl_->round_trips.begin(), impl_->round_trips.end());
  }
  if (!round_trips.empty()) {
    const auto middle = round_trips.begin() + static_cast<std::ptrdiff_t>(round_trips.size() / 2);
    std::nth_element(round_trips.begin(), middle, round_trips.end());
    status.round_trip_median_ns = *middle;
    status.round_trip_max_ns = *std::max_element(round_trips.begin(), round_trips.end());
  }
  return status;
}

bool TimeSyncClient::wait_synchronised(std::chrono::milliseconds timeout) const {
  std::unique_lock lock(impl_->mutex);
  return impl_->changed.wait_for(lock, timeout, [this] { return impl_->sync.estimate().synchronised; });
}

}  // namespace panoptes::dds
