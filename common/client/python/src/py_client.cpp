// SPDX-License-Identifier: Apache-2.0
#include "py_client.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <set>
#include <stdexcept>
#include <thread>
#include <type_traits>
#include <utility>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

namespace py = pybind11;

namespace panoptes::python {
namespace {

// Set once the interpreter starts exiting (atexit): the receive threads no longer take the GIL.
std::atomic<bool> interpreter_exiting{false};

// The callbacks' state of the client whose callback this thread is running, if any: a client
// dropped from inside its own callback must not wait for that callback to end.
thread_local const CallbackState* dispatching_state = nullptr;

// Open clients, for close_all_at_exit. Touched with the GIL held only. Never destroyed: clients
// may be deallocated late in interpreter shutdown.
std::set<PyClient*>& open_clients() {
  static auto* clients = new std::set<PyClient*>();
  return *clients;
}

// Longest slice of a wait with the GIL released: Ctrl-C (KeyboardInterrupt) is noticed this soon.
constexpr double kSignalCheckS = 0.05;

client::ClientOptions make_options(const std::optional<std::filesystem::path>& profile,
                                   std::optional<int> domain, double stale_after_s, long long queue_depth,
                                   bool reliable, const std::string& up_axis) {
  client::ClientOptions options;
  options.up_axis = up_axis;
  options.profile_file = profile ? profile->string() : std::string();
  if (domain && *domain < 0)
    throw client::ClientError("domain=" + std::to_string(*domain) +
                              ": not a DDS domain id (an integer 0..232)");
  options.domain_id = domain.value_or(-1);
  if (!std::isfinite(stale_after_s) || stale_after_s > 1e6)
    throw client::ClientError("stale_after must be a positive number of seconds (at most 1e6)");
  // Rounded up to whole milliseconds, so a tiny positive value stays positive; <= 0 is refused by
  // the library with its own message.
  options.stale_after = std::chrono::milliseconds(
      stale_after_s > 0 ? static_cast<long long>(std::ceil(stale_after_s * 1000.0)) : 0);
  options.queue_depth = queue_depth > 0 ? static_cast<std::size_t>(queue_depth) : 0;
  options.reliable = reliable;
  return options;
}

// Runs `work` with the GIL released. Not pybind11's gil_scoped_release: while the interpreter
// finalizes, taking the GIL back ends a daemon thread by unwinding its stack (pthread_exit), and a
// (noexcept) destructor taking it back would abort the process instead.
template <typename Work>
auto without_gil(Work&& work) {
  using Result = decltype(work());
  PyThreadState* const thread_state = PyEval_SaveThread();
  std::exception_ptr failure;
  if constexpr (std::is_void_v<Result>) {
    try {
      work();
    } catch (...) {
      failure = std::current_exception();
    }
    PyEval_RestoreThread(thread_state);
    if (failure) std::rethrow_exception(failure);
  } else {
    std::optional<Result> result;
    try {
      result.emplace(work());
    } catch (...) {
      failure = std::current_exception();
    }
    PyEval_RestoreThread(thread_state);
    if (failure) std::rethrow_exception(failure);
    return std::move(*result);
  }
}

// One line of a Python exception's text (pybind11 may append the traceback).
std::string first_line(const std::string& text) {
  return text.substr(0, text.find('\n'));
}

// Runs the Python callable `key` of `state` with the frame. Exceptions are caught here with the GIL
// held and passed on as std::runtime_error, which the library counts (Stats::callback_errors).
void run_python_callback(const std::shared_ptr<CallbackState>& state, int key, const client::Frame& frame) {
  if (state->closed || interpreter_exiting) return;
  std::string failure;
  {
    py::gil_scoped_acquire gil;
    if (state->closed) return;
    const auto found = state->functions.find(key);
    if (found == state->functions.end()) return;
    const py::object function = found->second;  // alive while it runs, even if removed meanwhile
    const CallbackState* previous = dispatching_state;
    dispatching_state = state.get();
    try {
      function(py::cast(frame));
    } catch (py::error_already_set& error) {
      failure = first_line(error.what());
      if (!state->error_printed) {
        state->error_printed = true;
        error.discard_as_unraisable(function);  // the traceback, once, as Python prints ignored exceptions
      }
    } catch (const std::exception& error) {
      failure = error.what();
    }
    dispatching_state = previous;
  }
  if (!failure.empty()) throw std::runtime_error("Python callback raised " + failure);
}

}  // namespace

PyClient::PyClient(const std::optional<std::filesystem::path>& profile, std::optional<int> domain,
                   double stale_after_s, long long queue_depth, bool reliable, const std::string& up_axis)
    : state_(std::make_shared<CallbackState>()) {
  const client::ClientOptions options =
      make_options(profile, domain, stale_after_s, queue_depth, reliable, up_axis);
  // Opening the bus takes milliseconds: other threads may run meanwhile.
  client_ = without_gil([&] { return std::make_unique<client::Client>(options); });
  open_clients().insert(this);
}

PyClient::~PyClient() {
  try {
    destroy();
  } catch (const std::exception& error) {  // nothing else to do in a destructor; say it rather than abort
    std::fprintf(stderr, "panoptes.Client: while closing: %s\n", error.what());
  }
}

void PyClient::destroy() {
  open_clients().erase(this);
  state_->closed = true;
  // With the GIL held (pybind11 deallocates with it): no callback is inside Python code now, and one
  // that is running keeps its own reference to its callable.
  state_->functions.clear();
  handles_.clear();
  if (dispatching_state == state_.get()) {
    // Dropped inside one of its own callbacks: the library cannot be destroyed from there (it would
    // wait for this very callback). Close it now and destroy it on another thread.
    client_->close();
    try {
      std::thread([doomed = std::move(client_)]() mutable { doomed.reset(); }).detach();
    } catch (const std::exception&) {
      static_cast<void>(client_.release());  // no thread: leak it rather than deadlock
    }
    return;
  }
  without_gil([this] { client_.reset(); });
}

// Waits in slices of kSignalCheckS with the GIL released, so Ctrl-C interrupts; `wait` is the
// library's wait_for_frame, wait_for_stroke, wait_for_grab_event or wait_for_descriptions.
template <class Wait>
py::object PyClient::wait_sliced(double timeout_s, const Wait& wait) {
  if (std::isnan(timeout_s) || timeout_s < 0)
    throw py::value_error("timeout must be a non-negative number of seconds, not " +
                          std::to_string(timeout_s));
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  for (;;) {
    const double elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();
    const double slice_s = std::clamp(timeout_s - elapsed_s, 0.0, kSignalCheckS);
    const auto slice = std::chrono::milliseconds(static_cast<long long>(std::ceil(slice_s * 1000.0)));
    auto result = without_gil([&] { return wait(slice); });
    if (result.first == client::Status::kOk) return py::cast(std::move(result.second));
    if (result.first == client::Status::kClosed) return py::none();
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (std::chrono::duration<double>(Clock::now() - start).count() >= timeout_s) return py::none();
  }
}

py::object PyClient::wait_for_frame(double timeout_s) {
  return wait_sliced(timeout_s, [this](std::chrono::milliseconds slice) {
    client::FrameResult result = client_->wait_for_frame(slice);
    // The cast needs the GIL: hand the frame out, cast it after.
    return std::make_pair(result.status, std::move(result.frame));
  });
}

py::object PyClient::wait_for_stroke(double timeout_s) {
  return wait_sliced(timeout_s, [this](std::chrono::milliseconds slice) {
    client::StrokeResult result = client_->wait_for_stroke(slice);
    return std::make_pair(result.status, std::move(result.stroke));
  });
}

py::object PyClient::wait_for_grab_event(double timeout_s) {
  return wait_sliced(timeout_s, [this](std::chrono::milliseconds slice) {
    client::GrabResult result = client_->wait_for_grab_event(slice);
    return std::make_pair(result.status, std::move(result.event));
  });
}

std::optional<client::ChainUpdate> PyClient::latest_chains() {
  return without_gil([this] { return client_->latest_chains(); });
}

std::optional<client::Frame> PyClient::latest() const {
  return client_->latest();
}

int PyClient::add_callback(const py::function& callback) {
  const int key = next_key_++;
  state_->functions.emplace(key, callback);
  int handle = 0;
  try {
    handle = without_gil([&] {
      return client_->add_callback(
          [state = state_, key](const client::Frame& frame) { run_python_callback(state, key, frame); });
    });
  } catch (...) {
    state_->functions.erase(key);
    throw;
  }
  handles_.emplace(handle, key);
  return handle;
}

void PyClient::remove_callback(int handle) {
  const auto found = handles_.find(handle);
  if (found == handles_.end()) return;  // unknown or already removed: nothing to do, as in C++
  const int key = found->second;
  handles_.erase(found);
  // Waits for the callback if it is running on another thread (which needs the GIL to finish).
  without_gil([&] { client_->remove_callback(handle); });
  state_->functions.erase(key);
}

std::vector<client::BodyDescription> PyClient::body_descriptions() const {
  return client_->body_descriptions();
}

std::vector<client::SubjectDescription> PyClient::subject_descriptions() const {
  return client_->subject_descriptions();
}

py::object PyClient::wait_for_descriptions(double timeout_s) {
  return wait_sliced(timeout_s, [this](std::chrono::milliseconds slice) {
    client::DescriptionsResult result = client_->wait_for_descriptions(slice);
    return std::make_pair(result.status, std::move(result.descriptions));
  });
}

client::BodyDescription PyClient::body_description(const std::string& name) const {
  return client_->body_description(name);
}

bool PyClient::connected() const {
  return client_->connected();
}

std::string PyClient::status_text() const {
  return client_->status_text();
}

client::Stats PyClient::stats() const {
  return client_->stats();
}

client::FrameRate PyClient::frame_rate() const {
  return client_->frame_rate();
}

std::optional<client::Timecode> PyClient::timecode(const client::Frame& frame) const {
  return client_->timecode(frame);
}

client::EstimatorHealth PyClient::estimator_health() const {
  return client_->estimator_health();
}

std::string PyClient::profile_file() const {
  return client_->profile_file();
}

int PyClient::domain_id() const {
  return client_->domain_id();
}

std::string PyClient::up_axis() const {
  return client_->up_axis();
}

void PyClient::close() {
  state_->closed = true;
  without_gil([this] { client_->close(); });  // a callback waiting for the GIL can finish
  state_->functions.clear();
  handles_.clear();
}

void PyClient::close_all_at_exit() {
  interpreter_exiting = true;
  std::vector<py::object> alive;  // references: a client cannot be deallocated while it closes
  for (PyClient* client : open_clients())
    alive.push_back(py::cast(client, py::return_value_policy::reference));
  for (const py::object& client : alive) client.cast<PyClient&>().close();
}

}  // namespace panoptes::python

