#pragma once

#include <Eigen/Core>

#include "common/se2.h"

// The sensors' and the motion's noise models: what the simulator draws from and what the agents'
// filters assume (the scenario's `sensors` and `noise` sections).
namespace mrslam::common {

struct LidarOptions {
  double max_range_m = 6.0;
  double min_range_m = 0.0;
  double fov_rad = 2.0 * kPi;
  double range_noise_sd_m = 0.03;
  double bearing_noise_sd_rad = 0.03;
  bool report_identity = false;
  double robot_detection_range_m = 6.0;
  double detection_probability = 1.0;
};

struct ImuOptions {
  bool enabled = true;
  int readings_per_step = 1;
  double gyro_noise_sd_radps = 0.01;
  double accel_noise_sd_mps2 = 0.05;
};

struct OdometryOptions {
  double v_noise_sd_mps = 0.0;
  double w_noise_sd_radps = 0.0;
};

struct SensorOptions {
  LidarOptions lidar;
  ImuOptions imu;
  OdometryOptions odometry;
};

// Per-step process noise variances over (x, y, heading), applied to the true motion by the
// simulator and assumed by the filters.
struct NoiseOptions {
  Eigen::Vector3d robot_process_var = Eigen::Vector3d::Constant(0.001);
  Eigen::Vector3d landmark_process_var = Eigen::Vector3d::Constant(0.001);
};

}  // namespace mrslam::common
