// SPDX-License-Identifier: Apache-2.0
// Client: two Bus readers (rt/panoptes/frames, rt/panoptes/body_descriptions) feeding the frame
// stream (queue and callbacks, stream.h) and the newest frame; on first use, readers of
// rt/panoptes/strokes and rt/panoptes/chains feeding their streams. The DDS listener thread converts
// and checks each sample, then hands the same immutable Frame to the queue, the newest and the callbacks.
#include "panoptes/client/client.h"

#include <algorithm>
#include <array>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <utility>

#include "conversion.h"
#include "frame_sequence.h"
#include "panoptes/dds/bus.h"
#include "panoptes/dds/domain.h"
#include "panoptes/errors.h"
#include "panoptes/time.h"
#include "panoptes_msgs/chains.h"
#include "panoptes_msgs/panoptes.h"
#include "panoptes_msgs/surface.h"
#include "stream.h"

namespace panoptes::client {
namespace {

constexpr std::size_t kRateWindow = 64;  // arrivals kept for status_text()'s frame rate

std::string seconds_text(std::chrono::steady_clock::duration d) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1f", std::chrono::duration<double>(d).count());
  return buffer;
}

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

SubjectMarkers Frame::subject(const std::string& name) const {
  return SubjectMarkers{this, name};
}

const Marker* SubjectMarkers::marker(const std::string& name) const {
  if (frame == nullptr) return nullptr;
  const auto it = std::find_if(frame->markers.begin(), frame->markers.end(),
                               [&](const Marker& m) { return m.subject == subject && m.name == name; });
  return it == frame->markers.end() ? nullptr : &*it;
}

std::vector<const Marker*> SubjectMarkers::markers() const {
  std::vector<const Marker*> out;
  if (frame == nullptr) return out;
  for (const Marker& m : frame->markers)
    if (m.named() && m.subject == subject) out.push_back(&m);
  return out;
}

const Chain* ChainUpdate::chain(const std::string& name) const {
  const auto it = std::find_if(chains.begin(), chains.end(), [&](const Chain& c) { return c.name == name; });
  return it == chains.end() ? nullptr : &*it;
}

std::string version() {
  return PANOPTES_CLIENT_VERSION;
}

int version_major() {
  return PANOPTES_CLIENT_VERSION_MAJOR;
}

int version_minor() {
  return PANOPTES_CLIENT_VERSION_MINOR;
}

int version_patch() {
  return PANOPTES_CLIENT_VERSION_PATCH;
}

// Hidden: nested in the exported Client, it would otherwise be exported with it.
struct __attribute__((visibility("hidden"))) Client::Impl {
  using Clock = std::chrono::steady_clock;

  explicit Impl(const ClientOptions& options_in)
      : options(options_in),
        callbacks([this](const std::string& what) { on_callback_error(what); }),
        frames(callbacks, options_in.queue_depth, FrameStream::DropCounting::kOncePulled),
        strokes(callbacks, options_in.queue_depth),
        grabs(callbacks, options_in.queue_depth) {}

  ClientOptions options;
  int domain = 0;
  UpAxis up_axis = UpAxis::kZ;
  std::string profile;
  Clock::time_point started = Clock::now();

  // Guards everything below up to the streams.
  mutable std::mutex mutex;
  std::shared_ptr<const Frame> newest;
  std::shared_ptr<const ChainUpdate> newest_chains;
  bool closed = false;
  Stats stats;  // the streams' counts are added by Client::stats()
  detail::FrameSequence sequence;
  std::vector<BodyDescription> descriptions;     // valid once stats.descriptions_received > 0
  std::condition_variable descriptions_arrived;  // or closed
  std::array<Clock::time_point, kRateWindow> arrivals{};
  std::array<std::int64_t, kRateWindow> stamps{};  // of the same frames, for frame_rate()
  bool newest_fixed = false;
  Clock::time_point last_arrival;

  // Frames (callbacks and pull), strokes (surface mode) and chains (callbacks get the update, the
  // queue holds its grab events); each with its queue and lock, the callbacks under one lock.
  using FrameStream = detail::Stream<std::shared_ptr<const Frame>, Frame>;
  detail::CallbackGroup callbacks;
  FrameStream frames;
  detail::Stream<Stroke> strokes;
  detail::Stream<GrabEvent, ChainUpdate> grabs;

