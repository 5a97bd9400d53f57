#include "scripts/launch/domain_picker.h"

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>

namespace mrslam::launch {

int MetatrafficUnicastPort(int domain) { return 7400 + 250 * domain + 10; }

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

int PickFreeDomain(pid_t pid) {
  const int count = kLastAutoDomain - kFirstAutoDomain + 1;
  const int start = static_cast<int>(static_cast<unsigned>(pid) % static_cast<unsigned>(count));
  for (int i = 0; i < count; ++i) {
    const int domain = kFirstAutoDomain + (start + i) % count;
    if (DomainLooksFree(domain)) return domain;
  }
  return -1;
}

}  // namespace mrslam::launch
