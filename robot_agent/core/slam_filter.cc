#include "robot_agent/core/slam_filter.h"

#include "robot_agent/core/fastslam.h"

namespace mrslam::robot_agent {

common::Pose2 InitialPoseInOwnFrame(const common::RobotOptions& robot) {
  return common::Compose(common::Inverse(robot.frame_in_world), robot.initial_pose);
}

std::unique_ptr<SlamFilter> CreateFilter(const common::ScenarioOptions& options,
                                         const std::string& robot_id, std::uint64_t seed) {
  if (options.filter.type == "fastslam") return CreateFastSlam(options, robot_id, seed);
  return nullptr;  // ekf and ekf_ela: not yet implemented
}

}  // namespace mrslam::robot_agent
