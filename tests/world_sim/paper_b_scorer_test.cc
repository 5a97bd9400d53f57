#include "world_sim/evaluator/paper_b_scorer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/se2.h"

namespace mrslam::evaluator {
namespace {

using common::Pose2;

constexpr double kTol = 1e-9;

// One robot at the origin of the world, whose frame is the world's; a static landmark "0" at
// (2, 0) and a moving one "1" at (x1, 0); "2" is static, far beyond the lidar's 5 m.
common::GroundTruth Truth(double x1) {
  common::GroundTruth truth;
  truth.robots = {{"r1", Pose2{}, true}};
  truth.landmarks = {
      {"0", Pose2{2.0, 0.0, 0.0}, false}, {"1", Pose2{x1, 0.0, 0.0}, true}, {"2", Pose2{40.0, 0.0, 0.0}, false}};
  return truth;
}

ReportedLandmark At(double x, double y, int id, bool tentative = false, bool moving = false) {
  return {Eigen::Vector2d(x, y), id, tentative, moving};
}

TEST(PaperBScorerTest, LandmarkRmseIsTheMeanOfThePerFrameRmseOverNonEmptyMaps) {
  PaperBScorer scorer({Pose2{}}, 5.0);
  scorer.AddFrame(Truth(3.0), {{Pose2{}, {}}});  // an empty map: no frame RMSE
  // 0.3 m and 0.4 m off: frame RMSE sqrt((0.09 + 0.16) / 2); the tentative one is left out.
  scorer.AddFrame(Truth(3.0), {{Pose2{}, {At(2.3, 0.0, 0), At(3.0, 0.4, 1, false, true), At(9.0, 9.0, -1, true)}}});
  // 0.1 m off: frame RMSE 0.1.
  scorer.AddFrame(Truth(3.5), {{Pose2{}, {At(2.1, 0.0, 0)}}});
  const PaperBScores s = scorer.Finish();
  EXPECT_NEAR(s.landmark_rmse_m, (std::sqrt(0.125) + 0.1) / 2.0, kTol);
  ASSERT_EQ(s.robot_landmark_rmse_m.size(), 1U);
  EXPECT_NEAR(s.robot_rmse_m, 0.0, kTol);
  // Four landmarks reported over the run, one of them held as moving.
  EXPECT_NEAR(s.moving_flag_share, 0.25, kTol);
  EXPECT_NEAR(s.mapped_at_end, 1.0, kTol);
}

TEST(PaperBScorerTest, StaticCompletenessCountsTheStaticLandmarksThatCameInReach) {
  PaperBScorer scorer({Pose2{}}, 5.0);
  scorer.AddFrame(Truth(3.0), {{Pose2{}, {At(3.0, 0.0, 1)}}});
  PaperBScores s = scorer.Finish();
  EXPECT_NEAR(s.static_completeness, 0.0, kTol);  // "0" was in reach but is not mapped
  scorer.AddFrame(Truth(3.0), {{Pose2{}, {At(2.0, 0.0, 0)}}});
  s = scorer.Finish();
  EXPECT_NEAR(s.static_completeness, 1.0, kTol);  // "2" never came in reach
  EXPECT_NEAR(s.static_only_completeness, 1.0, kTol);
}

TEST(PaperBScorerTest, RobotRmseIsInTheRobotsOwnFrame) {
  const Pose2 frame{1.0, -1.0, 0.5};
  PaperBScorer scorer({frame}, 5.0);
  common::GroundTruth truth = Truth(3.0);
  truth.robots[0].pose = common::Compose(frame, Pose2{2.0, 0.0, 0.0});
  scorer.AddFrame(truth, {{Pose2{2.0, 0.6, 0.0}, {}}});
  scorer.AddFrame(truth, {{Pose2{2.0, 0.8, 0.0}, {}}});
  EXPECT_NEAR(scorer.Finish().robot_rmse_m, std::sqrt((0.36 + 0.64) / 2.0), kTol);
  EXPECT_TRUE(std::isnan(scorer.Finish().landmark_rmse_m));  // the map was always empty
}

TEST(MeanOfFiniteTest, LeavesOutNonFiniteValues) {
  EXPECT_NEAR(MeanOfFinite({1.0, std::nan(""), 3.0}), 2.0, kTol);
  EXPECT_TRUE(std::isnan(MeanOfFinite({})));
}

}  // namespace
}  // namespace mrslam::evaluator
