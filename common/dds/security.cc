#include "common/dds/security.h"

#include <filesystem>

namespace mrslam::dds {

namespace {
constexpr int kInitialAnnouncements = 20;
constexpr int kInitialAnnouncementPeriodNs = 50'000'000;

std::string FileUri(const std::string& path) { return "file://" + path; }
}  // namespace

SecurityFiles SecurityFilesFor(const std::string& dir, const std::string& identity) {
  const std::filesystem::path base = std::filesystem::absolute(dir).lexically_normal();
  const auto in_dir = [&](const std::string& name) { return (base / name).string(); };
  return {in_dir("identity_ca.pem"),    in_dir(identity + "_cert.pem"), in_dir(identity + "_key.pem"),
          in_dir("permissions_ca.pem"), in_dir("governance.p7s"),       in_dir("permissions_" + identity + ".p7s")};
}

void EnableSecurity(const SecurityFiles& files, eprosima::fastdds::dds::DomainParticipantQos* qos) {
  auto& properties = qos->properties().properties();
  const auto set = [&](const std::string& name, const std::string& value) { properties.emplace_back(name, value); };
  const std::string auth = "dds.sec.auth.builtin.PKI-DH.";
  const std::string access = "dds.sec.access.builtin.Access-Permissions.";
  set("dds.sec.auth.plugin", "builtin.PKI-DH");
  set(auth + "identity_ca", FileUri(files.identity_ca));
  set(auth + "identity_certificate", FileUri(files.certificate));
  set(auth + "private_key", FileUri(files.private_key));
  set("dds.sec.access.plugin", "builtin.Access-Permissions");
  set(access + "permissions_ca", FileUri(files.permissions_ca));
  set(access + "governance", FileUri(files.governance));
  set(access + "permissions", FileUri(files.permissions));
  set("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
  auto& announcements = qos->wire_protocol().builtin.discovery_config.initial_announcements;
  announcements.count = kInitialAnnouncements;
  announcements.period = eprosima::fastrtps::Duration_t(0, kInitialAnnouncementPeriodNs);
}

}  // namespace mrslam::dds
