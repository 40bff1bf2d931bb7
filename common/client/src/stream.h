// SPDX-License-Identifier: Apache-2.0
// One way in for each kind of data the client delivers (frames, strokes, chains): a bounded queue
// that drops its oldest item, a wait with a timeout for the pull style, and a list of callbacks for
// the push style. Private to the library (docs/clients.md, "Inside the library").
#pragma once

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "panoptes/client/client.h"

namespace panoptes::client::detail {

// What the streams of one client share: the lock that callbacks run under, so that
// remove_callback() returns only when its callback cannot run, and a callback may add or remove
// callbacks of any stream (recursive; one lock for all streams, so that two listener threads
// each removing the other's callback cannot deadlock); the handles, unique across streams; and
// where the exceptions callbacks throw are counted.
class CallbackGroup {
 public:
  using ErrorSink = std::function<void(const std::string& what)>;

  explicit CallbackGroup(ErrorSink on_error) : on_error_(std::move(on_error)) {}

  // True while this thread runs one of the group's callbacks: close() from a callback must not
  // wait for the callback to finish.
  bool dispatching_on_this_thread() const { return dispatching_ == this; }

 private:
  template <class Item, class Delivered>
  friend class Stream;

  // Runs `call`, handing what it throws to the error sink.
  template <class Call>
  void guarded(const Call& call) const {
    std::string failure;
    try {
      call();
    } catch (const std::exception& e) {
      failure = e.what();
    } catch (...) {
      failure = "an exception that is not a std::exception";
    }
    if (!failure.empty()) on_error_(failure);
  }

  std::recursive_mutex mutex_;
  int next_handle_ = 1;  // under mutex_
  ErrorSink on_error_;
  static inline thread_local const CallbackGroup* dispatching_ = nullptr;
};

// Items of type Item, queued for wait(); callbacks receive a Delivered (the same type, or the
// whole message the items came from, as the chains' callbacks receive the update while the queue
// holds its grab events).
template <class Item, class Delivered = Item>
class Stream {
 public:
  using Callback = std::function<void(const Delivered&)>;

  // Whether an item dropped from a full queue counts before anyone has called wait(): a client
  // that only uses callbacks never drains the frame queue, and its overflow is no loss.
  enum class DropCounting { kAlways, kOncePulled };

  struct Counts {
    std::uint64_t pushed = 0;   // queued since the stream began
    std::uint64_t dropped = 0;  // pushed out of a full queue, unread (see DropCounting)
  };

  struct Pulled {
    Status status = Status::kTimeout;
    std::optional<Item> item;  // set when status is kOk
  };

  Stream(CallbackGroup& group, std::size_t capacity, DropCounting counting = DropCounting::kAlways)
      : group_(group), capacity_(std::max<std::size_t>(capacity, 1)), counting_(counting) {}

  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;

  // Queues `item`, dropping the oldest when the queue holds `capacity` items; false (nothing
  // queued) once closed. Call notify() after the callbacks ran.
  bool push(Item item) {
    std::lock_guard lock(mutex_);
    if (closed_) return false;
    if (queue_.size() >= capacity_) {
      queue_.pop_front();
      if (pulling_ || counting_ == DropCounting::kAlways) ++counts_.dropped;
    }
    queue_.push_back(std::move(item));
    ++counts_.pushed;
    return true;
  }

  // Runs every callback with `value`, each guarded (what it throws is counted, never propagated).
  void dispatch(const Delivered& value) {
    std::lock_guard lock(group_.mutex_);
    if (callbacks_->empty()) return;
    // The list is replaced, never changed in place: a callback may add or remove callbacks, and
    // the loop keeps its snapshot without copying or allocating.
    const std::shared_ptr<const List> current = callbacks_;
    const CallbackGroup* outer = std::exchange(CallbackGroup::dispatching_, &group_);
    for (const auto& entry : *current) group_.guarded([&] { (*entry.second)(value); });
    CallbackGroup::dispatching_ = outer;
  }

  // Wakes a thread waiting in wait(). Separate from push() so that callbacks, the low-latency way
  // in, run before the system call that waking costs.
  void notify() { ready_.notify_one(); }

  // The oldest queued item, waiting up to `timeout` for one; kClosed once closed.
  Pulled wait(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    pulling_ = true;
    ready_.wait_for(lock, timeout, [&] { return closed_ || !queue_.empty(); });
    Pulled result;
    if (closed_) {
      result.status = Status::kClosed;
    } else if (!queue_.empty()) {
      result.status = Status::kOk;
      result.item = std::move(queue_.front());
      queue_.pop_front();
    }
    return result;
  }

  int add_callback(Callback callback) {
    std::lock_guard lock(group_.mutex_);
    const int handle = group_.next_handle_++;
    auto copy = std::make_shared<List>(*callbacks_);
    copy->emplace_back(handle, std::make_shared<const Callback>(std::move(callback)));
    callbacks_ = std::move(copy);
    return handle;
  }

  // Returns when the callback cannot run any more (unless called from that very callback). An
  // unknown handle is ignored.
  void remove_callback(int handle) {
    std::lock_guard lock(group_.mutex_);
    auto copy = std::make_shared<List>(*callbacks_);
    std::erase_if(*copy, [&](const auto& entry) { return entry.first == handle; });
    callbacks_ = std::move(copy);
  }

  // Wakes every waiter; later waits return kClosed and later pushes are ignored.
  void close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    ready_.notify_all();
  }

  Counts counts() const {
    std::lock_guard lock(mutex_);
    return counts_;
  }

 private:
  using List = std::vector<std::pair<int, std::shared_ptr<const Callback>>>;

  CallbackGroup& group_;
  const std::size_t capacity_;
  const DropCounting counting_;

  mutable std::mutex mutex_;  // guards the queue, the counts and the flags
  std::condition_variable ready_;
  std::deque<Item> queue_;
  Counts counts_;
  bool pulling_ = false;  // wait() was called
  bool closed_ = false;

  std::shared_ptr<const List> callbacks_ = std::make_shared<const List>();  // under group_.mutex_
};

}  // namespace panoptes::client::detail
