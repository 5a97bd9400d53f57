#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/se2.h"

// Plain sensor, truth and estimate structs shared by the pure cores. The DDS nodes convert
// messages to and from these at the edge.
namespace mrslam::common {

// The DDS participant a sample came from (its writer's GUID prefix).
using WriterId = std::array<std::uint8_t, 12>;

struct Stamp {
  std::string robot_id;
  std::uint32_t step = 0;
  double time_s = 0.0;
};

struct LandmarkDetection {
  double time_s = 0.0;
  double range_m = 0.0;
  double bearing_rad = 0.0;
  int landmark_id = -1;  // -1: identity not reported
};

struct RobotDetection {
  double time_s = 0.0;
  double range_m = 0.0;
  double bearing_rad = 0.0;
  std::string seen_robot_id;
};

struct LidarScan {
  Stamp stamp;
  std::vector<LandmarkDetection> landmarks;
  std::vector<RobotDetection> robots;
};

struct ImuReading {
  double time_s = 0.0;
  double gyro_z_radps = 0.0;
  double accel_x_mps2 = 0.0;
  double accel_y_mps2 = 0.0;
};

struct ImuSamples {
  Stamp stamp;
  std::vector<ImuReading> readings;
};

struct OdometrySegment {
  double time_s = 0.0;  // start of the segment
  double dt_s = 0.0;
  double v_mps = 0.0;
  double w_radps = 0.0;
};

struct Odometry {
  Stamp stamp;
  std::vector<OdometrySegment> segments;
};

// Everything one robot senses in one step.
struct SensorStep {
  LidarScan lidar;
  ImuSamples imu;
  Odometry odometry;
};

struct EntityTruth {
  std::string id;
  Pose2 pose;  // world frame
  bool moving = false;
};

struct GroundTruth {
  Stamp stamp;
  std::vector<EntityTruth> robots;
  std::vector<EntityTruth> landmarks;
  std::vector<std::pair<std::string, Pose2>> frames;  // robot id -> pose of G_i in W
};

}  // namespace mrslam::common
