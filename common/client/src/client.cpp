// SPDX-License-Identifier: Apache-2.0
// Client: two Bus readers (rt/panoptes/frames, rt/panoptes/body_descriptions) feeding a queue, the
// newest frame and the callbacks; on first use, readers of rt/panoptes/strokes and rt/panoptes/chains. The
// DDS listener thread converts and checks each sample, then hands the same immutable Frame to all three.
#include "panoptes/client/client.h"

#include <algorithm>
#include <array>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <mutex>
#include <utility>

#include "conversion.h"
#include "frame_sequence.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/domain.h"
#include "panoptes/time.h"
#include "panoptes_msgs/chains.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/surface.h"

namespace panoptes::client {
namespace {

constexpr std::size_t kRateWindow = 64;  // arrivals kept for status_text()'s frame rate

std::string seconds_text(std::chrono::steady_clock::duration d) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1f", std::chrono::duration<double>(d).count());
  return buffer;
}

// The client whose callbacks this thread is running, if any: close() from a callback must not wait
// for the callback to finish.
thread_local const void* dispatching_client = nullptr;

}  // namespace

std::vector<Vec3> Frame::unlabelled_markers() const {
  std::vector<Vec3> out;
  for (const auto& marker : markers)
    if (!marker.labelled()) out.push_back(marker.position);
  return out;
}

const RigidBody* Frame::body(const std::string& name) const {
  const auto it =
      std::find_if(bodies.begin(), bodies.end(), [&](const RigidBody& b) { return b.name == name; });
  return it == bodies.end() ? nullptr : &*it;
}

const Chain* ChainUpdate::chain(const std::string& name) const {
  const auto it = std::find_if(chains.begin(), chains.end(), [&](const Chain& c) { return c.name == name; });
  return it == chains.end() ? nullptr : &*it;
}

// Hidden: nested in the exported Client, it would otherwise be exported with it.
struct __attribute__((visibility("hidden"))) Client::Impl {
  using Clock = std::chrono::steady_clock;

  ClientOptions options;
  int domain = 0;
  std::string profile;
  Clock::time_point started = Clock::now();

  // Guards everything below up to the callbacks.
  mutable std::mutex mutex;
  std::condition_variable frame_ready;
  std::deque<std::shared_ptr<const Frame>> queue;
  std::shared_ptr<const Frame> newest;
  bool pulling = false;  // wait_for_frame() was called: queue overflows count as drops
  bool closed = false;
  Stats stats;
  detail::FrameSequence sequence;
  std::vector<BodyDescription> descriptions;
  std::array<Clock::time_point, kRateWindow> arrivals{};
  Clock::time_point last_arrival;

  // Held while callbacks run, so that remove_callback() returns only when its callback cannot run.
  // Recursive: a callback may add or remove callbacks.
  // The list is replaced, never changed in place, so that a frame's delivery takes a snapshot
  // without copying or allocating.
  using CallbackList = std::vector<std::pair<int, std::shared_ptr<const FrameCallback>>>;
  std::recursive_mutex callbacks_mutex;
  std::shared_ptr<const CallbackList> callbacks = std::make_shared<const CallbackList>();
  int next_handle = 1;

  // Serialises close(); the bus and readers go last, after delivery stopped.
  std::mutex lifecycle_mutex;
  std::unique_ptr<dds::Bus> bus;
  std::unique_ptr<dds::Reader<msg::MocapFrame>> frame_reader;
  std::unique_ptr<dds::Reader<msg::BodyDescriptions>> description_reader;

  // Surface mode: subscribed on first use (lifecycle_mutex); the queue and stats under `mutex`,
  // the callbacks under callbacks_mutex like the frame callbacks.
  std::unique_ptr<dds::Reader<msg::StrokeEvents>> stroke_reader;
  std::condition_variable stroke_ready;
  std::deque<Stroke> strokes;
  using StrokeCallbackList = std::vector<std::pair<int, std::shared_ptr<const StrokeCallback>>>;
  std::shared_ptr<const StrokeCallbackList> stroke_callbacks = std::make_shared<const StrokeCallbackList>();

