#include "world_sim/core/world.h"

#include <string>

namespace mrslam::world_sim {

World::World(const common::ScenarioOptions& options) : options_(options) {
  robots_.reserve(options_.robots.size());
  for (const auto& r : options_.robots) {
    robots_.push_back({r, r.initial_pose, common::Rng(options_.seed, "world/" + r.id),
                       RobotSensors(r.id, options_.sensors, options_.seed)});
  }
  for (const auto& l : ExpandLandmarks(options_)) landmarks_.emplace_back(l, options_.seed);
}

double World::time_s() const { return step_ * options_.run.dt_s; }

std::vector<common::SensorStep> World::Step() {
  ++step_;
  const double dt_s = options_.run.dt_s;
  // The step runs from t0 = (k-1) dt to k dt; controls are read at t0.
  const double t0_s = (step_ - 1.0) * dt_s;

  std::vector<common::Pose2> poses_before;
  std::vector<VelocityCommand> commands;
  poses_before.reserve(robots_.size());
  commands.reserve(robots_.size());
  for (auto& robot : robots_) {
    const VelocityCommand command = CommandAt(robot.options.control, t0_s);
    poses_before.push_back(robot.pose);
    commands.push_back(command);
    robot.pose = StepRobot(robot.pose, command, dt_s, options_.noise.robot_process_var, robot.process_rng);
    for (const common::SlipOptions& slip : robot.options.slips) {
      if (static_cast<std::uint32_t>(slip.step) == step_) robot.pose = common::Compose(robot.pose, slip.displacement);
    }
  }
  for (auto& landmark : landmarks_) landmark.Step(dt_s, options_.noise.landmark_process_var);

  // Everyone senses the new state.
  std::vector<LandmarkTarget> landmark_targets;
  landmark_targets.reserve(landmarks_.size());
  for (const auto& landmark : landmarks_) {
    landmark_targets.push_back({landmark.id(), landmark.pose().Translation()});
  }
  std::vector<common::SensorStep> out;
  out.reserve(robots_.size());
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    SensingInput input;
    input.step = step_;
    input.dt_s = dt_s;
    input.pose_before = poses_before[i];
    input.pose_after = robots_[i].pose;
    input.command = commands[i];
    input.landmarks = landmark_targets;
    for (std::size_t j = 0; j < robots_.size(); ++j) {
      if (j == i) continue;
      input.other_robots.push_back({robots_[j].options.id, robots_[j].pose.Translation()});
    }
    out.push_back(robots_[i].sensors.Sense(input));
  }
  return out;
}

common::GroundTruth World::Truth() const {
  common::GroundTruth truth;
  truth.stamp = {"world", step_, time_s()};
  for (const auto& robot : robots_) {
    truth.robots.push_back({robot.options.id, robot.pose, true});
    truth.frames.emplace_back(robot.options.id, robot.options.frame_in_world);
  }
  for (const auto& landmark : landmarks_) {
    truth.landmarks.push_back({std::to_string(landmark.id()), landmark.pose(), landmark.moving()});
  }
  return truth;
}

}  // namespace mrslam::world_sim
