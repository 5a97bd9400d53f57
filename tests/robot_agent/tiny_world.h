#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/config/scenario_options.h"
#include "common/rng.h"
#include "common/se2.h"
#include "common/sensor_types.h"

// A minimal world for the filter tests (independent of world_sim): one robot and unicycle
// landmarks stepped with docs/models.md's motion model plus process noise, and a range-bearing lidar
// in random order. Built from the same ScenarioOptions the filter reads, so both agree.
namespace mrslam::robot_agent::testing {

// Owns the true states and one random stream.
class TinyWorld {
 public:
  TinyWorld(const common::ScenarioOptions& options, std::uint64_t seed)
      : options_(options),
        rng_(seed, "tiny_world"),
        imu_rng_(seed, "tiny_world_imu"),
        robot_(options.robots.at(0).initial_pose) {
    for (const auto& l : options.landmarks) landmarks_.push_back(l.pose);
  }

  // Advances one step; returns the robot's sensor samples.
  common::SensorStep Step() {
    const double dt = options_.run.dt_s;
    const auto& control = options_.robots.at(0).control;
    ++step_;
    const common::Pose2 before = robot_;
    robot_ = Noisy(common::UnicycleStep(robot_, control.v_mps, control.w_radps, dt), options_.noise.robot_process_var);
    for (std::size_t i = 0; i < landmarks_.size(); ++i) {
      const auto& m = options_.landmarks[i].motion;
      if (m.model == common::LandmarkMotionModel::kUnicycle) {
        landmarks_[i] =
            Noisy(common::UnicycleStep(landmarks_[i], m.v_mps, m.w_radps, dt), options_.noise.landmark_process_var);
      }
    }
    common::SensorStep s;
    s.lidar.stamp = {options_.robots[0].id, step_, step_ * dt};
    s.odometry.stamp = s.lidar.stamp;
    s.odometry.segments.push_back({(step_ - 1) * dt, dt, control.v_mps, control.w_radps});
    if (options_.sensors.imu.enabled) s.imu = Imu(before, s.lidar.stamp);
    const auto& lidar = options_.sensors.lidar;
    for (std::size_t i = 0; i < landmarks_.size(); ++i) {
      const common::RangeBearing z = common::MeasureRangeBearing(robot_, landmarks_[i].Translation());
      if (z.range_m > lidar.max_range_m) continue;
      common::LandmarkDetection d;
      d.time_s = step_ * dt;
      d.range_m = z.range_m + rng_.Normal(0.0, lidar.range_noise_sd_m);
      d.bearing_rad = common::WrapAngle(z.bearing_rad + rng_.Normal(0.0, lidar.bearing_noise_sd_rad));
      d.landmark_id = lidar.report_identity ? options_.landmarks[i].id : -1;
      s.lidar.landmarks.push_back(d);
    }
    std::shuffle(s.lidar.landmarks.begin(), s.lidar.landmarks.end(), rng_.engine());
    return s;
  }

  // True robot pose (the robot's frame is the world frame here).
  const common::Pose2& robot() const { return robot_; }
  const std::vector<common::Pose2>& landmarks() const { return landmarks_; }

 private:
  // One IMU reading per step from the true motion over the step (the robot starts at rest):
  // gyro_z = w, accel_x = (v - v_previous) / dt, each with its configured noise (own stream).
  common::ImuSamples Imu(const common::Pose2& before, const common::Stamp& stamp) {
    const double dt = options_.run.dt_s;
    const double v = std::hypot(robot_.x - before.x, robot_.y - before.y) / dt;
    const double w = common::WrapAngle(robot_.heading - before.heading) / dt;
    const auto& imu = options_.sensors.imu;
    common::ImuSamples out;
    out.stamp = stamp;
    out.readings.push_back({stamp.time_s, w + imu_rng_.Normal(0.0, imu.gyro_noise_sd_radps),
                            (v - previous_v_) / dt + imu_rng_.Normal(0.0, imu.accel_noise_sd_mps2), 0.0});
    previous_v_ = v;
    return out;
  }

  common::Pose2 Noisy(const common::Pose2& p, const Eigen::Vector3d& var) {
    return {p.x + rng_.Normal(0.0, std::sqrt(var(0))), p.y + rng_.Normal(0.0, std::sqrt(var(1))),
            common::WrapAngle(p.heading + rng_.Normal(0.0, std::sqrt(var(2))))};
  }

  common::ScenarioOptions options_;
  common::Rng rng_;
  common::Rng imu_rng_;
  double previous_v_ = 0.0;
  std::uint32_t step_ = 0;
  common::Pose2 robot_;
  std::vector<common::Pose2> landmarks_;
};

// A scenario with one robot r1 (frame = world) driving a circle, no landmarks yet.
inline common::ScenarioOptions OneRobotScenario(double v_mps, double w_radps, int particles) {
  common::ScenarioOptions o;
  o.name = "tiny";
  o.run.dt_s = 0.5;
  o.run.steps = 50;
  common::RobotOptions r;
  r.id = "r1";
  r.control.v_mps = v_mps;
  r.control.w_radps = w_radps;
  o.robots.push_back(r);
  o.sensors.lidar.max_range_m = 8.0;
  o.sensors.lidar.range_noise_sd_m = 0.05;
  o.sensors.lidar.bearing_noise_sd_rad = 0.02;
  o.noise.robot_process_var = Eigen::Vector3d(0.002, 0.002, 0.0005);
  o.noise.landmark_process_var = Eigen::Vector3d(0.0005, 0.0005, 0.0005);
  o.filter.particles = particles;
  return o;
}

inline void AddLandmark(common::ScenarioOptions* o, int id, const common::Pose2& pose, double v_mps = 0.0,
                        double w_radps = 0.0) {
  common::LandmarkOptions l;
  l.id = id;
  l.pose = pose;
  if (v_mps != 0.0 || w_radps != 0.0) {
    l.motion.model = common::LandmarkMotionModel::kUnicycle;
    l.motion.v_mps = v_mps;
    l.motion.w_radps = w_radps;
  }
  o->landmarks.push_back(l);
}

}  // namespace mrslam::robot_agent::testing
