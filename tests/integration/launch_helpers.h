#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"
#include "tests/integration/child_process.h"

// Helpers of the tests that run mrslam_launch.
namespace mrslam::testing {

// mrslam_launch on paper_two_robots with 100 particles into `out` on `domain`, then extra.
inline std::vector<std::string> TwoRobotLaunchArgs(const std::string& out, int domain,
                                                   const std::vector<std::string>& extra) {
  std::vector<std::string> argv = {BinPath("mrslam_launch"),
                                   "--scenario",
                                   SourcePath("config/paper_two_robots.yaml"),
                                   "--out",
                                   out,
                                   "--domain",
                                   std::to_string(domain),
                                   "--set",
                                   "filter.particles=100"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

// Waits until the robot's estimate of at least `step` has been published (or the timeout, or
// the launcher ended). True when seen.
inline bool WaitForEstimateStep(int domain, const std::string& robot, std::uint32_t step, ChildProcess& launcher,
                                std::chrono::seconds timeout) {
  dds::Participant participant({domain, "launcher_test", false});
  dds::Reader<msg::EstimatePubSubType> reader(participant, dds::EstimateTopic(robot));
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  msg::Estimate estimate;
  while (std::chrono::steady_clock::now() < deadline) {
    if (reader.Take(&estimate, std::chrono::milliseconds(100)) && estimate.stamp().step() >= step) return true;
    if (launcher.WaitExit(std::chrono::milliseconds(0)).has_value()) return false;
  }
  return false;
}

}  // namespace mrslam::testing
