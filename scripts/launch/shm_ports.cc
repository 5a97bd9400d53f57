#include "scripts/launch/shm_ports.h"

#include <cctype>
#include <filesystem>
#include <system_error>

namespace mrslam::launch {

namespace {
constexpr int kPortBase = 7400;
constexpr int kDomainGain = 250;
constexpr char kPortPrefix[] = "fastrtps_port";
constexpr char kSemaphorePrefix[] = "sem.fastrtps_port";
constexpr char kSemaphoreSuffix[] = "_mutex";

// The decimal number that is all of text, or -1.
int WholeNumber(const std::string& text) {
  if (text.empty() || text.size() > 6) return -1;
  for (const char c : text) {
    if (std::isdigit(static_cast<unsigned char>(c)) == 0) return -1;
  }
  return std::stoi(text);
}

bool StartsWith(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }
}  // namespace

DomainPorts PortsOfDomain(int domain) {
  const int first = kPortBase + kDomainGain * domain;
  return {first, first + kDomainGain - 1};
}

int PortOfShmFile(const std::string& name) {
  if (StartsWith(name, kSemaphorePrefix)) {
    const std::string rest = name.substr(sizeof(kSemaphorePrefix) - 1);
    const std::string suffix = kSemaphoreSuffix;
    if (rest.size() <= suffix.size() || rest.compare(rest.size() - suffix.size(), suffix.size(), suffix) != 0)
      return -1;
    return WholeNumber(rest.substr(0, rest.size() - suffix.size()));
  }
  if (StartsWith(name, kPortPrefix)) return WholeNumber(name.substr(sizeof(kPortPrefix) - 1));
  return -1;
}

int RemoveShmPortFiles(int domain, const std::string& shm_dir) {
  const DomainPorts ports = PortsOfDomain(domain);
  std::error_code error;
  int removed = 0;
  for (const auto& entry : std::filesystem::directory_iterator(shm_dir, error)) {
    const int port = PortOfShmFile(entry.path().filename().string());
    if (port < ports.first || port > ports.last) continue;
    if (std::filesystem::remove(entry.path(), error)) ++removed;
  }
  return removed;
}

}  // namespace mrslam::launch
