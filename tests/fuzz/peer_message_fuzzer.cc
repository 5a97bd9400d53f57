// libFuzzer harness: any bytes a peer could write into r1's inbox (the first byte picks the
// message type, the rest is its CDR payload) are decoded, converted and handed to r1's
// cooperation with a FastSLAM filter, which validates and applies or rejects them, without a
// crash, a hang or a leak.
#include <cstddef>
#include <cstdint>
#include <memory>

#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "mrslamPubSubTypes.h"
#include "robot_agent/cooperation/cooperation.h"
#include "robot_agent/factory/filter_factory.h"
#include "robot_agent/node/msg_conversion.h"
#include "tests/fuzz/cdr_input.h"

namespace mrslam::fuzz {
namespace {

const robot_agent::AgentOptions& Agent() {
  static const robot_agent::AgentOptions agent = common::AgentOptionsFor(
      common::LoadScenario(MRSLAM_SOURCE_DIR "/config/paper_two_robots.yaml", {"filter.particles=20"}), "r1");
  return agent;
}

template <typename PubSubType, typename Message>
void Deliver(const std::uint8_t* data, std::size_t size,
             std::vector<Message> robot_agent::cooperation::PeerInbox::*list) {
  typename PubSubType::type message;
  if (!Decode<PubSubType>(data, size, &message)) return;
  robot_agent::cooperation::PeerInbox inbox;
  (inbox.*list).push_back(robot_agent::FromMsg(message));
  robot_agent::cooperation::Cooperation cooperation(Agent());
  const auto filter = robot_agent::factory::CreateFilter(Agent(), 1);
  cooperation.Receive(inbox, filter.get());
}

}  // namespace
}  // namespace mrslam::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace mrslam;
  using robot_agent::cooperation::PeerInbox;
  if (size == 0) return 0;
  switch (data[0] % 3) {
    case 0:
      fuzz::Deliver<msg::RelativeMeasurementPubSubType>(data + 1, size - 1, &PeerInbox::measurements);
      break;
    case 1:
      fuzz::Deliver<msg::MapSnapshotPubSubType>(data + 1, size - 1, &PeerInbox::maps);
      break;
    default:
      fuzz::Deliver<msg::LandmarkMovedNoticePubSubType>(data + 1, size - 1, &PeerInbox::moved);
      break;
  }
  return 0;
}
