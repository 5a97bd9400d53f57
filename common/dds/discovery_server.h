#pragma once

#include <string>

#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

// Discovery through a server (docs/dds.md, "Discovery"): instead of every participant announcing
// itself and its endpoints to every other, each sends them to one server, which passes on to a
// participant only what concerns the topics it writes or reads. Data still flows directly
// between the participants. mrslam_launch --discovery-server makes its own participant the server
// and names it to the run's processes in MRSLAM_DISCOVERY_SERVER.
namespace mrslam::dds {

// The environment variable that names a run's discovery server, HOST:PORT (IPv4).
inline constexpr char kDiscoveryServerVariable[] = "MRSLAM_DISCOVERY_SERVER";

// Makes qos the discovery server listening at address (HOST:PORT, IPv4). Throws DdsError when
// address is not of that form.
void ServeDiscovery(const std::string& address, eprosima::fastdds::dds::DomainParticipantQos* qos);

// Makes qos a client of the server MRSLAM_DISCOVERY_SERVER names; unchanged when it is unset or
// empty. Throws DdsError when it is not HOST:PORT.
void UseDiscoveryServerFromEnvironment(eprosima::fastdds::dds::DomainParticipantQos* qos);

}  // namespace mrslam::dds