  // Serialises close(); the bus and readers go last, after delivery stopped. The stroke and chain
  // readers are made on first use.
  std::mutex lifecycle_mutex;
  std::unique_ptr<dds::Bus> bus;
  std::unique_ptr<dds::Reader<msg::MocapFrame>> frame_reader;
  std::unique_ptr<dds::Reader<msg::BodyDescriptions>> description_reader;
  std::unique_ptr<dds::Reader<msg::StrokeEvents>> stroke_reader;
  std::unique_ptr<dds::Reader<msg::ChainFrame>> chain_reader;
  std::unique_ptr<dds::Reader<msg::EstimatorStatus>> status_reader;
  std::unique_ptr<dds::Reader<msg::MarkerLabels>> labels_reader;
  detail::LabelMap labels;  // under `mutex`: the newest map of names (rt/panoptes/labels)
  EstimatorHealth health;   // under `mutex`
  Clock::time_point health_arrival;

  void on_frame(const msg::MocapFrame& message);
  void on_strokes(const msg::StrokeEvents& message);
  void on_chains(const msg::ChainFrame& message);
  // Makes the reader of `Message` on first use.
  template <class Message>
  void subscribe(std::unique_ptr<dds::Reader<Message>>& reader, void (Impl::*handler)(const Message&),
                 const char* what);
  void on_callback_error(const std::string& what);
  void on_descriptions(const msg::BodyDescriptions& message);
  void on_status(const msg::EstimatorStatus& message);
  void on_labels(const msg::MarkerLabels& message);
};

void Client::Impl::on_labels(const msg::MarkerLabels& message) {
  std::string error;
  auto map = detail::to_label_map(message, error);
  std::lock_guard lock(mutex);
  if (closed) return;
  if (!map) {
    ++stats.labels_malformed;
    stats.last_error = "labels (generation " + std::to_string(message.generation()) + "): " + error;
    return;
  }
  // The newest map wins, whichever run wrote it (as with the body descriptions).
  labels = std::move(*map);
  ++stats.labels_received;
}

void Client::Impl::on_status(const msg::EstimatorStatus& message) {
  EstimatorHealth next;
  next.received = true;
  next.cameras_live = static_cast<int>(message.cameras_live());
  next.cameras_lost = static_cast<int>(message.cameras_lost());
  next.tracks_unobserved = static_cast<int>(message.tracks_unobserved());
  for (const msg::CameraUsage& usage : message.cameras()) {
    CameraHealth camera;
    camera.camera_id = usage.camera_id();
    camera.live = usage.state() == 0;
    camera.since_last_frame_s = usage.since_last_frame_s();
    camera.utilisation = usage.utilisation();
    camera.refused_frames = usage.refused_frames();
    next.cameras.push_back(std::move(camera));
  }
  std::lock_guard lock(mutex);
  if (closed) return;
  health = std::move(next);
  health_arrival = Clock::now();
}

void Client::Impl::on_frame(const msg::MocapFrame& message) {
  const TimeNs receive_ns = wall_now_ns();
  std::string error;
  auto converted = detail::to_frame(message, receive_ns, error);
  if (converted) detail::turn_to_up_axis(*converted, up_axis);
  if (converted) {
    std::lock_guard lock(mutex);
    detail::apply_names(*converted, labels);  // the names as of now (docs/marker_sets.md)
  }
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
    stamps[stats.frames_received % kRateWindow] = frame->stamp_ns;
    newest_fixed = frame->source_frame == -1 && frame->source_camera.empty();
    last_arrival = now;
    ++stats.frames_received;
    newest = frame;
  }
  frames.push(frame);
  frames.dispatch(*frame);
  frames.notify();
}

void Client::Impl::on_callback_error(const std::string& what) {
  std::lock_guard stats_lock(mutex);
  ++stats.callback_errors;
  stats.last_error = "callback: " + what;
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
  }
  for (const Stroke& stroke : *converted) strokes.push(stroke);
  for (const Stroke& stroke : *converted) strokes.dispatch(stroke);
  strokes.notify();
}

