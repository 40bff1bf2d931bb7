// SPDX-License-Identifier: Apache-2.0
// The QoS of topics that late joiners read (common/dds/src/topics.cpp, docs/protocol.md "Late
// joiners on transient-local topics"): their last sample is handed over at once, not after Fast
// DDS's default 70 ms + 5 ms; the other topics keep Fast DDS's timers.
#include <gtest/gtest.h>

#include "topics.h"

namespace panoptes::dds {
namespace {

using eprosima::fastrtps::Duration_t;

TEST(TopicQos, TransientLocalReadersAskAfterAMillisecondAndWritersAnswerAtOnce) {
  for (const TopicSpec& spec :
       {TopicTraits<msg::BodyDescriptions>::spec(), TopicTraits<msg::CameraInfo>::spec(),
        TopicTraits<msg::SystemCalibration>::spec()}) {
    SCOPED_TRACE(spec.name);
    for (const Qos qos : {Qos::kDefault, Qos::kReliable}) {
      EXPECT_EQ(reader_qos_for(spec, qos).reliable_reader_qos().times.initialAcknackDelay,
                Duration_t(0, 1'000'000));
      EXPECT_EQ(writer_qos_for(spec, qos).reliable_writer_qos().times.nackResponseDelay, Duration_t(0, 0));
    }
    EXPECT_EQ(reader_qos_for(spec, Qos::kDefault).durability().kind, fdds::TRANSIENT_LOCAL_DURABILITY_QOS);
  }
}

TEST(TopicQos, VolatileTopicsKeepFastDdsTimers) {
  const TopicSpec spec = TopicTraits<msg::MocapFrame>::spec();
  EXPECT_EQ(reader_qos_for(spec, Qos::kReliable).reliable_reader_qos().times.initialAcknackDelay,
            fdds::DATAREADER_QOS_DEFAULT.reliable_reader_qos().times.initialAcknackDelay);
  EXPECT_EQ(writer_qos_for(spec, Qos::kDefault).reliable_writer_qos().times.nackResponseDelay,
            fdds::DATAWRITER_QOS_DEFAULT.reliable_writer_qos().times.nackResponseDelay);
}

// Fast DDS 2.9.1 can deadlock a volatile reliable writer as a reader leaves (docs/protocol.md,
// "Closing a participant"): the writers that offer reliability on best-effort topics offer
// transient-local durability; their readers, reliable topics' writers (where it cost best-effort
// readers samples) and best-effort writers stay volatile.
TEST(TopicQos, WritersOfferingReliabilityOfferTransientLocal) {
  for (const TopicSpec& spec : {TopicTraits<msg::MocapFrame>::spec(), TopicTraits<msg::FeatureFrame>::spec(),
                                TopicTraits<msg::TrackFrame>::spec(), TopicTraits<msg::BodyPose>::spec()}) {
    SCOPED_TRACE(spec.name);
    for (const Qos qos : {Qos::kDefault, Qos::kReliable}) {
      const fdds::DataWriterQos writer = writer_qos_for(spec, qos);
      EXPECT_EQ(writer.reliability().kind, fdds::RELIABLE_RELIABILITY_QOS);
      EXPECT_EQ(writer.durability().kind, fdds::TRANSIENT_LOCAL_DURABILITY_QOS);
      EXPECT_EQ(reader_qos_for(spec, qos).durability().kind, fdds::VOLATILE_DURABILITY_QOS);
    }
    EXPECT_EQ(writer_qos_for(spec, Qos::kBestEffort).durability().kind, fdds::VOLATILE_DURABILITY_QOS);
  }
  for (const TopicSpec& spec : {TopicTraits<msg::CameraCommand>::spec(), TopicTraits<msg::TimeSync>::spec(),
                                TopicTraits<tf2_msgs::msg::dds_::TFMessage_>::spec()}) {
    SCOPED_TRACE(spec.name);
    EXPECT_EQ(writer_qos_for(spec, Qos::kDefault).reliability().kind, fdds::RELIABLE_RELIABILITY_QOS);
    EXPECT_EQ(writer_qos_for(spec, Qos::kDefault).durability().kind, fdds::VOLATILE_DURABILITY_QOS);
  }
  const TopicSpec status = TopicTraits<msg::CameraStatus>::spec();  // best effort, not offered reliable
  EXPECT_EQ(writer_qos_for(status, Qos::kDefault).reliability().kind, fdds::BEST_EFFORT_RELIABILITY_QOS);
  EXPECT_EQ(writer_qos_for(status, Qos::kDefault).durability().kind, fdds::VOLATILE_DURABILITY_QOS);
}

}  // namespace
}  // namespace panoptes::dds
