#include "scripts/batch/oracle_reference.h"

#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "world_sim/core/world.h"

namespace mrslam::batch {

std::map<int, BatchSmoother::Kinematics> OracleKinematics(const common::ScenarioOptions& scenario) {
  if (scenario.landmark_field.enabled) {
    throw std::invalid_argument("the reference knows listed landmarks only, not a landmark_field");
  }
  std::map<int, BatchSmoother::Kinematics> kinematics;
  for (const auto& l : scenario.landmarks) {
    BatchSmoother::Kinematics k;
    if (l.motion.model == common::LandmarkMotionModel::kUnicycle) {
      k = {false, l.motion.v_mps, l.motion.w_radps};
    } else if (l.motion.model != common::LandmarkMotionModel::kStatic) {
      throw std::invalid_argument("the reference knows static and unicycle landmarks only (landmark " +
                                  std::to_string(l.id) + ")");
    }
    kinematics[l.id] = k;
  }
  return kinematics;
}

std::vector<BatchSmoother::RobotStart> OracleStarts(const common::ScenarioOptions& scenario,
                                                    const std::vector<int>& robot_indices,
                                                    const std::vector<common::Pose2>& first_pose_guesses) {
  if (robot_indices.empty() || first_pose_guesses.size() + 1 != robot_indices.size()) {
    throw std::invalid_argument("the reference needs one first-pose guess per robot after the first");
  }
  std::vector<BatchSmoother::RobotStart> robots;
  for (std::size_t r = 0; r < robot_indices.size(); ++r) {
    const common::RobotOptions& robot = scenario.robots.at(robot_indices[r]);
    robots.push_back({robot.id, r == 0 ? common::InitialPoseInOwnFrame(robot) : first_pose_guesses[r - 1]});
  }
  return robots;
}

common::Pose2 FirstPoseGuess(const common::ScenarioOptions& scenario,
                             const std::vector<std::pair<std::string, common::Pose2>>& frames, int i, int j) {
  const common::Pose2 true_ij = common::Between(frames.at(i).second, frames.at(j).second);
  return common::Compose(common::Compose(true_ij, common::InitialPoseInOwnFrame(scenario.robots.at(j))),
                         {0.3, 0.3, common::kPi / 36});
}

BatchSmoother OracleSmoother(const common::ScenarioOptions& scenario, const std::vector<int>& robot_indices,
                             const std::vector<common::Pose2>& first_pose_guesses, int robot_detections_from_step) {
  auto starts = OracleStarts(scenario, robot_indices, first_pose_guesses);
  auto kinematics = OracleKinematics(scenario);
  return BatchSmoother(common::AgentOptionsFor(scenario, starts.front().id), starts, std::move(kinematics),
                       robot_detections_from_step,
                       scenario.replay.enabled ? BatchSmoother::Unlisted::kStatic : BatchSmoother::Unlisted::kLeftOut);
}

std::optional<std::map<int, BatchSmoother::Kinematics>> FieldStatics(const common::ScenarioOptions& scenario) {
  if (!scenario.landmark_field.enabled) return std::nullopt;
  std::map<int, BatchSmoother::Kinematics> statics;
  for (const auto& l : world_sim::ExpandLandmarks(scenario)) {
    if (l.motion.model == common::LandmarkMotionModel::kStatic) statics[l.id] = {};
  }
  return statics;
}

std::unique_ptr<BatchSmoother> MakeOracleReference(
    const common::ScenarioOptions& scenario,
    const std::optional<std::map<int, BatchSmoother::Kinematics>>& field_statics, const std::vector<int>& robot_indices,
    const std::vector<common::Pose2>& first_pose_guesses, int robot_detections_from_step) {
  if (!field_statics) {
    return std::make_unique<BatchSmoother>(
        OracleSmoother(scenario, robot_indices, first_pose_guesses, robot_detections_from_step));
  }
  return std::make_unique<BatchSmoother>(
      common::AgentOptionsFor(scenario, scenario.robots.at(robot_indices.front()).id),
      OracleStarts(scenario, robot_indices, first_pose_guesses), *field_statics, robot_detections_from_step);
}

}  // namespace mrslam::batch