  // Articulated chains: as the strokes (subscribed on first use); the newest update and the grab
  // event queue under `mutex`.
  std::unique_ptr<dds::Reader<msg::ChainFrame>> chain_reader;
  std::condition_variable grab_ready;
  std::deque<GrabEvent> grabs;
  std::shared_ptr<const ChainUpdate> newest_chains;
  using ChainCallbackList = std::vector<std::pair<int, std::shared_ptr<const ChainCallback>>>;
  std::shared_ptr<const ChainCallbackList> chain_callbacks = std::make_shared<const ChainCallbackList>();

  void on_frame(const msg::MocapFrame& message);
  void on_strokes(const msg::StrokeEvents& message);
  void subscribe_strokes();
  void on_chains(const msg::ChainFrame& message);
  void subscribe_chains();
  // A callback list with `callback` added under a new handle (callbacks_mutex held).
  template <class List, class Callback>
  int added(std::shared_ptr<const List>& list, Callback callback);
  template <class List>
  void removed(std::shared_ptr<const List>& list, int handle);
  // Runs `call` and counts what it throws.
  template <class Call>
  void guarded(const Call& call);
  void on_descriptions(const msg::BodyDescriptions& message);
  void dispatch(const Frame& frame);
};

void Client::Impl::on_frame(const msg::MocapFrame& message) {
  const TimeNs receive_ns = wall_now_ns();
  std::string error;
  auto converted = detail::to_frame(message, receive_ns, error);
  std::shared_ptr<const Frame> frame;
  if (converted) frame = std::make_shared<const Frame>(std::move(*converted));
  {
    std::lock_guard lock(mutex);
    if (closed) return;
    if (!frame) {
      ++stats.frames_malformed;
      stats.last_error = "frame " + std::to_string(message.frame_number()) + ": " + error;
      return;
    }
    const detail::FrameSequence::Step step = sequence.observe(frame->frame_number);
    stats.frames_missed += step.missed;
    if (step.restart) ++stats.estimator_restarts;
    const Clock::time_point now = Clock::now();
    arrivals[stats.frames_received % kRateWindow] = now;
    last_arrival = now;
    ++stats.frames_received;
    if (queue.size() >= options.queue_depth) {
      queue.pop_front();
      if (pulling) ++stats.frames_dropped;
    }
    queue.push_back(frame);
    newest = frame;
  }
  // Callbacks first: they are the low-latency way in, and waking a waiting thread costs a system call.
  dispatch(*frame);
  frame_ready.notify_one();
}

template <class Call>
void Client::Impl::guarded(const Call& call) {
  std::string failure;
  try {
    call();
  } catch (const std::exception& e) {
    failure = e.what();
  } catch (...) {
    failure = "an exception that is not a std::exception";
  }
  if (!failure.empty()) {
    std::lock_guard stats_lock(mutex);
    ++stats.callback_errors;
    stats.last_error = "callback: " + failure;
  }
}

void Client::Impl::dispatch(const Frame& frame) {
  std::lock_guard lock(callbacks_mutex);
  if (callbacks->empty()) return;
  const std::shared_ptr<const CallbackList> current = callbacks;  // a callback may add or remove callbacks
  dispatching_client = this;
  for (const auto& entry : *current) guarded([&] { (*entry.second)(frame); });
  dispatching_client = nullptr;
}

