#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/config/scenario_options.h"
#include "common/rng.h"
#include "common/se2.h"
#include "common/sensor_types.h"
#include "world_sim/core/robot_motion.h"

namespace mrslam::world_sim {

// Something a lidar may see: a landmark (id) or another robot (robot_id), at a true position.
struct LandmarkTarget {
  int id = 0;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
};
struct RobotTarget {
  std::string robot_id;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
};

// What one robot's sensors need to know about step k.
struct SensingInput {
  std::uint32_t step = 0;
  double dt_s = 0.0;
  common::Pose2 pose_before;  // true pose at (k-1)*dt
  common::Pose2 pose_after;   // true pose at k*dt
  VelocityCommand command;    // applied during the step
  std::vector<LandmarkTarget> landmarks;
  std::vector<RobotTarget> other_robots;
};

// One robot's odometry, IMU and lidar. Owns the robot's sensor random stream (derived from
// (seed, "sensors/<id>")) and the IMU's memory of the previous step's true speed.
class RobotSensors {
 public:
  RobotSensors(std::string robot_id, const common::SensorOptions& options, std::uint64_t seed);

  // Senses step k: odometry, then IMU, then lidar, all stamped (robot id, k, k*dt).
  common::SensorStep Sense(const SensingInput& input);

 private:
  common::Odometry SenseOdometry(const SensingInput& input, const common::Stamp& stamp);
  common::ImuSamples SenseImu(const SensingInput& input, const common::Stamp& stamp);
  common::LidarScan SenseLidar(const SensingInput& input, const common::Stamp& stamp);
  // True when a true (range, bearing) lies in [min_range, max_range] and the field of view.
  bool InView(const common::RangeBearing& truth, double min_range_m, double max_range_m) const;
  // The true (range, bearing) plus the lidar's noise.
  common::RangeBearing AddNoise(const common::RangeBearing& truth);

  std::string robot_id_;
  common::SensorOptions options_;
  common::Rng rng_;
  std::optional<double> previous_speed_mps_;  // v_{k-1} of the IMU model
};

}  // namespace mrslam::world_sim
