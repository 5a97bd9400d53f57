#include "common/config/agent_options_projection.h"

namespace mrslam::common {

Pose2 InitialPoseInOwnFrame(const RobotOptions& robot) {
  return Compose(Inverse(robot.frame_in_world), robot.initial_pose);
}

robot_agent::AgentOptions AgentOptionsFor(const ScenarioOptions& scenario, const std::string& robot_id) {
  const int index = scenario.RobotIndex(robot_id);
  if (index < 0) {
    throw ScenarioError("unknown robot id '" + robot_id + "' (not in scenario '" + scenario.name + "')");
  }
  robot_agent::AgentOptions agent;
  agent.robot_id = robot_id;
  for (const auto& robot : scenario.robots) agent.team.push_back(robot.id);
  agent.initial_pose = InitialPoseInOwnFrame(scenario.robots[index]);
  agent.dt_s = scenario.run.dt_s;
  agent.sensors = scenario.sensors;
  agent.noise = scenario.noise;
  agent.filter = scenario.filter;
  agent.rendezvous = scenario.rendezvous;
  agent.cooperation = scenario.cooperation;
  return agent;
}

}  // namespace mrslam::common
