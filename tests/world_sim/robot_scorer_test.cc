#include "world_sim/evaluator/robot_scorer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <set>
#include <vector>

#include "common/angles.h"
#include "common/se2.h"

namespace mrslam::evaluator {
namespace {

using common::kPi;
using common::Pose2;

constexpr double kTol = 1e-9;

// The robot's own frame G: at (1, 2) in the world, rotated by +90 degrees.
const Pose2 kFrame{1.0, 2.0, kPi / 2};

common::LidarOptions Lidar(double range_m) {
  common::LidarOptions lidar;
  lidar.max_range_m = range_m;
  return lidar;
}

// Two true landmarks: "0" near the robot's path, "1" far away.
common::GroundTruth Truth() {
  common::GroundTruth truth;
  truth.landmarks = {{"0", Pose2{3.0, 2.0, 0.0}, false}, {"1", Pose2{50.0, 50.0, 0.0}, false}};
  return truth;
}

// A landmark's true position in G, as a map entry.
MapPoint InOwnFrame(const Pose2& world_pose) {
  MapPoint p;
  p.position_m = common::TransformPoint(common::Inverse(kFrame), world_pose.Translation());
  return p;
}

common::Odometry Forward(double v_mps, double dt_s) {
  common::Odometry odometry;
  odometry.segments.push_back({0.0, dt_s, v_mps, 0.0});
  return odometry;
}

TEST(RobotScorerTest, AnExactEstimateScoresZeroErrorsAndAFullMapOfWhatWasInReach) {
  const Pose2 robot_world{1.0, 2.0, kPi / 2};  // at the frame's origin
  RobotScorer scorer(kFrame, Pose2{}, Lidar(5.0));
  const StepScore step =
      scorer.Add(Truth(), robot_world, Pose2{}, std::nullopt, {InOwnFrame(Truth().landmarks[0].pose)}, nullptr);
  EXPECT_NEAR(step.position_err_m, 0.0, kTol);
  EXPECT_NEAR(step.heading_err_rad, 0.0, kTol);
  ASSERT_EQ(step.landmark_errors_m.size(), 1U);
  EXPECT_NEAR(step.landmark_errors_m[0], 0.0, kTol);
  EXPECT_DOUBLE_EQ(step.map_completeness, 1.0);  // landmark 1 was never in reach
  const RobotSummary summary = scorer.Summary();
  EXPECT_EQ(summary.steps_scored, 1U);
  EXPECT_EQ(summary.landmarks_mapped, 1U);
  ASSERT_EQ(scorer.InMap().size(), 1U);
  EXPECT_EQ(scorer.InMap().count(0), 1U);
}

TEST(RobotScorerTest, NeesIsScoredOnlyWithACovariance) {
  const Pose2 robot_world{1.0, 2.0, kPi / 2};
  RobotScorer scorer(kFrame, Pose2{}, Lidar(5.0));
  // Off by 0.1 m in x with a variance of 0.01 m^2: NEES 1 on that step.
  const Eigen::Matrix3d covariance = Eigen::Vector3d(0.01, 0.01, 0.01).asDiagonal();
  EXPECT_NEAR(scorer.Add(Truth(), robot_world, Pose2{0.1, 0.0, 0.0}, covariance, {}, nullptr).nees, 1.0, 1e-9);
  EXPECT_TRUE(std::isnan(scorer.Add(Truth(), robot_world, Pose2{0.3, 0.0, 0.0}, std::nullopt, {}, nullptr).nees));
  const RobotSummary summary = scorer.Summary();
  EXPECT_NEAR(summary.mean_nees, 1.0, 1e-9);  // the step without a covariance is left out
  EXPECT_NEAR(summary.position_rmse_m, std::sqrt((0.01 + 0.09) / 2.0), kTol);
  EXPECT_DOUBLE_EQ(summary.landmark_rmse_m, 0.0);   // an empty map has no landmark error
  EXPECT_DOUBLE_EQ(summary.map_completeness, 0.0);  // landmark 0 was in reach but never mapped
}

TEST(RobotScorerTest, DeadReckoningAdvancesOnlyOnStepsWithOdometry) {
  RobotScorer scorer(kFrame, Pose2{}, Lidar(5.0));
  // The robot truly drives 1 m along its own x axis; its odometry reads 1.5 m.
  const Pose2 moved_world = common::Compose(kFrame, Pose2{1.0, 0.0, 0.0});
  const common::Odometry odometry = Forward(1.5, 1.0);
  scorer.Add(Truth(), kFrame, Pose2{}, std::nullopt, {}, nullptr);
  scorer.Add(Truth(), moved_world, Pose2{1.0, 0.0, 0.0}, std::nullopt, {}, &odometry);
  const RobotSummary summary = scorer.Summary();
  EXPECT_NEAR(summary.dead_reckoning_rmse_m, 0.5, 1e-9);  // one step with odometry, 0.5 m off
  EXPECT_NEAR(summary.position_rmse_m, 0.0, kTol);
}

TEST(RobotScorerTest, ReachFollowsTheLidarsRangeAndFieldOfView) {
  common::LidarOptions lidar = Lidar(5.0);
  lidar.fov_rad = kPi / 2;  // +-45 degrees
  const Pose2 robot{0.0, 0.0, 0.0};
  EXPECT_TRUE(InLidarReach(lidar, robot, Eigen::Vector2d(4.0, 1.0)));
  EXPECT_FALSE(InLidarReach(lidar, robot, Eigen::Vector2d(6.0, 0.0)));  // beyond range
  EXPECT_FALSE(InLidarReach(lidar, robot, Eigen::Vector2d(1.0, 3.0)));  // outside the field of view
}

TEST(RobotScorerTest, LandmarkErrorsSplitByWhatTheMapLandmarkStandsFor) {
  const Pose2 robot_world{1.0, 2.0, kPi / 2};
  RobotScorer scorer(kFrame, Pose2{}, Lidar(100.0));  // both landmarks within reach
  common::GroundTruth truth = Truth();
  truth.landmarks[1].moving = true;
  MapPoint near_static = InOwnFrame(truth.landmarks[0].pose);
  near_static.position_m.x() += 0.3;
  MapPoint near_mover = InOwnFrame(truth.landmarks[1].pose);
  near_mover.position_m.y() += 0.4;
  const MapPoint ghost{Eigen::Vector2d(-30.0, -30.0), -1};  // no true landmark within 3 m
  scorer.Add(truth, robot_world, Pose2{}, std::nullopt, {near_static, near_mover, ghost}, nullptr);
  RobotSummary s = scorer.Summary();
  EXPECT_NEAR(s.static_landmark_rmse_m, std::sqrt((0.09 + 9.0) / 2.0), 1e-9);  // the ghost counts as static
  EXPECT_NEAR(s.moving_landmark_rmse_m, 0.4, 1e-9);
  EXPECT_DOUBLE_EQ(s.moving_completeness, 1.0);
  // The mover leaves the map: the static figures stay, moving completeness drops to 0.
  scorer.Add(truth, robot_world, Pose2{}, std::nullopt, {near_static}, nullptr);
  s = scorer.Summary();
  EXPECT_DOUBLE_EQ(s.moving_completeness, 0.0);
  EXPECT_DOUBLE_EQ(s.map_completeness, 0.5);
  EXPECT_NEAR(s.moving_landmark_rmse_m, 0.4, 1e-9);
}

// Landmark 1 (far away) stands in the map as a peer handed it over, never within the robot's
// reach: the own figure leaves it out, the landmark RMSE counts it.
TEST(RobotScorerTest, TheOwnLandmarkFigureCountsOnlyWhatTheRobotCouldHaveObserved) {
  RobotScorer scorer(kFrame, Pose2{}, Lidar(5.0));
  MapPoint own = InOwnFrame(Truth().landmarks[0].pose);
  own.position_m.x() += 0.2;
  MapPoint handed = InOwnFrame(Truth().landmarks[1].pose);
  handed.position_m.y() += 1.0;
  scorer.Add(Truth(), kFrame, Pose2{}, std::nullopt, {own, handed}, nullptr);
  const RobotSummary s = scorer.Summary();
  EXPECT_NEAR(s.own_landmark_rmse_m, 0.2, kTol);
  EXPECT_NEAR(s.landmark_rmse_m, std::sqrt((0.04 + 1.0) / 2.0), kTol);
}

TEST(RobotScorerTest, AdoptedLandmarkNeesCountsOnlyLandmarksTakenFromOtherRobots) {
  RobotScorer scorer(kFrame, Pose2{}, Lidar(5.0), /*robot_index=*/0);
  MapPoint own = InOwnFrame(Truth().landmarks[0].pose);
  own.position_m.x() += 1.0;  // its own, far off: not counted
  own.covariance_m2 = 0.01 * Eigen::Matrix2d::Identity();
  own.origin_robot = 0;
  MapPoint handed = InOwnFrame(Truth().landmarks[1].pose);
  handed.position_m += Eigen::Vector2d(0.3, 0.4);  // from robot 2, with sd 0.5 m in x and 0.2 m in y
  handed.covariance_m2 = Eigen::Vector2d(0.25, 0.04).asDiagonal();
  handed.origin_robot = 2;
  EXPECT_TRUE(std::isnan(RobotScorer(kFrame, Pose2{}, Lidar(5.0), 0).Summary().adopted_landmark_nees));
  scorer.Add(Truth(), kFrame, Pose2{}, std::nullopt, {own, handed}, nullptr);
  EXPECT_NEAR(scorer.Summary().adopted_landmark_nees, 0.09 / 0.25 + 0.16 / 0.04, kTol);
}

TEST(RobotScorerTest, WithoutMoversMovingFiguresAreNeutral) {
  RobotScorer scorer(kFrame, Pose2{}, Lidar(5.0));
  scorer.Add(Truth(), kFrame, Pose2{}, std::nullopt, {InOwnFrame(Truth().landmarks[0].pose)}, nullptr);
  const RobotSummary s = scorer.Summary();
  EXPECT_DOUBLE_EQ(s.moving_landmark_rmse_m, 0.0);
  EXPECT_DOUBLE_EQ(s.moving_completeness, 1.0);
  EXPECT_NEAR(s.static_landmark_rmse_m, 0.0, kTol);
}

}  // namespace
}  // namespace mrslam::evaluator