void Client::Impl::on_strokes(const msg::StrokeEvents& message) {
  std::string error;
  auto converted = detail::to_strokes(message, wall_now_ns(), error);
  {
    std::lock_guard lock(mutex);
    if (closed) return;
    if (!converted) {
      ++stats.strokes_malformed;
      stats.last_error = "strokes from '" + message.source_camera() + "': " + error;
      return;
    }
    for (const Stroke& stroke : *converted) {
      if (strokes.size() >= options.queue_depth) {
        strokes.pop_front();
        ++stats.strokes_dropped;
      }
      strokes.push_back(stroke);
      ++stats.strokes_received;
    }
  }
  {
    std::lock_guard lock(callbacks_mutex);
    const std::shared_ptr<const StrokeCallbackList> current = stroke_callbacks;
    dispatching_client = this;
    for (const Stroke& stroke : *converted)
      for (const auto& entry : *current) guarded([&] { (*entry.second)(stroke); });
    dispatching_client = nullptr;
  }
  stroke_ready.notify_one();
}

void Client::Impl::subscribe_strokes() {
  std::lock_guard lifecycle(lifecycle_mutex);
  if (stroke_reader || !bus) return;
  try {
    stroke_reader = bus->make_reader<msg::StrokeEvents>(
        [this](msg::StrokeEvents&& message) { on_strokes(message); }, dds::Qos::kReliable);
  } catch (const std::exception& e) {
    throw ClientError(std::string("panoptes client: strokes: ") + e.what());
  }
}

void Client::Impl::on_chains(const msg::ChainFrame& message) {
  std::string error;
  auto converted = detail::to_chain_update(message, wall_now_ns(), error);
  std::shared_ptr<const ChainUpdate> update;
  if (converted) update = std::make_shared<const ChainUpdate>(std::move(*converted));
  {
    std::lock_guard lock(mutex);
    if (closed) return;
    if (!update) {
      ++stats.chain_updates_malformed;
      stats.last_error = "chains from '" + message.source_camera() + "' frame " +
                         std::to_string(message.source_frame()) + ": " + error;
      return;
    }
    ++stats.chain_updates_received;
    newest_chains = update;
    for (const GrabEvent& event : update->events) {
      if (grabs.size() >= options.queue_depth) {
        grabs.pop_front();
        ++stats.grab_events_dropped;
      }
      grabs.push_back(event);
      ++stats.grab_events_received;
    }
  }
  {
    std::lock_guard lock(callbacks_mutex);
    const std::shared_ptr<const ChainCallbackList> current = chain_callbacks;
    dispatching_client = this;
    for (const auto& entry : *current) guarded([&] { (*entry.second)(*update); });
    dispatching_client = nullptr;
  }
  if (!update->events.empty()) grab_ready.notify_one();
}

void Client::Impl::subscribe_chains() {
  std::lock_guard lifecycle(lifecycle_mutex);
  if (chain_reader || !bus) return;
  try {
    chain_reader = bus->make_reader<msg::ChainFrame>(
        [this](msg::ChainFrame&& message) { on_chains(message); }, dds::Qos::kReliable);
  } catch (const std::exception& e) {
    throw ClientError(std::string("panoptes client: chains: ") + e.what());
  }
}

template <class List, class Callback>
int Client::Impl::added(std::shared_ptr<const List>& list, Callback callback) {
  const int handle = next_handle++;
  auto copy = std::make_shared<List>(*list);
  copy->emplace_back(handle, std::make_shared<const Callback>(std::move(callback)));
  list = std::move(copy);
  return handle;
}

template <class List>
void Client::Impl::removed(std::shared_ptr<const List>& list, int handle) {
  auto copy = std::make_shared<List>(*list);
  std::erase_if(*copy, [&](const auto& entry) { return entry.first == handle; });
  list = std::move(copy);
}

void Client::Impl::on_descriptions(const msg::BodyDescriptions& message) {
  std::string error;
  auto bodies = detail::to_descriptions(message, error);
  std::lock_guard lock(mutex);
  if (!bodies) {
    ++stats.descriptions_malformed;
    stats.last_error =
        "body descriptions (generation " + std::to_string(message.generation()) + "): " + error;
    return;
  }
  // The latest set wins, whichever run wrote it: a restarted estimator counts generations from 1
  // again, and its transient-local sample must replace the old run's set.
  descriptions = std::move(*bodies);
  ++stats.descriptions_received;
}

