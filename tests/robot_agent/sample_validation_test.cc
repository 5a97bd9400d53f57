// Malformed samples are removed and counted before the filter sees them.
#include "robot_agent/cooperation/sample_validation.h"

#include <gtest/gtest.h>

#include <limits>

namespace mrslam::robot_agent::cooperation {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(SampleValidationTest, LidarDropsNonFiniteAndNegativeRanges) {
  common::LidarScan scan;
  scan.landmarks = {{0.0, 2.0, 0.1, -1}, {0.0, kNaN, 0.1, -1}, {0.0, 2.0, kInf, -1}, {0.0, -0.5, 0.0, -1}};
  scan.robots = {{0.0, 3.0, 0.2, "r2"}, {0.0, 3.0, 0.2, ""}};
  EXPECT_EQ(SanitizeLidar(&scan), 4);
  ASSERT_EQ(scan.landmarks.size(), 1U);
  EXPECT_EQ(scan.landmarks[0].range_m, 2.0);
  ASSERT_EQ(scan.robots.size(), 1U);
}

TEST(SampleValidationTest, OdometryAndImu) {
  common::Odometry odo;
  odo.segments = {{0.0, 0.1, 1.0, 0.2}, {0.1, 0.0, 1.0, 0.2}, {0.2, 0.1, kNaN, 0.2}};
  EXPECT_EQ(SanitizeOdometry(&odo), 2);
  EXPECT_EQ(odo.segments.size(), 1U);
  common::ImuSamples imu;
  imu.readings = {{0.0, 0.1, 0.0, 0.0}, {0.0, kInf, 0.0, 0.0}};
  EXPECT_EQ(SanitizeImu(&imu), 1);
  EXPECT_EQ(imu.readings.size(), 1U);
}

TEST(SampleValidationTest, StampProblems) {
  EXPECT_EQ(StampProblem({"r1", 5, 3.0}, "r1"), "");
  EXPECT_NE(StampProblem({"r2", 5, 3.0}, "r1").find("robot 'r2'"), std::string::npos);
  EXPECT_NE(StampProblem({"r1", 5, kNaN}, "r1").find("non-finite"), std::string::npos);
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
