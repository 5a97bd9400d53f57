#include "common/dds/discovery_server.h"

#include <cstdlib>

#include <fastdds/rtps/attributes/ServerAttributes.h>

#include "common/dds/participant.h"

namespace mrslam::dds {

namespace {

using eprosima::fastdds::rtps::RemoteServerList_t;
using eprosima::fastrtps::rtps::DiscoveryProtocol_t;

// The server at address (HOST:PORT) with the GUID prefix of the first server of a list, the one
// its clients expect; throws DdsError naming `what` when address is not of that form.
RemoteServerList_t ServerAt(const std::string& address, const std::string& what) {
  RemoteServerList_t servers;
  if (address.find(':') == std::string::npos ||
      !eprosima::fastdds::rtps::load_environment_server_info(address, servers) || servers.size() != 1) {
    throw DdsError(what + " '" + address + "' is not HOST:PORT");
  }
  return servers;
}

// How often a client asks the server until answered, and the server looks for news to pass on:
// Fast DDS's 450 ms would add about a second to every start.
const eprosima::fastrtps::Duration_t kSyncPeriod(0, 20000000);

}  // namespace

void ServeDiscovery(const std::string& address, eprosima::fastdds::dds::DomainParticipantQos* qos) {
  const RemoteServerList_t servers = ServerAt(address, "the discovery server's address");
  auto& wire = qos->wire_protocol();
  wire.builtin.discovery_config.discoveryProtocol = DiscoveryProtocol_t::SERVER;
  wire.builtin.discovery_config.discoveryServer_client_syncperiod = kSyncPeriod;
  wire.prefix = servers.front().guidPrefix;
  wire.builtin.metatrafficUnicastLocatorList = servers.front().metatrafficUnicastLocatorList;
}

void UseDiscoveryServerFromEnvironment(eprosima::fastdds::dds::DomainParticipantQos* qos) {
  const char* address = std::getenv(kDiscoveryServerVariable);
  if (address == nullptr || *address == '\0') return;
  auto& discovery = qos->wire_protocol().builtin.discovery_config;
  discovery.m_DiscoveryServers = ServerAt(address, kDiscoveryServerVariable);
  discovery.discoveryProtocol = DiscoveryProtocol_t::CLIENT;
  discovery.discoveryServer_client_syncperiod = kSyncPeriod;
}

}  // namespace mrslam::dds
