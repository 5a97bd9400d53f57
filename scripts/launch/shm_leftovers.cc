#include "scripts/launch/shm_leftovers.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <regex>
#include <string>
#include <system_error>
#include <vector>

namespace mrslam::launch {
namespace {

namespace fs = std::filesystem;

// True when a living process holds the lock file (Fast DDS keeps an flock on it while the
// segment or port is open); false when it is missing or nobody holds it.
bool Locked(const fs::path& lock_file) {
  const int fd = open(lock_file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool locked = flock(fd, LOCK_EX | LOCK_NB) != 0;
  close(fd);
  return locked;
}

int RemoveAll(const fs::path& dir, const std::vector<std::string>& names) {
  int removed = 0;
  for (const auto& name : names) {
    std::error_code ec;
    if (fs::remove(dir / name, ec)) ++removed;
  }
  return removed;
}

}  // namespace

int RemoveShmLeftovers(int domain, const std::string& dir) {
  const fs::path shm(dir);
  int removed = 0;
  static const std::regex kSegmentLock("fastrtps_[0-9a-z]{16}_el");
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(shm, ec)) {
    const std::string name = entry.path().filename().string();
    if (std::regex_match(name, kSegmentLock) && !Locked(entry.path())) {
      removed += RemoveAll(shm, {name.substr(0, name.size() - 3), name});
    }
  }
  const int first_port = 7400 + 250 * domain;
  for (int port = first_port; port < first_port + 250; ++port) {
    const std::string name = "fastrtps_port" + std::to_string(port);
    const bool any = fs::exists(shm / name) || fs::exists(shm / ("sem." + name + "_mutex"));
    if (!any || Locked(shm / (name + "_el"))) continue;
    removed += RemoveAll(shm, {name, name + "_el", name + "_sl", "sem." + name + "_mutex"});
  }
  return removed;
}

}  // namespace mrslam::launch
