// The QoS a participant gives its writers and transports, as built from config/dds_profiles.xml:
// the history depth per stream, when readers acknowledge, and the UDP socket sizes; and the type
// supports it constructs.
#include <gtest/gtest.h>

#include <memory>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"

namespace mrslam {
namespace {

constexpr int kDomain = 108;  // this test's own DDS domain
constexpr int kHistorySteps = 50;

dds::ParticipantOptions Options() {
  dds::ParticipantOptions options;
  options.domain = kDomain;
  options.name = "participant_test";
  options.history_steps = kHistorySteps;
  return options;
}

TEST(ParticipantTest, PromptWritersTakeTheProfilesHeartbeatAndPiggyback) {
  dds::Participant participant(Options());
  const auto qos = participant.WriterQos(dds::History::kRecent);
  EXPECT_EQ(qos.history().depth, kHistorySteps);
  EXPECT_EQ(qos.reliable_writer_qos().times.heartbeatPeriod, eprosima::fastrtps::Duration_t(0, 20000000));
  EXPECT_FALSE(qos.reliable_writer_qos().disable_heartbeat_piggyback);
}

TEST(ParticipantTest, PerSecondWritersHeartbeatOnceASecondAndNeverWithASample) {
  dds::Participant participant(Options());
  const auto qos = participant.WriterQos(dds::History::kRecent, dds::Acknowledgment::kPerSecond);
  EXPECT_EQ(qos.history().depth, kHistorySteps);
  EXPECT_EQ(qos.reliable_writer_qos().times.heartbeatPeriod, eprosima::fastrtps::Duration_t(1, 0));
  EXPECT_TRUE(qos.reliable_writer_qos().disable_heartbeat_piggyback);
  EXPECT_EQ(qos.reliability().kind, eprosima::fastdds::dds::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(qos.durability().kind, eprosima::fastdds::dds::TRANSIENT_LOCAL_DURABILITY_QOS);
}

TEST(ParticipantTest, WholeRunStreamsKeepTheProfilesDepth) {
  dds::Participant participant(Options());
  EXPECT_EQ(participant.WriterQos(dds::History::kWhole).history().depth, 20000);
  EXPECT_EQ(participant.ReaderQos(dds::History::kWhole).history().depth, 20000);
  EXPECT_EQ(participant.ReaderQos(dds::History::kRecent).history().depth, kHistorySteps);
}

TEST(ParticipantTest, UdpSocketsAskForFourMebibytes) {
  dds::Participant participant(Options());
  const auto& transports = participant.get()->get_qos().transport().user_transports;
  int udp = 0;
  for (const auto& t : transports) {
    const auto* d = dynamic_cast<const eprosima::fastdds::rtps::UDPv4TransportDescriptor*>(t.get());
    if (d == nullptr) continue;
    ++udp;
    EXPECT_EQ(d->receiveBufferSize, 4u << 20);
    EXPECT_EQ(d->sendBufferSize, 4u << 20);
  }
  EXPECT_EQ(udp, 1);
}

// A factor batch's type support that counts its constructions.
int constructed = 0;
struct CountedFactorBatchType : msg::FactorBatchPubSubType {
  CountedFactorBatchType() { ++constructed; }
};

TEST(ParticipantTest, ATypeSupportIsConstructedOncePerParticipant) {
  dds::Participant participant(Options());
  constructed = 0;
  {
    const dds::Reader<CountedFactorBatchType> from_r2(participant, dds::PeerTopic("r1", "r2", "factors"));
    const dds::Reader<CountedFactorBatchType> from_r3(participant, dds::PeerTopic("r1", "r3", "factors"));
    const dds::Writer<CountedFactorBatchType> to_r2(participant, dds::PeerTopic("r2", "r1", "factors"));
  }
  const dds::Reader<CountedFactorBatchType> again(participant, dds::PeerTopic("r1", "r2", "factors"));
  EXPECT_EQ(constructed, 1);
}

}  // namespace
}  // namespace mrslam
