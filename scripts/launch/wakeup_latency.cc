#include "scripts/launch/wakeup_latency.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>

namespace mrslam::launch {

WakeupLatencyRequest::WakeupLatencyRequest(int max_us, const std::string& device) {
  const int fd = ::open(device.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) {
    error_ = "cannot open " + device + " (" + std::strerror(errno) + ")";
    return;
  }
  const std::int32_t value = max_us;
  if (::write(fd, &value, sizeof(value)) != static_cast<ssize_t>(sizeof(value))) {
    error_ = "cannot write to " + device + " (" + std::strerror(errno) + ")";
    ::close(fd);
    return;
  }
  fd_ = fd;
}

WakeupLatencyRequest::~WakeupLatencyRequest() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace mrslam::launch
