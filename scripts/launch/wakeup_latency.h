#pragma once

#include <string>

// A request to the kernel that the CPUs wake from idle within a bound (Linux PM QoS,
// /dev/cpu_dma_latency): while it is held, the idle loop polls instead of halting the CPU, so a
// process woken by a DDS sample runs sooner, without waiting for the CPU (or, in a virtual
// machine, the host) to wake it from a halt. The cost is that idle CPUs stay busy polling for as
// long as the request is held. The request lasts while the file stays open.
namespace mrslam::launch {

class WakeupLatencyRequest {
 public:
  // Opens `device` and writes the bound in microseconds (a 32-bit integer, as the kernel reads
  // it). held() says whether that worked; error() says why not (one line, naming the file).
  explicit WakeupLatencyRequest(int max_us, const std::string& device = "/dev/cpu_dma_latency");
  ~WakeupLatencyRequest();
  WakeupLatencyRequest(const WakeupLatencyRequest&) = delete;
  WakeupLatencyRequest& operator=(const WakeupLatencyRequest&) = delete;

  bool held() const { return fd_ >= 0; }
  const std::string& error() const { return error_; }

 private:
  int fd_ = -1;
  std::string error_;
};

}  // namespace mrslam::launch
