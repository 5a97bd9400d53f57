// libFuzzer harness: any bytes a peer could write into r1's inbox (the first byte picks the
// message type, the rest is its CDR payload) are decoded, converted and handed to r1's
// cooperation (sharing raw measurements for a batch of them) with a FastSLAM filter, which validates and applies or
// rejects them, without a crash, a hang or a leak.
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

// r1 of paper_two_robots; sharing its raw measurements or not.
const robot_agent::AgentOptions& Agent(bool share_factors = false) {
  static const auto make = [](bool share) {
    return common::AgentOptionsFor(
        common::LoadScenario(
            MRSLAM_SOURCE_DIR "/config/paper_two_robots.yaml",
            {"filter.particles=20", std::string("cooperation.share_factors=") + (share ? "true" : "false")}),
        "r1");
  };
  static const robot_agent::AgentOptions plain = make(false), sharing = make(true);
  return share_factors ? sharing : plain;
}

template <typename PubSubType, typename Message>
void Deliver(const std::uint8_t* data, std::size_t size,
             std::vector<Message> robot_agent::cooperation::PeerInbox::*list, bool share_factors = false) {
  typename PubSubType::type message;
  if (!Decode<PubSubType>(data, size, &message)) return;
  robot_agent::cooperation::PeerInbox inbox;
  (inbox.*list).push_back(robot_agent::FromMsg(message));
  robot_agent::cooperation::Cooperation cooperation(Agent(share_factors));
  const auto filter = robot_agent::factory::CreateFilter(Agent(share_factors), 1);
  cooperation.Receive(inbox, filter.get());
}

}  // namespace
}  // namespace mrslam::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace mrslam;
  using robot_agent::cooperation::PeerInbox;
  if (size == 0) return 0;
  switch (data[0] % 4) {
    case 0:
      fuzz::Deliver<msg::RelativeMeasurementPubSubType>(data + 1, size - 1, &PeerInbox::measurements);
      break;
    case 1:
      fuzz::Deliver<msg::MapSnapshotPubSubType>(data + 1, size - 1, &PeerInbox::maps);
      break;
    case 2:
      fuzz::Deliver<msg::LandmarkMovedNoticePubSubType>(data + 1, size - 1, &PeerInbox::moved);
      break;
    default:
      fuzz::Deliver<msg::FactorBatchPubSubType>(data + 1, size - 1, &PeerInbox::factors, /*share_factors=*/true);
      break;
  }
  return 0;
}
