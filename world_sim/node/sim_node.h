#pragma once

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/config/scenario_options.h"

namespace mrslam::world_sim {

// Thrown when a run cannot complete: an agent silent past the timeout, DDS refusing a sample.
class SimError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SimNodeOptions {
  int domain = 0;
  bool shared_memory = false;
  // Agents that take part in the lockstep barrier (default: every robot of the scenario).
  std::vector<std::string> agents;
  // How long to wait at the end for readers (the evaluator) to acknowledge every sample.
  double drain_timeout_s = 10.0;
  // Before step 1, wait until this many readers (the evaluator) have matched the truth topic.
  int truth_readers = 0;
  // DDS-Security on with the identities in this folder (identity "world_sim"); empty: off.
  std::string security_dir;
};

// The simulator's DDS node: steps the pure World and publishes, per robot, lidar, IMU and
// odometry on its own topics, the truth on mrslam/world/truth and the step clock on
// mrslam/world/clock. In lockstep it waits for every agent's acknowledgement of step k before
// step k+1 and forwards the agents' peer-message counts in the next clock message; in realtime
// it follows the wall clock times the realtime factor. Owns the participant and endpoints.
class SimNode {
 public:
  SimNode(const common::ScenarioOptions& scenario, const SimNodeOptions& options);
  ~SimNode();
  SimNode(const SimNode&) = delete;
  SimNode& operator=(const SimNode&) = delete;

  // Runs the scenario to its last step. Returns false if stopped early by `stop`; throws
  // SimError when an agent stays silent past run.ack_timeout_s.
  bool Run(const std::atomic<bool>& stop);

 private:
  struct Impl;
  Impl* impl_;
};

}  // namespace mrslam::world_sim
