#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/se2.h"
#include "robot_agent/cooperation/factor_exchange.h"
#include "robot_agent/options/agent_options.h"
#include "robot_agent/smoother/joint_graph.h"

// The joint estimate over the raw measurements an agent holds (docs/cooperation.md): the joint
// graph (smoother/joint_graph.h) of its own steps and every other origin's it holds, solved.
namespace mrslam::robot_agent::cooperation {

struct JointEstimate {
  // The own keyframes' steps and poses in the own frame.
  std::vector<std::pair<int, common::Pose2>> path;
  // Per other robot placed: T(G_self <- G_robot) and its covariance.
  struct Frame {
    std::string robot;
    common::Pose2 t_self_robot;
    Eigen::Matrix3d covariance;
  };
  std::vector<Frame> frames;
  std::vector<std::string> not_placed;  // held but linked by no mutual detection
  int readings = 0, outliers = 0;
};

// The joint graph's robots from `logs` (FactorExchange::logs or HeldFactors::logs): `self`'s
// first, then the others in id order (pointing into logs).
std::vector<smoother::JointGraph::RobotLog> RobotLogs(const std::string& self,
                                                      const std::map<std::string, FactorLog>& logs);
// What a solved graph of `robots` gives the agent.
JointEstimate Summarize(const smoother::JointGraph& graph, const std::vector<smoother::JointGraph::RobotLog>& robots);

// Solves the joint graph over `logs`, `self`'s first.
JointEstimate SolveJoint(const AgentOptions& options, const std::string& self,
                         const std::map<std::string, FactorLog>& logs);

}  // namespace mrslam::robot_agent::cooperation
