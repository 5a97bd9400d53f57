// The QoS a participant gives its writers and transports, as built from config/dds_profiles.xml:
// the history depth per stream, when readers acknowledge, and the UDP socket sizes; the type
// supports it constructs; and discovery through a server (MRSLAM_DISCOVERY_SERVER).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include "common/dds/discovery_server.h"
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

using eprosima::fastrtps::rtps::DiscoveryProtocol_t;

// Sets MRSLAM_DISCOVERY_SERVER while it lives.
class DiscoveryServerVariable {
 public:
  explicit DiscoveryServerVariable(const std::string& value) {
    setenv(dds::kDiscoveryServerVariable, value.c_str(), 1);
  }
  ~DiscoveryServerVariable() { unsetenv(dds::kDiscoveryServerVariable); }
  DiscoveryServerVariable(const DiscoveryServerVariable&) = delete;
  DiscoveryServerVariable& operator=(const DiscoveryServerVariable&) = delete;
};

const std::string kServer = "127.0.0.1:7208";  // mrslam_launch's address for domain 108

dds::ParticipantOptions ServerOptions() {
  dds::ParticipantOptions options = Options();
  options.name = "participant_test_server";
  options.serve_discovery_at = kServer;
  return options;
}

bool WaitForMatch(const dds::Writer<msg::StepClockPubSubType>& writer, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (writer.MatchedReaders() == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return writer.MatchedReaders() > 0;
}

TEST(ParticipantTest, WithoutTheVariableAParticipantAnnouncesItselfToEveryOther) {
  unsetenv(dds::kDiscoveryServerVariable);
  dds::Participant participant(Options());
  EXPECT_EQ(participant.get()->get_qos().wire_protocol().builtin.discovery_config.discoveryProtocol,
            DiscoveryProtocol_t::SIMPLE);
}

TEST(ParticipantTest, AnAddressThatIsNotHostAndPortIsOneClearError) {
  for (const std::string bad : {"nonsense", "127.0.0.1", "127.0.0.1:port"}) {
    const DiscoveryServerVariable variable(bad);
    try {
      dds::Participant participant(Options());
      ADD_FAILURE() << bad << " was taken";
    } catch (const dds::DdsError& e) {
      EXPECT_EQ(std::string(e.what()), "MRSLAM_DISCOVERY_SERVER '" + bad + "' is not HOST:PORT");
    }
  }
  dds::ParticipantOptions options = ServerOptions();
  options.serve_discovery_at = "localhost";
  EXPECT_THROW(dds::Participant{options}, dds::DdsError);
}

// Two clients of one server find each other through it; a participant of the same domain that
// does not use the server finds neither.
TEST(ParticipantTest, ClientsOfAServerFindEachOtherAndNoOneElse) {
  unsetenv(dds::kDiscoveryServerVariable);
  dds::Participant outsider(Options());
  const dds::Writer<msg::StepClockPubSubType> outsiders_writer(outsider, dds::kClockTopic);
  dds::Participant server(ServerOptions());
  EXPECT_EQ(server.get()->get_qos().wire_protocol().builtin.discovery_config.discoveryProtocol,
            DiscoveryProtocol_t::SERVER);
  const DiscoveryServerVariable variable(kServer);
  dds::Participant writing(Options()), reading(Options());
  EXPECT_EQ(writing.get()->get_qos().wire_protocol().builtin.discovery_config.discoveryProtocol,
            DiscoveryProtocol_t::CLIENT);
  const dds::Writer<msg::StepClockPubSubType> writer(writing, dds::kClockTopic);
  const dds::Reader<msg::StepClockPubSubType> reader(reading, dds::kClockTopic);
  ASSERT_TRUE(WaitForMatch(writer, std::chrono::seconds(10)));
  EXPECT_EQ(writer.MatchedReaders(), 1);
  // The outsider announces itself by multicast, which the clients do not listen to, and they
  // announce themselves only to the server: well past the profiles' first announcements (10 at
  // 20 ms) it has matched no one.
  EXPECT_FALSE(WaitForMatch(outsiders_writer, std::chrono::milliseconds(1500)));
}

}  // namespace
}  // namespace mrslam
