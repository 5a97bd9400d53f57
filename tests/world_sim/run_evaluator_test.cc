#include "world_sim/evaluator/run_evaluator.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "common/angles.h"

namespace mrslam::evaluator {
namespace {

// Two robots 10 m apart, each with one landmark 1 m ahead of it and a 3 m lidar: r1 reaches
// landmark 1 only, r2 landmark 2 only. Each maps its own landmark.
class RunEvaluatorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    scenario_.name = "run_evaluator_test";
    scenario_.run.steps = 1;
    scenario_.sensors.lidar.max_range_m = 3.0;
    scenario_.sensors.lidar.fov_rad = 2.0 * common::kPi;
    for (const auto& [id, frame] : {std::pair<std::string, common::Pose2>{"r1", {0.0, 0.0, 0.0}},
                                    std::pair<std::string, common::Pose2>{"r2", {10.0, 0.0, 0.0}}}) {
      common::RobotOptions r;
      r.id = id;
      r.frame_in_world = frame;
      scenario_.robots.push_back(r);
    }
    out_dir_ = (std::filesystem::temp_directory_path() / ("mrslam-evaluator-" + std::to_string(getpid()))).string();
  }
  void TearDown() override { std::filesystem::remove_all(out_dir_); }

  // Scores the run in which r1 knows the frames in r1_frames_known.
  nlohmann::json Score(const std::vector<std::string>& r1_frames_known) const {
    RunEvaluator evaluator(scenario_);
    for (std::uint32_t step = 0; step <= 1; ++step) {
      common::GroundTruth truth;
      truth.stamp.step = step;
      truth.robots = {{"r1", {0.0, 0.0, 0.0}, false}, {"r2", {10.0, 0.0, 0.0}, false}};
      truth.landmarks = {{"1", {1.0, 0.0, 0.0}, false}, {"2", {11.0, 0.0, 0.0}, false}};
      truth.frames = {{"r1", {0.0, 0.0, 0.0}}, {"r2", {10.0, 0.0, 0.0}}};
      evaluator.AddTruth(truth);
      RobotEstimate r1, r2;
      r1.step = r2.step = step;
      r1.landmarks = {{Eigen::Vector2d(1.0, 0.0), 1}};
      r2.landmarks = {{Eigen::Vector2d(1.0, 0.0), 2}};  // in r2's own frame
      r1.frames_known = r1_frames_known;
      r1.rejected_samples = 2 * step;     // the agent's running count
      r1.step_cpu_ms = 1.0 + 2.0 * step;  // 1 and 3 ms
      evaluator.AddEstimate("r1", r1);
      evaluator.AddEstimate("r2", r2);
      if (step > 0) {  // standing still
        common::Odometry odometry;
        odometry.stamp.step = step;
        odometry.segments = {{0.0, 1.0, 0.0, 0.0}};
        evaluator.AddOdometry("r1", odometry);
        evaluator.AddOdometry("r2", odometry);
      }
    }
    EXPECT_TRUE(evaluator.Complete()) << evaluator.Missing();
    return evaluator.Write(out_dir_, 0.0);
  }

  common::ScenarioOptions scenario_;
  std::string out_dir_;
};

