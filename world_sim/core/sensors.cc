#include "world_sim/core/sensors.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "common/angles.h"

namespace mrslam::world_sim {

RobotSensors::RobotSensors(std::string robot_id, const common::SensorOptions& options, std::uint64_t seed)
    : robot_id_(std::move(robot_id)), options_(options), rng_(seed, "sensors/" + robot_id_) {}

common::SensorStep RobotSensors::Sense(const SensingInput& input) {
  const common::Stamp stamp{robot_id_, input.step, input.step * input.dt_s};
  common::SensorStep out;
  out.odometry = SenseOdometry(input, stamp);
  out.imu = SenseImu(input, stamp);
  out.lidar = SenseLidar(input, stamp);
  return out;
}

common::Odometry RobotSensors::SenseOdometry(const SensingInput& input, const common::Stamp& stamp) {
  // One segment over the step: the command applied plus noise,
  // v = v_cmd + N(0, sd_v^2), w = w_cmd + N(0, sd_w^2).
  common::Odometry odometry;
  odometry.stamp = stamp;
  common::OdometrySegment segment;
  segment.time_s = (input.step - 1.0) * input.dt_s;
  segment.dt_s = input.dt_s;
  segment.v_mps = input.command.v_mps + rng_.Normal(0.0, options_.odometry.v_noise_sd_mps);
  segment.w_radps = input.command.w_radps + rng_.Normal(0.0, options_.odometry.w_noise_sd_radps);
  odometry.segments.push_back(segment);
  return odometry;
}

common::ImuSamples RobotSensors::SenseImu(const SensingInput& input, const common::Stamp& stamp) {
  common::ImuSamples imu;
  imu.stamp = stamp;
  // The true motion over step k (process noise included):
  //   v_k = |p_k - p_{k-1}| / dt,  w_k = wrap(phi_k - phi_{k-1}) / dt,
  //   gyro_z = w_k, accel_x = (v_k - v_{k-1}) / dt (tangential), accel_y = v_k * w_k
  //   (centripetal), with v_0 = 0: the robot stands still at step 0, so step 1's reading carries
  //   its acceleration to the first speed (an accelerometer sees it; a filter integrating
  //   accel_x from rest needs it).
  const double dt_s = input.dt_s;
  const double v_mps =
      std::hypot(input.pose_after.x - input.pose_before.x, input.pose_after.y - input.pose_before.y) / dt_s;
  const double w_radps = common::WrapAngle(input.pose_after.heading - input.pose_before.heading) / dt_s;
  const double previous_v_mps = previous_speed_mps_.value_or(0.0);
  previous_speed_mps_ = v_mps;
  if (!options_.imu.enabled) return imu;

  const int n = options_.imu.readings_per_step;
  const double start_s = (input.step - 1.0) * dt_s;
  for (int i = 0; i < n; ++i) {
    common::ImuReading r;
    r.time_s = start_s + (i + 1) * dt_s / n;
    r.gyro_z_radps = w_radps + rng_.Normal(0.0, options_.imu.gyro_noise_sd_radps);
    r.accel_x_mps2 = (v_mps - previous_v_mps) / dt_s + rng_.Normal(0.0, options_.imu.accel_noise_sd_mps2);
    r.accel_y_mps2 = v_mps * w_radps + rng_.Normal(0.0, options_.imu.accel_noise_sd_mps2);
    imu.readings.push_back(r);
  }
  return imu;
}

bool RobotSensors::InView(const common::RangeBearing& truth, double min_range_m, double max_range_m) const {
  // Seen iff r in [min, max] and |b| <= fov / 2 (true values).
  return truth.range_m >= min_range_m && truth.range_m <= max_range_m &&
         std::abs(truth.bearing_rad) <= 0.5 * options_.lidar.fov_rad;
}

common::RangeBearing RobotSensors::AddNoise(const common::RangeBearing& truth) {
  // z = (r, b) + N(0, diag(sd_r^2, sd_b^2)), range clamped at 0, bearing wrapped.
  common::RangeBearing z;
  z.range_m = std::max(0.0, truth.range_m + rng_.Normal(0.0, options_.lidar.range_noise_sd_m));
  z.bearing_rad = common::WrapAngle(truth.bearing_rad + rng_.Normal(0.0, options_.lidar.bearing_noise_sd_rad));
  return z;
}

common::LidarScan RobotSensors::SenseLidar(const SensingInput& input, const common::Stamp& stamp) {
  const auto& lidar = options_.lidar;
  common::LidarScan scan;
  scan.stamp = stamp;
  for (const auto& target : input.landmarks) {
    // r = |p_L - p_R|, b = wrap(atan2(dy, dx) - phi_R).
    const common::RangeBearing truth = common::MeasureRangeBearing(input.pose_after, target.position_m);
    if (!InView(truth, lidar.min_range_m, lidar.max_range_m)) continue;
    // Missed with probability 1 - p_d (no draw when p_d = 1).
    if (lidar.detection_probability < 1.0 && rng_.Uniform() >= lidar.detection_probability) {
      continue;
    }
    const common::RangeBearing z = AddNoise(truth);
    scan.landmarks.push_back({stamp.time_s, z.range_m, z.bearing_rad, lidar.report_identity ? target.id : -1});
  }
  // The order of the detections carries no identity: Fisher-Yates shuffle.
  for (int i = static_cast<int>(scan.landmarks.size()) - 1; i > 0; --i) {
    std::swap(scan.landmarks[i], scan.landmarks[rng_.UniformInt(0, i)]);
  }
  for (const auto& target : input.other_robots) {
    const common::RangeBearing truth = common::MeasureRangeBearing(input.pose_after, target.position_m);
    if (!InView(truth, 0.0, lidar.robot_detection_range_m)) continue;
    const common::RangeBearing z = AddNoise(truth);
    scan.robots.push_back({stamp.time_s, z.range_m, z.bearing_rad, target.robot_id});
  }
  return scan;
}

}  // namespace mrslam::world_sim
