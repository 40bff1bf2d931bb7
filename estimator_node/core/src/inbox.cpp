// SPDX-License-Identifier: Apache-2.0
#include "panoptes/estimator/inbox.h"

#include <algorithm>

namespace panoptes::estimator {
namespace {
bool later(const FeatureFrame& a, const FeatureFrame& b) {
  return a.stamp_ns > b.stamp_ns;
}
}  // namespace

FrameInbox::FrameInbox(std::size_t capacity, TimeNs latency_window_ns)
    : capacity_(std::max<std::size_t>(capacity, 1)), window_ns_(latency_window_ns) {}

bool FrameInbox::push(FeatureFrame frame) {
  std::unique_lock<std::mutex> lock(mutex_);
  bool dropped = false;
  if (heap_.size() >= capacity_) {
    // Drop the oldest: it is the most likely to be late already.
    std::pop_heap(heap_.begin(), heap_.end(), later);
    heap_.pop_back();
    ++drops_;
    dropped = true;
  }
  heap_.push_back(std::move(frame));
  std::push_heap(heap_.begin(), heap_.end(), later);
  ++pushes_;
  lock.unlock();
  pushed_.notify_one();
  return !dropped;
}

void FrameInbox::wait(TimeNs now_ns, std::chrono::nanoseconds max_wait) {
  std::unique_lock<std::mutex> lock(mutex_);
  TimeNs wait_ns = max_wait.count();
  if (!heap_.empty()) wait_ns = std::min(wait_ns, heap_.front().stamp_ns + window_ns_ - now_ns);
  if (wait_ns <= 0) return;
  const std::uint64_t pushes = pushes_;
  pushed_.wait_for(lock, std::chrono::nanoseconds(wait_ns), [&] { return pushes_ != pushes; });
}

std::vector<FeatureFrame> FrameInbox::pop_due(TimeNs now_ns) {
  std::vector<FeatureFrame> due;
  std::lock_guard<std::mutex> lock(mutex_);
  while (!heap_.empty() && heap_.front().stamp_ns <= now_ns - window_ns_) {
    std::pop_heap(heap_.begin(), heap_.end(), later);
    due.push_back(std::move(heap_.back()));
    heap_.pop_back();
  }
  return due;
}

bool FrameInbox::has_due(TimeNs now_ns) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return !heap_.empty() && heap_.front().stamp_ns <= now_ns - window_ns_;
}

std::optional<TimeNs> FrameInbox::next_due_ns() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (heap_.empty()) return std::nullopt;
  return heap_.front().stamp_ns + window_ns_;
}

std::vector<FeatureFrame> FrameInbox::drain() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<FeatureFrame> all = std::move(heap_);
  heap_.clear();
  std::sort(all.begin(), all.end(),
            [](const FeatureFrame& a, const FeatureFrame& b) { return a.stamp_ns < b.stamp_ns; });
  return all;
}

std::uint64_t FrameInbox::drops() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return drops_;
}

std::size_t FrameInbox::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return heap_.size();
}

}  // namespace panoptes::estimator