TEST_F(RunEvaluatorTest, UnionCompletenessCountsTheLandmarksOfTheFramesKnown) {
  const nlohmann::json alone = Score({});
  EXPECT_DOUBLE_EQ(alone["robots"]["r1"]["map_completeness"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(alone["robots"]["r1"]["union_completeness"].get<double>(), 1.0);
  // Knowing r2's frame, r1's map should also hold landmark 2, which only r2 reached.
  const nlohmann::json knowing = Score({"r2"});
  EXPECT_DOUBLE_EQ(knowing["robots"]["r1"]["map_completeness"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(knowing["robots"]["r1"]["union_completeness"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(knowing["robots"]["r2"]["union_completeness"].get<double>(), 1.0);
}

TEST_F(RunEvaluatorTest, RejectedSamplesAreTheAgentsCountAtTheEnd) {
  const nlohmann::json summary = Score({});
  EXPECT_EQ(summary["robots"]["r1"]["rejected_samples"].get<unsigned>(), 2U);
  EXPECT_EQ(summary["robots"]["r2"]["rejected_samples"].get<unsigned>(), 0U);
}

TEST_F(RunEvaluatorTest, StepCpuTimeIsSummarizedByMedianAndP99) {
  const nlohmann::json summary = Score({});
  EXPECT_DOUBLE_EQ(summary["robots"]["r1"]["step_cpu_ms_median"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(summary["robots"]["r1"]["step_cpu_ms_p99"].get<double>(), 1.0 + 2.0 * 0.99);
  EXPECT_DOUBLE_EQ(summary["robots"]["r2"]["step_cpu_ms_median"].get<double>(), 0.0);
}

TEST_F(RunEvaluatorTest, AnAnnouncedFinalTrajectoryIsAwaitedAndScored) {
  RunEvaluator evaluator(scenario_);
  common::GroundTruth truth;
  truth.robots = {{"r1", {0.0, 0.0, 0.0}, false}, {"r2", {10.0, 0.0, 0.0}, false}};
  truth.frames = {{"r1", {0.0, 0.0, 0.0}}, {"r2", {10.0, 0.0, 0.0}}};
  for (std::uint32_t step = 0; step <= 1; ++step) {
    truth.stamp.step = step;
    evaluator.AddTruth(truth);
    RobotEstimate r1, r2;
    r1.step = r2.step = step;
    r1.pose = {0.3, 0.4, 0.0};  // 0.5 m off online
    if (step == 1) r1.final_trajectory_chunks = 2;
    evaluator.AddEstimate("r1", r1);
    evaluator.AddEstimate("r2", r2);
  }
  common::Odometry odometry;
  odometry.stamp.step = 1;
  evaluator.AddOdometry("r1", odometry);
  evaluator.AddOdometry("r2", odometry);
  EXPECT_FALSE(evaluator.Complete());
  EXPECT_NE(evaluator.Missing().find("final trajectory, 0 of 2 chunks"), std::string::npos) << evaluator.Missing();
  evaluator.AddFinalTrajectory("r1", 1, {{1, 0.1, {0.0, 0.1, 0.0}}});
  EXPECT_FALSE(evaluator.Complete());
  evaluator.AddFinalTrajectory("r1", 0, {{0, 0.0, {0.0, 0.0, 0.0}}});
  ASSERT_TRUE(evaluator.Complete()) << evaluator.Missing();
  const nlohmann::json summary = evaluator.Write(out_dir_, 0.0);
  // r1: its final trajectory is 0 and 0.1 m off; r2, a filter, is scored on its online path.
  EXPECT_NEAR(summary["robots"]["r1"]["final_trajectory_rmse_m"].get<double>(), std::sqrt(0.01 / 2.0), 1e-12);
  EXPECT_NEAR(summary["robots"]["r1"]["position_rmse_m"].get<double>(), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(summary["robots"]["r2"]["final_trajectory_rmse_m"].get<double>(),
                   summary["robots"]["r2"]["position_rmse_m"].get<double>());
  EXPECT_TRUE(std::filesystem::exists(out_dir_ + "/trajectories/r1_final.tum"));
}

// Held() counts what is new only: a sample sent again (a replayed history) does not make it grow,
// so the evaluator's bound on a run that is gone is not reset by replays.
TEST_F(RunEvaluatorTest, HeldGrowsWithNewStepsOnlyNotWithReplays) {
  RunEvaluator evaluator(scenario_);
  EXPECT_EQ(evaluator.Held(), 0U);
  common::GroundTruth truth;
  truth.stamp.step = 0;
  evaluator.AddTruth(truth);
  RobotEstimate r1;
  r1.step = 1;
  evaluator.AddEstimate("r1", r1);
  EXPECT_EQ(evaluator.Held(), 2U);
  evaluator.AddTruth(truth);
  evaluator.AddEstimate("r1", r1);
  EXPECT_EQ(evaluator.Held(), 2U);
  truth.stamp.step = 1;
  evaluator.AddTruth(truth);
  common::Odometry odometry;
  odometry.stamp.step = 1;
  evaluator.AddOdometry("r2", odometry);
  evaluator.AddFinalTrajectory("r1", 0, {});
  EXPECT_EQ(evaluator.Held(), 5U);
}

}  // namespace
}  // namespace mrslam::evaluator