Client::Client(const ClientOptions& options) : impl_(std::make_unique<Impl>()) {
  if (options.queue_depth == 0) throw OptionError("queue_depth must be at least 1");
  if (options.stale_after.count() <= 0) throw OptionError("stale_after must be positive");
  impl_->options = options;
  try {
    impl_->domain = dds::resolve_domain(options.domain_id);  // the check every program makes
  } catch (const dds::DomainError& e) {
    throw OptionError(e.what());  // "PANOPTES_DOMAIN=abc: not a DDS domain id (an integer 0..232)"
  }
  Impl* impl = impl_.get();
  try {
    dds::BusOptions bus_options;
    bus_options.profile_file = options.profile_file;
    bus_options.domain_id = impl->domain;
    bus_options.participant_name = "panoptes_client";
    impl->bus = std::make_unique<dds::Bus>(bus_options);
    impl->profile = impl->bus->profile_file().string();
    impl->description_reader = impl->bus->make_reader<msg::BodyDescriptions>(
        [impl](msg::BodyDescriptions&& message) { impl->on_descriptions(message); });
    impl->frame_reader = impl->bus->make_reader<msg::MocapFrame>(
        [impl](msg::MocapFrame&& message) { impl->on_frame(message); },
        options.reliable ? dds::Qos::kReliable : dds::Qos::kDefault);
  } catch (const std::exception& e) {
    impl->frame_reader.reset();
    impl->description_reader.reset();
    impl->bus.reset();
    throw ClientError(std::string("panoptes client: ") + e.what());
  }
}

Client::~Client() {
  close();
}

int Client::add_callback(FrameCallback callback) {
  std::lock_guard lock(impl_->callbacks_mutex);
  return impl_->added(impl_->callbacks, std::move(callback));
}

void Client::remove_callback(int handle) {
  std::lock_guard lock(impl_->callbacks_mutex);
  impl_->removed(impl_->callbacks, handle);
}

int Client::add_stroke_callback(StrokeCallback callback) {
  int handle = 0;
  {
    std::lock_guard lock(impl_->callbacks_mutex);
    handle = impl_->added(impl_->stroke_callbacks, std::move(callback));
  }
  impl_->subscribe_strokes();
  return handle;
}

void Client::remove_stroke_callback(int handle) {
  std::lock_guard lock(impl_->callbacks_mutex);
  impl_->removed(impl_->stroke_callbacks, handle);
}

int Client::add_chain_callback(ChainCallback callback) {
  int handle = 0;
  {
    std::lock_guard lock(impl_->callbacks_mutex);
    handle = impl_->added(impl_->chain_callbacks, std::move(callback));
  }
  impl_->subscribe_chains();
  return handle;
}

void Client::remove_chain_callback(int handle) {
  std::lock_guard lock(impl_->callbacks_mutex);
  impl_->removed(impl_->chain_callbacks, handle);
}

GrabResult Client::wait_for_grab_event(std::chrono::milliseconds timeout) {
  impl_->subscribe_chains();
  std::unique_lock lock(impl_->mutex);
  impl_->grab_ready.wait_for(lock, timeout, [&] { return impl_->closed || !impl_->grabs.empty(); });
  GrabResult result;
  if (impl_->closed) {
    result.status = Status::kClosed;
  } else if (!impl_->grabs.empty()) {
    result.status = Status::kOk;
    result.event = std::move(impl_->grabs.front());
    impl_->grabs.pop_front();
  }
  return result;
}

std::optional<ChainUpdate> Client::latest_chains() {
  impl_->subscribe_chains();
  std::shared_ptr<const ChainUpdate> update;
  {
    std::lock_guard lock(impl_->mutex);
    update = impl_->newest_chains;
  }
  if (!update) return std::nullopt;
  return *update;
}

