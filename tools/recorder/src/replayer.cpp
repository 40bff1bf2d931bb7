// SPDX-License-Identifier: Apache-2.0
#include "panoptes/recorder/replayer.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <set>
#include <stdexcept>
#include <thread>

#include "panoptes/dds/cdr.h"
#include "panoptes/recorder/ros2_naming.h"
#include "panoptes/recording/mcap_reader.h"

namespace panoptes::recorder {

namespace {

using Clock = std::chrono::steady_clock;

std::int64_t wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// The DDS names of the topics in `wanted` (either naming); empty (every recordable topic) if none.
std::set<std::string> wanted_topics(const std::vector<std::string>& wanted) {
  std::set<std::string> out;
  for (const auto& name : wanted) {
    const std::string dds_name = name.rfind("rt/", 0) == 0 ? name : dds_topic_name(name).value_or(name);
    if (!dds::recordable_topic(dds_name))
      throw std::invalid_argument("--topics: '" + name +
                                  "' is not a Panoptes topic nor one of its ROS 2 topics");
    out.insert(dds_name);
  }
  return out;
}

}  // namespace

Replayer::Replayer(const std::filesystem::path& path, ReplayOptions options) : options_(std::move(options)) {
  const std::set<std::string> wanted = wanted_topics(options_.topics);
  recording::McapReader reader(path);
  std::map<std::uint16_t, std::size_t> channel_topic;  // channel id -> index in topics_, or npos
  const auto report = reader.read([&](const recording::MessageView& m) {
    auto [it, added] = channel_topic.try_emplace(m.channel->id, SIZE_MAX);
    if (added) {
      const auto name = dds_topic_name(m.channel->topic);
      const bool chosen =
          name && (wanted.empty() ? dds::recordable_topic(*name).has_value() : wanted.count(*name) != 0);
      if (chosen && m.channel->message_encoding == kMessageEncoding) {
        const auto found = std::find(topics_.begin(), topics_.end(), *name);
        it->second = static_cast<std::size_t>(found - topics_.begin());
        if (found == topics_.end()) topics_.push_back(*name);
      }
    }
    if (it->second == SIZE_MAX) return;
    messages_.push_back({it->second, m.log_time, std::vector<std::uint8_t>(m.data.begin(), m.data.end())});
  });
  problems_ = report.problems;
  std::stable_sort(messages_.begin(), messages_.end(),
                   [](const ReplayMessage& a, const ReplayMessage& b) { return a.log_time < b.log_time; });
  if (messages_.empty()) return;
  const std::uint64_t first = messages_.front().log_time;
  const auto from = first + static_cast<std::uint64_t>(std::max(0.0, options_.start_s) * 1e9);
  const auto to = options_.end_s < 0 ? UINT64_MAX : first + static_cast<std::uint64_t>(options_.end_s * 1e9);
  std::erase_if(messages_, [&](const ReplayMessage& m) { return m.log_time < from || m.log_time > to; });
}

ReplayReport Replayer::run(dds::Bus& bus, double discovery_s, const std::function<bool()>& stop) {
  std::vector<std::unique_ptr<dds::RawWriter>> writers;
  for (const auto& topic : topics_) writers.push_back(bus.make_raw_writer(topic));
  // Until every writer has matched a reader, or discovery_s has passed (a topic nobody reads).
  const auto discovery_end =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(discovery_s));
  const auto all_matched = [&] {
    return std::all_of(writers.begin(), writers.end(),
                       [](const auto& w) { return w->matched_readers() > 0; });
  };
  while (Clock::now() < discovery_end && !all_matched() && !stop())
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (all_matched())
    std::this_thread::sleep_for(std::chrono::milliseconds(200));  // let the match settle both ways
  ReplayReport report;
  if (messages_.empty()) return report;
  const std::uint64_t first = messages_.front().log_time;
  report.recorded_s = static_cast<double>(messages_.back().log_time - first) * 1e-9;
  const auto begin = Clock::now();
  auto next_progress = begin + std::chrono::seconds(1);
  std::vector<std::uint8_t> shifted;
  do {
    const auto pass_start = Clock::now();
    const std::int64_t shift_ns = wall_ns() - static_cast<std::int64_t>(first);
    if (report.passes == 0) report.first_shift_ns = shift_ns;
    for (const auto& m : messages_) {
      if (stop()) break;
      const auto due =
          pass_start +
          std::chrono::nanoseconds(
              options_.rate > 0
                  ? static_cast<std::int64_t>(static_cast<double>(m.log_time - first) / options_.rate)
                  : 0);
      auto now = Clock::now();
      if (now < due) {
        std::this_thread::sleep_until(due);
        now = Clock::now();
      }
      const double lag_ms =
          options_.rate > 0 ? std::chrono::duration<double, std::milli>(now - due).count() : 0;
      report.max_lag_ms = std::max(report.max_lag_ms, lag_ms);
      if (lag_ms > options_.late_ms) ++report.late;
      if (options_.restamp) {
        shifted = m.cdr;
        if (dds::shift_sample_times(topics_[m.topic], shifted, shift_ns)) writers[m.topic]->write(shifted);
      } else {
        writers[m.topic]->write(m.cdr);
      }
      ++report.published;
      ++report.per_topic[topics_[m.topic]];
      if (!options_.quiet && now >= next_progress) {
        std::fprintf(stderr, "panoptes_replay: %.1f s of %.1f s, %llu messages, lag %.1f ms\n",
                     static_cast<double>(m.log_time - first) * 1e-9, report.recorded_s,
                     static_cast<unsigned long long>(report.published), lag_ms);
        next_progress += std::chrono::seconds(1);
      }
    }
    ++report.passes;
  } while (options_.loop && !stop());
  report.wall_s = std::chrono::duration<double>(Clock::now() - begin).count();
  return report;
}

}  // namespace panoptes::recorder
