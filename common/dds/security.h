#pragma once

#include <string>

#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

// DDS-Security for one participant (docs/security.md): where a process's files are in a security
// folder made by scripts/security/make_identities.sh, and the participant properties that turn on
// the builtin plugins (PKI-DH authentication, access control by signed permissions, AES-GCM-GMAC).
namespace mrslam::dds {

// The files of one process's identity, as absolute paths.
struct SecurityFiles {
  std::string identity_ca;
  std::string certificate;
  std::string private_key;
  std::string permissions_ca;
  std::string governance;
  std::string permissions;
};

// The files of `identity` (world_sim, evaluator, monitor or a robot id) in `dir`:
// identity_ca.pem, <identity>_cert.pem, <identity>_key.pem, permissions_ca.pem, governance.p7s,
// permissions_<identity>.p7s.
SecurityFiles SecurityFilesFor(const std::string& dir, const std::string& identity);

// Sets the DDS-Security properties on qos from the files, and a denser initial discovery burst:
// a participant's handshakes start only once it is discovered, and their retries back off from
// 500 ms, so a lost first announcement would otherwise cost seconds.
void EnableSecurity(const SecurityFiles& files, eprosima::fastdds::dds::DomainParticipantQos* qos);

}  // namespace mrslam::dds
