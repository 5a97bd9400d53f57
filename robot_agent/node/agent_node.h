#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "robot_agent/cooperation/sample_intake.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"

namespace mrslam::robot_agent {

// Thrown when the agent cannot go on: the simulator silent past the timeout, DDS refusing.
class AgentError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// How the node runs (the agent itself is described by AgentOptions).
struct AgentNodeOptions {
  int domain = 0;
  bool shared_memory = false;
  double timeout_s = 30.0;  // no new step for this long is an error
  // Before saying "ready", wait until this many readers have matched the estimate topic.
  int estimate_readers = 0;
  bool lockstep = true;
  std::uint32_t horizon_steps = 1000;  // samples and peer messages further ahead are rejected
  // Finish normally even after rejections that make the run's numbers doubtful (malformed,
  // foreign-writer, contested, beyond-horizon); otherwise the agent ends with an AgentError.
  bool allow_rejected = false;
  // DDS-Security on with the identities in this folder (the agent's identity is its robot id).
  std::string security_dir;
  // How many samples of each stream it writes DDS keeps for late readers (0: the profiles').
  int history_steps = 0;
  // With a folder: the agent writes its state there (<robot>.snapshot) every
  // snapshot_every_steps steps and, started again in the same run, restores the one it finds
  // and goes on from the step after it. run_fingerprint names the run a snapshot belongs to.
  std::string snapshot_dir;
  std::uint32_t snapshot_every_steps = 50;
  std::string run_fingerprint;
  // With a folder: after the last step the agent writes the raw measurements it holds there
  // (<robot>.factors, cooperation/held_factors.h).
  std::string factors_dir;
};

// What the agent processed and rejected (each rejection also logged as a warning).
struct AgentCounters {
  int steps_processed = 0;
  cooperation::RejectionCounts rejected;
  // Realtime: peer messages of a step already past, applied at the next step.
  std::uint32_t peer_messages_late = 0;
};

// A robot agent's DDS node: reads only its own robot's sensor topic (lidar, IMU and odometry) and the
// step clock (never the truth), runs the filter on each complete step in order, publishes its
// estimate on mrslam/<robot>/estimate and acknowledges the step on mrslam/<robot>/ack (step 0 =
// ready). Sensor samples are taken only from the simulator (the participant that writes the step
// clock); what is rejected is counted by kind (cooperation::Rejection). With a snapshot folder it
// writes its state atomically every few steps and restores it when started again (docs/faults.md,
// "Agents that come back"); samples of steps the snapshot already holds are then replays, dropped
// without a count. Owns the participant, endpoints, filter.
class AgentNode {
 public:
  AgentNode(const AgentOptions& agent, const AgentNodeOptions& options, std::unique_ptr<filters::SlamFilter> filter);
  ~AgentNode();
  AgentNode(const AgentNode&) = delete;
  AgentNode& operator=(const AgentNode&) = delete;

  // Processes steps until the clock's last step. False if stopped early; throws AgentError.
  bool Run(const std::atomic<bool>& stop);
  const AgentCounters& counters() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mrslam::robot_agent
