#pragma once

#include <string>

#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "robot_agent/options/agent_options.h"

// What of the scenario an agent may know: the projection that keeps the ground truth (true
// poses, frames in the world, the landmarks) out of the agent's options.
namespace mrslam::common {

// A robot's initial pose in its own frame G_i: inverse(frame_in_world) * initial_pose.
Pose2 InitialPoseInOwnFrame(const RobotOptions& robot);

// Robot robot_id's options. Throws ScenarioError when the scenario has no such robot.
robot_agent::AgentOptions AgentOptionsFor(const ScenarioOptions& scenario, const std::string& robot_id);

}  // namespace mrslam::common
