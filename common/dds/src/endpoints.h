// SPDX-License-Identifier: Apache-2.0
// Private to panoptes_dds: what the typed and the raw readers and writers share.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>

#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include "panoptes/dds/decode.h"
#include "scoping.h"

namespace panoptes::dds {

class WriterListener : public fdds::DataWriterListener {
 public:
  void on_publication_matched(fdds::DataWriter*, const fdds::PublicationMatchedStatus& status) override {
    matched.store(status.current_count);
  }
  std::atomic<int> matched{0};
};

// What the typed and the raw readers' listeners share: the callback, the check of a sample's id
// against its writer's partition on a camera-scoped topic, the counts, and deactivation.
template <class Callback>
class GatedReaderListener : public fdds::DataReaderListener {
 public:
  // `partitions`, on a camera-scoped topic: the writers' partitions each sample is checked against.
  GatedReaderListener(Callback callback, ReceiveCounters& counters, const WriterPartitions* partitions)
      : callback_(std::move(callback)), counters_(counters), partitions_(partitions) {}

  void on_subscription_matched(fdds::DataReader*, const fdds::SubscriptionMatchedStatus& status) override {
    matched.store(status.current_count);
  }
  // After this returns no callback is running or will run.
  void deactivate() {
    std::lock_guard<std::mutex> lock(mutex_);
    active_ = false;
  }

  std::atomic<int> matched{0};
  std::atomic<std::uint64_t> received{0};

 protected:
  // False (counted) when the sample's id, from `id_of()` (asked only on a camera-scoped topic),
  // names another camera than its writer's partition.
  template <class IdOf>
  bool admits(const fdds::SampleInfo& info, const IdOf& id_of) {
    return partitions_ == nullptr || partitions_->admits(info.publication_handle, id_of(), counters_);
  }

  Callback callback_;
  ReceiveCounters& counters_;
  std::mutex mutex_;  // held while a callback runs
  bool active_ = true;

 private:
  const WriterPartitions* partitions_;
};

}  // namespace panoptes::dds
