#include "robot_agent/node/peer_endpoints.h"

namespace mrslam::robot_agent {

PeerReaders::PeerReaders(dds::Participant& participant, const std::string& self, const std::string& peer,
                         dds::Notifier* notifier)
    : relative(participant, dds::PeerTopic(self, peer, "relative"), notifier),
      map(participant, dds::PeerTopic(self, peer, "map"), notifier),
      moved(participant, dds::PeerTopic(self, peer, "moved"), notifier) {}

PeerWriters::PeerWriters(dds::Participant& participant, const std::string& self, const std::string& peer)
    : relative(participant, dds::PeerTopic(peer, self, "relative")),
      map(participant, dds::PeerTopic(peer, self, "map")),
      moved(participant, dds::PeerTopic(peer, self, "moved")) {}

}  // namespace mrslam::robot_agent
