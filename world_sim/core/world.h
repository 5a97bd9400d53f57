#pragma once

#include <cstdint>
#include <vector>

#include "common/se2.h"

#include "common/config/scenario_options.h"
#include "common/rng.h"
#include "common/sensor_types.h"
#include "world_sim/core/landmark_motion.h"
#include "world_sim/core/robot_motion.h"
#include "world_sim/core/sensors.h"
#include "world_sim/core/step_source.h"

namespace mrslam::world_sim {

// The landmark list a scenario describes: its explicit landmarks followed by the generated
// field (jittered grid; a seeded share of them move in a random cardinal direction).
std::vector<common::LandmarkOptions> ExpandLandmarks(const common::ScenarioOptions& options);

// The simulated 2-D world: differential-drive robots, landmarks with their motion models, and
// each robot's sensors. Owns the true state and one seeded random stream per entity, so that a
// scenario and a seed fix every sample. Pure: no DDS, no wall clock.
//
// Step k (k = 1..steps) moves every robot and landmark from time (k-1)*dt to k*dt with the
// unicycle model of docs/models.md plus process noise, then senses: odometry carries the command
// applied during the step (plus odometry noise); the IMU the true rotation rate and body-frame
// acceleration over the step (plus noise); the lidar every landmark and robot in range and
// field of view at the new pose, in random order.
class World : public StepSource {
 public:
  explicit World(const common::ScenarioOptions& options);

  // Advances one step and returns each robot's samples, in scenario order.
  std::vector<common::SensorStep> Step() override;

  std::uint32_t step() const override { return step_; }
  double time_s() const override;
  // The truth now (world frame), with every robot's frame.
  common::GroundTruth Truth() const override;

 private:
  // One robot: its options, true pose, process-noise stream (seed, "world/<id>") and sensors.
  struct SimRobot {
    common::RobotOptions options;
    common::Pose2 pose;
    common::Rng process_rng;
    RobotSensors sensors;
  };

  common::ScenarioOptions options_;
  std::uint32_t step_ = 0;
  std::vector<SimRobot> robots_;        // scenario order
  std::vector<SimLandmark> landmarks_;  // ExpandLandmarks order
};

}  // namespace mrslam::world_sim