namespace panoptes::python {

namespace {

// The PyClient of `self`, refusing (TypeError) one whose C++ object was never constructed
// (Client.__new__(Client), a subclass that skips __init__): pybind11 would call the method on it.
PyClient& checked(py::handle self) {
  if (!py::isinstance<PyClient>(self)) throw py::type_error("not a panoptes.Client");
  auto* instance = reinterpret_cast<py::detail::instance*>(self.ptr());
  const auto value_and_holder = instance->get_value_and_holder(py::detail::get_type_info(typeid(PyClient)));
  if (!value_and_holder.holder_constructed())
    throw py::type_error("panoptes.Client.__init__() was not called");
  return *value_and_holder.value_ptr<PyClient>();
}

template <typename Result, typename... Args>
auto bound(Result (PyClient::*method)(Args...)) {
  return [method](py::handle self, Args... args) -> Result {
    return (checked(self).*method)(std::forward<Args>(args)...);
  };
}
template <typename Result, typename... Args>
auto bound(Result (PyClient::*method)(Args...) const) {
  return [method](py::handle self, Args... args) -> Result {
    return (checked(self).*method)(std::forward<Args>(args)...);
  };
}

}  // namespace

// The Client class's docstring.
constexpr const char* kClientDoc =
    R"doc(Client(profile=None, domain=None, stale_after=1.0, queue_depth=1024, reliable=True, up_axis='')

Reads Panoptes frames (bodies, markers, latency) and body descriptions from the estimator.

