#include "robot_agent/core/slam_filter.h"

#include <cmath>
#include <cstddef>
#include <limits>

#include "robot_agent/core/ekf_slam.h"
#include "robot_agent/core/fastslam.h"

namespace mrslam::robot_agent {

common::Pose2 InitialPoseInOwnFrame(const common::RobotOptions& robot) {
  return common::Compose(common::Inverse(robot.frame_in_world), robot.initial_pose);
}

int NearestKnownKinematics(const std::vector<common::KnownKinematics>& candidates, double v_mps, double w_radps) {
  int nearest = -1;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const double d = std::abs(candidates[c].v_mps - v_mps) + std::abs(candidates[c].w_radps - w_radps);
    if (d < best) {
      best = d;
      nearest = static_cast<int>(c);
    }
  }
  return nearest;
}

std::unique_ptr<SlamFilter> CreateFilter(const common::ScenarioOptions& options, const std::string& robot_id,
                                         std::uint64_t seed) {
  if (options.filter.type == "fastslam") return CreateFastSlam(options, robot_id, seed);
  if (options.filter.type == "ekf") return CreateEkfSlam(options, robot_id, /*ela=*/false);
  if (options.filter.type == "ekf_ela") return CreateEkfSlam(options, robot_id, /*ela=*/true);
  return nullptr;
}

}  // namespace mrslam::robot_agent