StrokeResult Client::wait_for_stroke(std::chrono::milliseconds timeout) {
  impl_->subscribe_strokes();
  std::unique_lock lock(impl_->mutex);
  impl_->stroke_ready.wait_for(lock, timeout, [&] { return impl_->closed || !impl_->strokes.empty(); });
  StrokeResult result;
  if (impl_->closed) {
    result.status = Status::kClosed;
  } else if (!impl_->strokes.empty()) {
    result.status = Status::kOk;
    result.stroke = std::move(impl_->strokes.front());
    impl_->strokes.pop_front();
  }
  return result;
}

FrameResult Client::wait_for_frame(std::chrono::milliseconds timeout) {
  std::unique_lock lock(impl_->mutex);
  impl_->pulling = true;
  impl_->frame_ready.wait_for(lock, timeout, [&] { return impl_->closed || !impl_->queue.empty(); });
  FrameResult result;
  if (impl_->closed) {
    result.status = Status::kClosed;
  } else if (!impl_->queue.empty()) {
    const std::shared_ptr<const Frame> frame = std::move(impl_->queue.front());
    impl_->queue.pop_front();
    lock.unlock();
    result.status = Status::kOk;
    result.frame = *frame;
  }
  return result;
}

std::optional<Frame> Client::latest() const {
  std::shared_ptr<const Frame> frame;
  {
    std::lock_guard lock(impl_->mutex);
    frame = impl_->newest;
  }
  if (!frame) return std::nullopt;
  return *frame;
}

std::vector<BodyDescription> Client::body_descriptions() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->descriptions;
}

BodyDescription Client::body_description(const std::string& name) const {
  std::lock_guard lock(impl_->mutex);
  std::string known;
  for (const auto& body : impl_->descriptions) {
    if (body.name == name) return body;
    known += (known.empty() ? "" : ", ") + body.name;
  }
  throw UnknownBody("unknown body '" + name + "' (known: " + (known.empty() ? "none yet" : known) + ")");
}

bool Client::connected() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->stats.frames_received > 0 &&
         Impl::Clock::now() - impl_->last_arrival <= impl_->options.stale_after;
}

std::string Client::status_text() const {
  std::lock_guard lock(impl_->mutex);
  const auto now = Impl::Clock::now();
  const Stats& stats = impl_->stats;
  if (impl_->closed) return "closed";
  if (stats.frames_received == 0)
    return "no data for " + seconds_text(now - impl_->started) +
           " s (nothing received since the client started)";
  if (now - impl_->last_arrival > impl_->options.stale_after)
    return "no data for " + seconds_text(now - impl_->last_arrival) + " s (last frame " +
           std::to_string(impl_->newest->frame_number) + ")";
  const std::uint64_t n = std::min<std::uint64_t>(stats.frames_received, kRateWindow);
  const auto oldest = impl_->arrivals[(stats.frames_received - n) % kRateWindow];
  const double span_s = std::chrono::duration<double>(impl_->last_arrival - oldest).count();
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "receiving (%.0f frames/s)",
                n > 1 && span_s > 0 ? static_cast<double>(n - 1) / span_s : 0.0);
  return buffer;
}

Stats Client::stats() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

std::string Client::profile_file() const {
  return impl_->profile;
}

int Client::domain_id() const {
  return impl_->domain;
}

void Client::close() {
  std::lock_guard lifecycle(impl_->lifecycle_mutex);
  {
    std::lock_guard lock(impl_->mutex);
    impl_->closed = true;
  }
  impl_->frame_ready.notify_all();
  impl_->stroke_ready.notify_all();
  impl_->grab_ready.notify_all();
  // From a callback the readers stay until the destructor: removing a reader waits for its
  // listener, which is this very thread.
  if (dispatching_client == impl_.get()) return;
  impl_->stroke_reader.reset();
  impl_->chain_reader.reset();
  impl_->frame_reader.reset();
  impl_->description_reader.reset();
  impl_->bus.reset();
}

}  // namespace panoptes::client
