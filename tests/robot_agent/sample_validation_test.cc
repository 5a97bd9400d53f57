// Malformed samples are removed and counted before the filter sees them.
#include "robot_agent/cooperation/sample_validation.h"

#include <gtest/gtest.h>

#include <limits>

namespace mrslam::robot_agent::cooperation {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(SampleValidationTest, EachPartDropsItsMalformedItems) {
  common::SensorStep step;
  step.lidar.landmarks = {{0.0, 2.0, 0.1, -1}, {0.0, kNaN, 0.1, -1}, {0.0, 2.0, kInf, -1}, {0.0, -0.5, 0.0, -1}};
  step.lidar.robots = {{0.0, 3.0, 0.2, "r2"}, {0.0, 3.0, 0.2, ""}};
  step.odometry.segments = {{0.0, 0.1, 1.0, 0.2}, {0.1, 0.0, 1.0, 0.2}, {0.2, 0.1, kNaN, 0.2}};
  step.imu.readings = {{0.0, 0.1, 0.0, 0.0}, {0.0, kInf, 0.0, 0.0}};
  EXPECT_EQ(SanitizeSensorStep(&step), 7);
  ASSERT_EQ(step.lidar.landmarks.size(), 1U);
  EXPECT_EQ(step.lidar.landmarks[0].range_m, 2.0);
  ASSERT_EQ(step.lidar.robots.size(), 1U);
  EXPECT_EQ(step.lidar.robots[0].seen_robot_id, "r2");
  ASSERT_EQ(step.odometry.segments.size(), 1U);
  EXPECT_EQ(step.odometry.segments[0].time_s, 0.0);
  EXPECT_EQ(step.imu.readings.size(), 1U);
}

TEST(SampleValidationTest, StampProblems) {
  EXPECT_EQ(StampProblem({"r1", 5, 3.0}, "r1"), "");
  EXPECT_NE(StampProblem({"r2", 5, 3.0}, "r1").find("robot 'r2'"), std::string::npos);
  EXPECT_NE(StampProblem({"r1", 5, kNaN}, "r1").find("non-finite"), std::string::npos);
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
