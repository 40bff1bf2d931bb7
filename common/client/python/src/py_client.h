// SPDX-License-Identifier: Apache-2.0
// PyClient: panoptes::client::Client for Python (the `panoptes.Client` class). It owns the Python
// callables given to add_callback and runs them on the library's receive thread with the GIL held;
// every call that may wait for a running callback (close, remove_callback, destruction) releases the
// GIL first, so a callback waiting for the GIL can finish.
#pragma once

#include <atomic>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/pybind11.h>

#include "panoptes/client/client.h"

namespace panoptes::python {

// Shared by a PyClient and the C++ callbacks it registered (which may outlive it by a moment when
// the client is dropped from inside one of its own callbacks). Touched only with the GIL held,
// except `closed`, which the receive thread reads before taking the GIL.
struct CallbackState {
  std::map<int, pybind11::object> functions;  // handle -> Python callable; emptied before close
  std::atomic<bool> closed{false};
  bool error_printed = false;  // the first exception's traceback goes to stderr, the others are counted
};

class PyClient {
 public:
  PyClient(const std::optional<std::filesystem::path>& profile, std::optional<int> domain,
           double stale_after_s, long long queue_depth, bool reliable, const std::string& up_axis);
  ~PyClient();
  PyClient(const PyClient&) = delete;
  PyClient& operator=(const PyClient&) = delete;

  pybind11::object wait_for_frame(double timeout_s);
  pybind11::object wait_for_stroke(double timeout_s);      // surface mode: a Stroke or None
  pybind11::object wait_for_grab_event(double timeout_s);  // chains: a GrabEvent or None
  std::optional<client::ChainUpdate> latest_chains();
  std::optional<client::Frame> latest() const;
  int add_callback(const pybind11::function& callback);
  void remove_callback(int handle);
  std::vector<client::BodyDescription> body_descriptions() const;
  std::vector<client::SubjectDescription> subject_descriptions() const;
  pybind11::object wait_for_descriptions(double timeout_s);  // a list of BodyDescription or None
  client::BodyDescription body_description(const std::string& name) const;
  bool connected() const;
  std::string status_text() const;
  client::Stats stats() const;
  client::EstimatorHealth estimator_health() const;
  client::FrameRate frame_rate() const;
  std::optional<client::Timecode> timecode(const client::Frame& frame) const;
  std::string profile_file() const;
  int domain_id() const;
  std::string up_axis() const;
  bool closed() const { return state_->closed; }
  void close();

  // Closes every open client: registered with atexit, so no callback runs while the interpreter
  // shuts down. Clients created afterwards never call into Python.
  static void close_all_at_exit();

 private:
  template <class Wait>
  pybind11::object wait_sliced(double timeout_s, const Wait& wait);
  void destroy();  // the destructor's work: close, drop the callables, destroy the library's client

  std::unique_ptr<client::Client> client_;
  std::shared_ptr<CallbackState> state_;
  std::map<int, int> handles_;  // the library's callback handle -> key in state_->functions
  int next_key_ = 0;
};

}  // namespace panoptes::python
