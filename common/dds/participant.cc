#include "common/dds/participant.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <mutex>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include "common/dds/discovery_server.h"
#include "common/dds/identity_check.h"
#include "common/dds/security.h"

namespace mrslam::dds {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

int ResolveDomain(int scenario_domain, int flag_domain) {
  int domain = flag_domain >= 0 ? flag_domain : scenario_domain;
  if (const char* env = std::getenv("MRSLAM_DOMAIN"); env != nullptr && *env != '\0') {
    char* end = nullptr;
    const long v = std::strtol(env, &end, 10);
    if (end == nullptr || *end != '\0') {
      throw DdsError(std::string("MRSLAM_DOMAIN='") + env + "' is not an integer");
    }
    domain = static_cast<int>(v);
  }
  if (domain < 0 || domain > 232) {
    throw DdsError("DDS domain " + std::to_string(domain) + " is outside 0..232");
  }
  return domain;
}

std::string ProfilesPath() {
  if (const char* env = std::getenv("MRSLAM_DDS_PROFILES"); env != nullptr && *env != '\0') return env;
  return MRSLAM_SOURCE_QOS_PROFILE;
}

namespace {

// Loads the XML profiles once per process (before any participant QoS is read, or the
// profiles are silently ignored).
void LoadProfilesOnce() {
  static std::once_flag once;
  static std::string error;
  std::call_once(once, [] {
    const std::string path = ProfilesPath();
    if (!std::ifstream(path)) {
      error = "DDS profiles file '" + path + "' not found (set MRSLAM_DDS_PROFILES)";
      return;
    }
    if (fdds::DomainParticipantFactory::get_instance()->load_XML_profiles_file(path) != ReturnCode_t::RETCODE_OK) {
      error = "DDS profiles file '" + path + "' could not be loaded";
    }
  });
  if (!error.empty()) throw DdsError(error);
}

// Checks the identity's files and turns DDS-Security on.
void Secure(const ParticipantOptions& options, fdds::DomainParticipantQos* qos) {
  if (options.identity.empty()) throw DdsError("a security folder needs the process identity");
  const SecurityFiles files = SecurityFilesFor(options.security_dir, options.identity);
  CheckSecurityFiles(files, options.identity);
  EnableSecurity(files, qos);
}

}  // namespace

Participant::Participant(const ParticipantOptions& options) : history_steps_(options.history_steps) {
  LoadProfilesOnce();
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  fdds::DomainParticipantQos qos;
  const std::string profile = options.shared_memory ? "mrslam_shm" : "mrslam_udp";
  if (factory->get_participant_qos_from_profile(profile, qos) != ReturnCode_t::RETCODE_OK) {
    throw DdsError("DDS participant profile '" + profile + "' missing from " + ProfilesPath());
  }
  qos.name(options.name);
  if (options.serve_discovery_at.empty()) {
    UseDiscoveryServerFromEnvironment(&qos);
  } else {
    ServeDiscovery(options.serve_discovery_at, &qos);
  }
  if (!options.security_dir.empty()) Secure(options, &qos);
  participant_ = factory->create_participant(options.domain, qos, nullptr, fdds::StatusMask::none());
  if (participant_ == nullptr) {
    throw DdsError("cannot create a DDS participant on domain " + std::to_string(options.domain) +
                   (options.security_dir.empty() ? "" : " with the security files of '" + options.identity + "'"));
  }
  publisher_ = participant_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  subscriber_ = participant_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  if (publisher_ == nullptr || subscriber_ == nullptr) {
    throw DdsError("cannot create a DDS publisher/subscriber");
  }
}

Participant::~Participant() {
  if (participant_ == nullptr) return;
  participant_->delete_contained_entities();
  fdds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

std::string Participant::RegisterType(const fdds::TypeSupport& type) {
  std::string type_name = type.get_type_name();
  if (participant_->find_type(type_name).empty() && type.register_type(participant_) != ReturnCode_t::RETCODE_OK) {
    throw DdsError("cannot register DDS type '" + type_name + "'");
  }
  return type_name;
}

fdds::Topic* Participant::GetTopic(const std::string& name, const std::string& type_name) {
  if (auto it = topics_.find(name); it != topics_.end()) return it->second;
  auto* topic = participant_->create_topic(name, type_name, fdds::TOPIC_QOS_DEFAULT);
  if (topic == nullptr) throw DdsError("cannot create DDS topic '" + name + "'");
  topics_[name] = topic;
  return topic;
}

namespace {

// A history of depth samples (KEEP_LAST), its resource limits to match.
template <typename Qos>
void SetDepth(int depth, Qos* qos) {
  qos->history().depth = depth;
  qos->resource_limits().max_samples = depth;
  qos->resource_limits().max_samples_per_instance = depth;
  qos->resource_limits().allocated_samples = std::min(qos->resource_limits().allocated_samples, depth);
}

}  // namespace

fdds::DataWriterQos Participant::WriterQos(History history, Acknowledgment acknowledgment) const {
  fdds::DataWriterQos qos;
  if (publisher_->get_datawriter_qos_from_profile(kWriterProfile, qos) != ReturnCode_t::RETCODE_OK) {
    throw DdsError(std::string("DDS writer profile '") + kWriterProfile + "' missing from " + ProfilesPath());
  }
  if (history == History::kRecent && history_steps_ > 0) SetDepth(history_steps_, &qos);
  if (acknowledgment == Acknowledgment::kPerSecond) {
    qos.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(1, 0);
    qos.reliable_writer_qos().disable_heartbeat_piggyback = true;
  }
  return qos;
}

fdds::DataReaderQos Participant::ReaderQos(History history) const {
  fdds::DataReaderQos qos;
  if (subscriber_->get_datareader_qos_from_profile(kReaderProfile, qos) != ReturnCode_t::RETCODE_OK) {
    throw DdsError(std::string("DDS reader profile '") + kReaderProfile + "' missing from " + ProfilesPath());
  }
  if (history == History::kRecent && history_steps_ > 0) SetDepth(history_steps_, &qos);
  return qos;
}

std::string SensorTopic(const std::string& robot_id) { return "mrslam/" + robot_id + "/sensors"; }
std::string EstimateTopic(const std::string& robot_id) { return "mrslam/" + robot_id + "/estimate"; }
std::string FinalTrajectoryTopic(const std::string& robot_id) { return "mrslam/" + robot_id + "/final_trajectory"; }
std::string AckTopic(const std::string& robot_id) { return "mrslam/" + robot_id + "/ack"; }
std::string PeerTopic(const std::string& recipient_id, const std::string& sender_id, const std::string& kind) {
  return "mrslam/peer/" + recipient_id + "/from/" + sender_id + "/" + kind;
}

}  // namespace mrslam::dds
