#include "robot_agent/node/peer_endpoints.h"

namespace mrslam::robot_agent {

PeerReaders::PeerReaders(dds::Participant& participant, const std::string& self, const std::string& peer,
                         dds::Notifier* notifier, bool share_factors)
    : relative(participant, dds::PeerTopic(self, peer, "relative"), notifier),
      map(participant, dds::PeerTopic(self, peer, "map"), notifier),
      moved(participant, dds::PeerTopic(self, peer, "moved"), notifier) {
  if (share_factors) factors.emplace(participant, dds::PeerTopic(self, peer, "factors"), notifier);
}

PeerWriters::PeerWriters(dds::Participant& participant, const std::string& self, const std::string& peer,
                         bool share_factors)
    : relative(participant, dds::PeerTopic(peer, self, "relative")),
      map(participant, dds::PeerTopic(peer, self, "map")),
      moved(participant, dds::PeerTopic(peer, self, "moved")) {
  if (share_factors) factors.emplace(participant, dds::PeerTopic(peer, self, "factors"));
}

}  // namespace mrslam::robot_agent
