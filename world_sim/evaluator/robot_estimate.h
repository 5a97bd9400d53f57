#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/se2.h"
#include "world_sim/evaluator/metrics.h"

// One robot's estimate at one step as the evaluator and the viewer take it from the agent's
// message (no filter types, no DDS).
namespace mrslam::evaluator {

// A rendezvous as an agent reports it: T(G_self <- G_peer) at a step.
struct RendezvousRecord {
  std::string peer;
  std::uint32_t step = 0;
  common::Pose2 t_self_peer;
};

// A landmark of a robot's map with its uncertainty and motion, in the robot's frame (what the
// view shows; view.jsonl).
struct MapLandmark {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance_m2 = Eigen::Matrix2d::Identity();  // of the position
  int landmark_id = -1;                                         // reported identity, -1 if unknown
  bool moving = false;
  double heading_rad = 0.0;  // direction of motion
  double v_mps = 0.0;        // speed (0 when the estimate carries none)
};

// One robot's estimate at one step.
struct RobotEstimate {
  std::uint32_t step = 0;
  double time_s = 0.0;
  common::Pose2 pose;  // in the robot's own frame
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  double effective_sample_size = 0.0;
  std::vector<MapPoint> landmarks;           // in the robot's own frame (scored)
  std::vector<MapLandmark> shown_landmarks;  // the same landmarks with covariance and motion
  std::vector<std::string> frames_known;
  // Per other robot whose data reached the agent: the steps 1..n of its run taken in.
  std::map<std::string, std::uint32_t> data_held;
  std::vector<RendezvousRecord> rendezvous;
  // Samples and peer messages the agent has rejected so far (malformed, stale, not for it).
  std::uint32_t rejected_samples = 0;
  double step_cpu_ms = 0.0;           // the agent's CPU time for this step's estimation
  std::uint64_t estimator_bytes = 0;  // what the agent's estimator holds after the step
  // Serialized bytes of the peer messages the agent has sent and taken in so far.
  std::uint64_t peer_bytes_sent = 0, peer_bytes_received = 0;
  // Realtime: peer messages the agent took in after their step was past (applied a step late).
  std::uint32_t peer_messages_late = 0;
  // When the agent wrote the message and the evaluator received it (ns since the Unix epoch;
  // 0 unknown): DeliveryTiming.
  std::int64_t written_ns = 0;
  std::int64_t received_ns = 0;
  // The step's sensor step: received by the agent less written by world_sim, us (0 unknown).
  double data_hop_us = 0.0;
  // Last step: chunks of the agent's final trajectory to come (0: its online path is final).
  std::uint32_t final_trajectory_chunks = 0;
};

}  // namespace mrslam::evaluator