  profile      DDS XML profile file; None: $PANOPTES_DDS_PROFILE, else the installed loopback profile
  domain       DDS domain 0..232; None: $PANOPTES_DOMAIN, else 0
  stale_after  seconds without a frame after which connected() is False and status_text() says so
  queue_depth  frames kept for wait_for_frame(); when full the oldest is dropped (stats().frames_dropped)
  reliable     ask the estimator to repair lost frames
  up_axis      'z' (as published) or 'y' (x, y, z) -> (x, z, -y); '': $PANOPTES_UP_AXIS, else 'z'

Raises ClientError (with the library's message) when the bus cannot be opened or an option is bad.
Use it as a context manager, or call close():

    with panoptes.Client() as client:
        frame = client.wait_for_frame(2.0)
        if frame is None:
            print(client.status_text())   # "no data for 2.0 s ..."
        else:
            print(frame.body("head").position)

Every method may be called from any thread. Clients still open when the interpreter exits are closed.)doc";

void bind_client(py::module_& m) {
  using py::literals::operator""_a;
  py::class_<PyClient>(m, "Client", kClientDoc)
      .def(py::init<const std::optional<std::filesystem::path>&, std::optional<int>, double, long long, bool,
                    const std::string&>(),
           "profile"_a = py::none(), "domain"_a = py::none(), "stale_after"_a = 1.0, "queue_depth"_a = 1024,
           "reliable"_a = true, "up_axis"_a = "")
      .def("wait_for_frame", bound(&PyClient::wait_for_frame), "timeout"_a,
           R"doc(wait_for_frame(timeout) -> Frame or None

The next frame not yet returned by wait_for_frame (in order, from a queue of queue_depth frames), waiting
up to `timeout` seconds with the GIL released. None on timeout (status_text() says why) or when the client
is closed. Ctrl-C interrupts the wait (KeyboardInterrupt).)doc")
      .def("wait_for_stroke", bound(&PyClient::wait_for_stroke), "timeout"_a,
           R"doc(wait_for_stroke(timeout) -> Stroke or None

Surface mode (docs/surface.md): the next stroke event not yet returned (in order, from a queue of
queue_depth), waiting up to `timeout` seconds with the GIL released. The first call subscribes to
rt/panoptes/strokes; events before it are not seen. None on timeout or when the client is closed.)doc")
      .def("wait_for_grab_event", bound(&PyClient::wait_for_grab_event), "timeout"_a,
           R"doc(wait_for_grab_event(timeout) -> GrabEvent or None

Articulated chains (docs/articulated.md): the next grab or release not yet returned (in order, from a
queue of queue_depth), waiting up to `timeout` seconds with the GIL released. The first call subscribes
to rt/panoptes/chains; events before it are not seen. None on timeout or when the client is closed.)doc")
      .def(
          "latest_chains", bound(&PyClient::latest_chains),
          "latest_chains() -> ChainUpdate or None: the newest chain update (subscribes to rt/panoptes/chains "
          "on first use)")
      .def("latest", bound(&PyClient::latest),
           "latest() -> Frame or None: the newest frame received (does not consume the wait_for_frame queue)")
      .def("add_callback", bound(&PyClient::add_callback), "callback"_a,
           R"doc(add_callback(callback) -> int handle

callback(frame) runs on the library's receive thread for every frame, with the GIL held: keep it short.
An exception it raises is caught and counted (stats().callback_errors, stats().last_error; the first
one's traceback is printed). No callback runs after close() or remove_callback() returned.)doc")
      .def("remove_callback", bound(&PyClient::remove_callback), "handle"_a,
           "remove_callback(handle): after it returns that callback does not run (unknown handles are "
           "ignored)")
      .def("body_descriptions", bound(&PyClient::body_descriptions),
           "body_descriptions() -> list of BodyDescription: the estimator's bodies (known to late joiners "
           "too); empty until the first set arrived, which may be after the first frame")
      .def("subject_descriptions", bound(&PyClient::subject_descriptions),
           "subject_descriptions() -> list of SubjectDescription: the subjects the estimator labels "
           "(rt/panoptes/labels; known to late joiners too); empty before the first map")
      .def("wait_for_descriptions", bound(&PyClient::wait_for_descriptions), "timeout"_a,
           R"doc(wait_for_descriptions(timeout) -> list of BodyDescription or None

The estimator's bodies as soon as a set has arrived (at once if one has; an empty list: the estimator
has no bodies), waiting up to `timeout` seconds with the GIL released. None on timeout (no estimator
yet; status_text() says why) or when the client is closed. Ctrl-C interrupts the wait.)doc")
      .def("body_description", bound(&PyClient::body_description), "name"_a,
           "body_description(name) -> BodyDescription; raises UnknownBody (a KeyError) naming the body")
      .def("connected", bound(&PyClient::connected),
           "connected() -> bool: a frame arrived within stale_after")
      .def("status_text", bound(&PyClient::status_text),
           "status_text() -> str: 'receiving (240 frames/s)', 'no data for 3.2 s (last frame 1234)', "
           "'closed', ...")
      .def("stats", bound(&PyClient::stats), "stats() -> Stats: counters since the client was opened")
      .def("frame_rate", bound(&PyClient::frame_rate),
           "frame_rate() -> FrameRate: the rate the estimator publishes frames at (fixed, hz)")
      .def(
          "timecode", bound(&PyClient::timecode), py::arg("frame"),
          "timecode(frame) -> Timecode or None: the frame's SMPTE-style timecode in a fixed-rate stream at a "
          "whole rate (docs/frames.md)")
      .def("estimator_health", bound(&PyClient::estimator_health),
           "estimator_health() -> EstimatorHealth: the cameras as the estimator's latest status reports them")
      .def_property_readonly("profile_file", bound(&PyClient::profile_file),
                             "the DDS profile file the client opened")
      .def_property_readonly("domain_id", bound(&PyClient::domain_id), "the DDS domain the client opened")
      .def_property_readonly("up_axis", bound(&PyClient::up_axis),
                             "the world's up axis of everything this client returns: 'z' or 'y'")
      .def_property_readonly("closed", bound(&PyClient::closed), "close() was called")
      .def("close", bound(&PyClient::close),
           "close(): stops delivery and wakes wait_for_frame and the other waits (None). Idempotent; "
           "allowed from a callback.")
      .def("__enter__", [](py::handle self) { return py::reinterpret_borrow<py::object>(self); })
      .def(
          "__exit__",
          [](py::handle self, const py::args&) {
            checked(self).close();
            return false;
          },
          "closes the client")
      .def("__repr__", [](py::handle self) {
        const PyClient& client = checked(self);
        return "<panoptes.Client domain " + std::to_string(client.domain_id()) + ": " + client.status_text() +
               ">";
      });
}

}  // namespace panoptes::python
