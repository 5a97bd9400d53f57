// Round trips between the plain structs of the cores and the DDS messages.
#include "common/dds/msg_conversion.h"

#include <gtest/gtest.h>

#include "common/rng.h"

namespace mrslam::dds {
namespace {

TEST(MsgConversionTest, SensorStepRoundTrip) {
  common::Rng rng(7);
  for (int trial = 0; trial < 100; ++trial) {
    const common::Stamp stamp{"r" + std::to_string(trial), static_cast<std::uint32_t>(trial), 0.1 * trial};
    common::SensorStep step;
    step.lidar.stamp = stamp;
    step.imu.stamp = stamp;
    step.odometry.stamp = stamp;
    for (int i = 0; i < trial % 7; ++i) {
      step.lidar.landmarks.push_back(
          {rng.Uniform(0, 9), rng.Uniform(0, 8), rng.Uniform(-3, 3), rng.UniformInt(-1, 20)});
    }
    step.lidar.robots.push_back({rng.Uniform(), rng.Uniform(0, 6), rng.Uniform(-3, 3), "r9"});
    step.imu.readings.push_back({0.5, rng.Normal(), rng.Normal(), rng.Normal()});
    step.odometry.segments = {{0.0, 0.05, rng.Normal(), rng.Normal()}, {0.05, 0.05, 1.0, -0.2}};
    const auto back = FromMsg(ToMsg(step));
    for (const common::Stamp* s : {&back.lidar.stamp, &back.imu.stamp, &back.odometry.stamp}) {
      EXPECT_EQ(s->robot_id, stamp.robot_id);
      EXPECT_EQ(s->step, stamp.step);
      EXPECT_EQ(s->time_s, stamp.time_s);
    }
    const auto& scan = step.lidar;
    ASSERT_EQ(back.lidar.landmarks.size(), scan.landmarks.size());
    for (std::size_t i = 0; i < scan.landmarks.size(); ++i) {
      EXPECT_EQ(back.lidar.landmarks[i].range_m, scan.landmarks[i].range_m);
      EXPECT_EQ(back.lidar.landmarks[i].bearing_rad, scan.landmarks[i].bearing_rad);
      EXPECT_EQ(back.lidar.landmarks[i].landmark_id, scan.landmarks[i].landmark_id);
      EXPECT_EQ(back.lidar.landmarks[i].time_s, scan.landmarks[i].time_s);
    }
    ASSERT_EQ(back.lidar.robots.size(), 1U);
    EXPECT_EQ(back.lidar.robots[0].seen_robot_id, "r9");
    EXPECT_EQ(back.lidar.robots[0].range_m, scan.robots[0].range_m);

    ASSERT_EQ(back.imu.readings.size(), 1U);
    EXPECT_EQ(back.imu.readings[0].gyro_z_radps, step.imu.readings[0].gyro_z_radps);
    EXPECT_EQ(back.imu.readings[0].accel_x_mps2, step.imu.readings[0].accel_x_mps2);
    EXPECT_EQ(back.imu.readings[0].accel_y_mps2, step.imu.readings[0].accel_y_mps2);

    const auto& odo = step.odometry;
    ASSERT_EQ(back.odometry.segments.size(), 2U);
    for (std::size_t i = 0; i < 2; ++i) {
      EXPECT_EQ(back.odometry.segments[i].v_mps, odo.segments[i].v_mps);
      EXPECT_EQ(back.odometry.segments[i].w_radps, odo.segments[i].w_radps);
      EXPECT_EQ(back.odometry.segments[i].dt_s, odo.segments[i].dt_s);
      EXPECT_EQ(back.odometry.segments[i].time_s, odo.segments[i].time_s);
    }
  }
}

TEST(MsgConversionTest, GroundTruthAndCovarianceRoundTrip) {
  common::GroundTruth truth;
  truth.stamp = {"world", 3, 1.95};
  truth.robots.push_back({"r1", {1.0, -2.0, 0.5}, true});
  truth.landmarks.push_back({"7", {3.0, 4.0, -1.0}, false});
  truth.frames.emplace_back("r1", common::Pose2{0.347, 2.209, -0.6194});
  const auto back = FromMsg(ToMsg(truth));
  ASSERT_EQ(back.robots.size(), 1U);
  EXPECT_EQ(back.robots[0].id, "r1");
  EXPECT_EQ(back.robots[0].pose.heading, 0.5);
  ASSERT_EQ(back.landmarks.size(), 1U);
  EXPECT_EQ(back.landmarks[0].id, "7");
  EXPECT_FALSE(back.landmarks[0].moving);
  ASSERT_EQ(back.frames.size(), 1U);
  EXPECT_EQ(back.frames[0].second.y, 2.209);

  Eigen::Matrix3d cov;
  cov << 1, 2, 3, 4, 5, 6, 7, 8, 9;
  EXPECT_EQ(CovarianceFromMsg(CovarianceToMsg(cov)), cov);
  EXPECT_EQ(CovarianceToMsg(cov)[1], 2.0);  // row-major
}

}  // namespace
}  // namespace mrslam::dds