void Client::Impl::on_chains(const msg::ChainFrame& message) {
  std::string error;
  auto converted = detail::to_chain_update(message, wall_now_ns(), error);
  if (converted) detail::turn_to_up_axis(*converted, up_axis);
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
  }
  for (const GrabEvent& event : update->events) grabs.push(event);
  grabs.dispatch(*update);
  if (!update->events.empty()) grabs.notify();
}

template <class Message>
void Client::Impl::subscribe(std::unique_ptr<dds::Reader<Message>>& reader,
                             void (Impl::*handler)(const Message&), const char* what) {
  std::lock_guard lifecycle(lifecycle_mutex);
  if (reader || !bus) return;
  try {
    reader = bus->make_reader<Message>([this, handler](Message&& message) { (this->*handler)(message); },
                                       dds::Qos::kReliable);
  } catch (const std::exception& e) {
    throw ClientError(std::string("panoptes client: ") + what + ": " + e.what());
  }
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
  descriptions_arrived.notify_all();
}

Client::Client(const ClientOptions& options) {
  if (options.queue_depth == 0) throw OptionError("queue_depth must be at least 1");
  if (options.stale_after.count() <= 0) throw OptionError("stale_after must be positive");
  impl_ = std::make_unique<Impl>(options);
  try {
    impl_->domain = dds::resolve_domain(options.domain_id);  // the check every program makes
  } catch (const dds::DomainError& e) {
    throw OptionError(e.what());  // "PANOPTES_DOMAIN=abc: not a DDS domain id (an integer 0..232)"
  }
  try {
    impl_->up_axis = detail::choose_up_axis(options.up_axis);
  } catch (const ConfigError& e) {
    throw OptionError(e.what());  // "PANOPTES_UP_AXIS=x: not an up axis (z or y)"
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
    impl->status_reader = impl->bus->make_reader<msg::EstimatorStatus>(
        [impl](msg::EstimatorStatus&& message) { impl->on_status(message); });
    impl->labels_reader = impl->bus->make_reader<msg::MarkerLabels>(
        [impl](msg::MarkerLabels&& message) { impl->on_labels(message); });
    impl->frame_reader = impl->bus->make_reader<msg::MocapFrame>(
        [impl](msg::MocapFrame&& message) { impl->on_frame(message); },
        options.reliable ? dds::Qos::kReliable : dds::Qos::kDefault);
  } catch (const InputError& e) {  // the profile file or the security files: the options' fault
    impl->bus.reset();
    throw OptionError(std::string("panoptes client: ") + e.what());
  } catch (const std::exception& e) {
    impl->frame_reader.reset();
    impl->status_reader.reset();
    impl->labels_reader.reset();
    impl->description_reader.reset();
    impl->bus.reset();
    throw ClientError(std::string("panoptes client: ") + e.what());
  }
}

Client::~Client() {
  close();
}

int Client::add_callback(FrameCallback callback) {
  return impl_->frames.add_callback(std::move(callback));
}

void Client::remove_callback(int handle) {
  impl_->frames.remove_callback(handle);
}

int Client::add_stroke_callback(StrokeCallback callback) {
  const int handle = impl_->strokes.add_callback(std::move(callback));
  impl_->subscribe(impl_->stroke_reader, &Impl::on_strokes, "strokes");
  return handle;
}

void Client::remove_stroke_callback(int handle) {
  impl_->strokes.remove_callback(handle);
}

int Client::add_chain_callback(ChainCallback callback) {
  const int handle = impl_->grabs.add_callback(std::move(callback));
  impl_->subscribe(impl_->chain_reader, &Impl::on_chains, "chains");
  return handle;
}

void Client::remove_chain_callback(int handle) {
  impl_->grabs.remove_callback(handle);
}

GrabResult Client::wait_for_grab_event(std::chrono::milliseconds timeout) {
  impl_->subscribe(impl_->chain_reader, &Impl::on_chains, "chains");
  auto pulled = impl_->grabs.wait(timeout);
  GrabResult result;
  result.status = pulled.status;
  if (pulled.item) result.event = std::move(*pulled.item);
  return result;
}

