#include "scripts/launch/domain_picker.h"

#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>

namespace mrslam::launch {

int MetatrafficUnicastPort(int domain) { return 7400 + 250 * domain + 10; }

std::string DiscoveryServerAddress(int domain) { return "127.0.0.1:" + std::to_string(7100 + domain); }

bool DomainLooksFree(int domain) {
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_ANY);
  address.sin_port = htons(static_cast<std::uint16_t>(MetatrafficUnicastPort(domain)));
  const bool free = bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) == 0;
  close(fd);
  return free;
}

DomainReservation::~DomainReservation() { Release(); }

DomainReservation::DomainReservation(DomainReservation&& other) noexcept
    : domain_(std::exchange(other.domain_, -1)), fd_(std::exchange(other.fd_, -1)) {}

DomainReservation& DomainReservation::operator=(DomainReservation&& other) noexcept {
  if (this != &other) {
    Release();
    domain_ = std::exchange(other.domain_, -1);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

void DomainReservation::Release() {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
  domain_ = -1;
}

DomainReservation DomainReservation::TryHold(int domain) {
  const int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return {};
  // Abstract namespace: sun_path starts with a zero byte; the name is the bytes after it.
  const std::string name = "mrslam-dds-domain-" + std::to_string(domain);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path + 1, name.data(), name.size());
  const auto length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 + name.size());
  if (bind(fd, reinterpret_cast<const sockaddr*>(&address), length) != 0) {
    close(fd);
    return {};
  }
  return {domain, fd};
}

DomainReservation PickFreeDomain(pid_t pid) {
  const int count = kLastAutoDomain - kFirstAutoDomain + 1;
  const int start = static_cast<int>(static_cast<unsigned>(pid) % static_cast<unsigned>(count));
  for (int i = 0; i < count; ++i) {
    const int domain = kFirstAutoDomain + (start + i) % count;
    DomainReservation held = DomainReservation::TryHold(domain);
    if (held.domain() >= 0 && DomainLooksFree(domain)) return held;
  }
  return {};
}

}  // namespace mrslam::launch