std::optional<ChainUpdate> Client::latest_chains() {
  impl_->subscribe(impl_->chain_reader, &Impl::on_chains, "chains");
  std::shared_ptr<const ChainUpdate> update;
  {
    std::lock_guard lock(impl_->mutex);
    update = impl_->newest_chains;
  }
  if (!update) return std::nullopt;
  return *update;
}

StrokeResult Client::wait_for_stroke(std::chrono::milliseconds timeout) {
  impl_->subscribe(impl_->stroke_reader, &Impl::on_strokes, "strokes");
  auto pulled = impl_->strokes.wait(timeout);
  StrokeResult result;
  result.status = pulled.status;
  if (pulled.item) result.stroke = std::move(*pulled.item);
  return result;
}

FrameResult Client::wait_for_frame(std::chrono::milliseconds timeout) {
  const auto pulled = impl_->frames.wait(timeout);
  FrameResult result;
  result.status = pulled.status;
  if (pulled.item) result.frame = **pulled.item;
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

FrameRate Client::frame_rate() const {
  std::lock_guard lock(impl_->mutex);
  const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(impl_->stats.frames_received, kRateWindow));
  std::vector<std::int64_t> stamps(impl_->stamps.begin(),
                                   impl_->stamps.begin() + static_cast<std::ptrdiff_t>(n));
  return {impl_->newest_fixed, detail::rate_from_stamps(std::move(stamps), impl_->newest_fixed)};
}

std::optional<Timecode> Client::timecode(const Frame& frame) const {
  return detail::timecode_of(frame.stamp_ns, frame_rate());
}

std::vector<BodyDescription> Client::body_descriptions() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->descriptions;
}

std::vector<SubjectDescription> Client::subject_descriptions() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->labels.subjects;
}

DescriptionsResult Client::wait_for_descriptions(std::chrono::milliseconds timeout) {
  std::unique_lock lock(impl_->mutex);
  impl_->descriptions_arrived.wait_for(
      lock, timeout, [this] { return impl_->closed || impl_->stats.descriptions_received > 0; });
  DescriptionsResult result;
  if (impl_->closed) {
    result.status = Status::kClosed;
  } else if (impl_->stats.descriptions_received > 0) {
    result.status = Status::kOk;
    result.descriptions = impl_->descriptions;
  }
  return result;
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

EstimatorHealth Client::estimator_health() const {
  std::lock_guard lock(impl_->mutex);
  EstimatorHealth health = impl_->health;
  if (health.received)
    health.age_s = std::chrono::duration<double>(Impl::Clock::now() - impl_->health_arrival).count();
  return health;
}

Stats Client::stats() const {
  Stats stats;
  {
    std::lock_guard lock(impl_->mutex);
    stats = impl_->stats;
  }
  stats.frames_dropped = impl_->frames.counts().dropped;
  const auto strokes = impl_->strokes.counts();
  stats.strokes_received = strokes.pushed;
  stats.strokes_dropped = strokes.dropped;
  const auto grabs = impl_->grabs.counts();
  stats.grab_events_received = grabs.pushed;
  stats.grab_events_dropped = grabs.dropped;
  return stats;
}

std::string Client::profile_file() const {
  return impl_->profile;
}

int Client::domain_id() const {
  return impl_->domain;
}

std::string Client::up_axis() const {
  return up_axis_name(impl_->up_axis);
}

void Client::close() {
  std::lock_guard lifecycle(impl_->lifecycle_mutex);
  {
    std::lock_guard lock(impl_->mutex);
    impl_->closed = true;
  }
  impl_->descriptions_arrived.notify_all();
  impl_->frames.close();
  impl_->strokes.close();
  impl_->grabs.close();
  // From a callback the readers stay until the destructor: removing a reader waits for its
  // listener, which is this very thread.
  if (impl_->callbacks.dispatching_on_this_thread()) return;
  impl_->stroke_reader.reset();
  impl_->chain_reader.reset();
  impl_->frame_reader.reset();
  impl_->status_reader.reset();
  impl_->labels_reader.reset();
  impl_->description_reader.reset();
  impl_->bus.reset();
}

}  // namespace panoptes::client
