#include "world_sim/evaluator/run_evaluator.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

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

  // Scores the run in which r1 knows the frames in r1_frames_known and holds r1_data_held.
  nlohmann::json Score(const std::vector<std::string>& r1_frames_known,
                       const std::map<std::string, std::uint32_t>& r1_data_held = {}) const {
    RunEvaluator evaluator(scenario_, out_dir_);
    for (std::uint32_t step = 0; step <= 1; ++step) {
      common::GroundTruth truth;
      truth.stamp.step = step;
      truth.robots = {{"r1", {0.0, 0.0, 0.0}, false}, {"r2", {10.0, 0.0, 0.0}, false}};
      truth.landmarks = {{"1", {1.0, 0.0, 0.0}, false}, {"2", {11.0, 0.0, 0.0}, false}};
      if (with_mover_) truth.landmarks.push_back({"3", {12.0, 0.0, 0.0}, true});  // within r2's reach
      truth.frames = {{"r1", {0.0, 0.0, 0.0}}, {"r2", {10.0, 0.0, 0.0}}};
      evaluator.AddTruth(truth);
      RobotEstimate r1, r2;
      r1.step = r2.step = step;
      r1.landmarks = {{Eigen::Vector2d(1.0, 0.0), 1}};
      r2.landmarks = {{Eigen::Vector2d(1.0, 0.0), 2}};  // in r2's own frame
      r1.frames_known = r1_frames_known;
      r1.data_held = r1_data_held;
      r1.rejected_samples = 2 * step;                  // the agent's running count
      r1.peer_messages_late = 5 * step;                // the agent's running count
      r1.step_cpu_ms = 1.0 + 2.0 * step;               // 1 and 3 ms
      r1.peer_bytes_sent = std::uint64_t{300} * step;  // the agent's running counts
      r1.peer_bytes_received = std::uint64_t{100} * step;
      r1.estimator_bytes = 3000 - 1000 * step;  // 3000 and 2000 bytes: the most came first
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
    return evaluator.Finish(0.0);
  }

  common::ScenarioOptions scenario_;
  std::string out_dir_;
  bool with_mover_ = false;
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

TEST_F(RunEvaluatorTest, ReachableUnionCompletenessCountsOnlyWhatReachedTheAgent) {
  // r1 knows r2's frame but none of r2's data reached it: landmark 2 could not be in its map.
  const nlohmann::json frame_only = Score({"r2"});
  EXPECT_DOUBLE_EQ(frame_only["robots"]["r1"]["union_completeness"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(frame_only["robots"]["r1"]["reachable_union_completeness"].get<double>(), 1.0);
  // r2's step 1, in which landmark 2 was within its reach, reached r1.
  const nlohmann::json with_data = Score({"r2"}, {{"r2", 1U}});
  EXPECT_DOUBLE_EQ(with_data["robots"]["r1"]["reachable_union_completeness"].get<double>(), 0.5);
  // Data of a robot whose frame it does not know adds nothing.
  const nlohmann::json data_only = Score({}, {{"r2", 1U}});
  EXPECT_DOUBLE_EQ(data_only["robots"]["r1"]["reachable_union_completeness"].get<double>(), 1.0);
}

TEST_F(RunEvaluatorTest, StaticReachableUnionCompletenessLeavesTheMoversOut) {
  // r2 also saw a moving landmark; r2's data reached r1, whose map holds landmark 1 only.
  with_mover_ = true;
  const nlohmann::json s = Score({"r2"}, {{"r2", 1U}});
  EXPECT_DOUBLE_EQ(s["robots"]["r1"]["reachable_union_completeness"].get<double>(), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(s["robots"]["r1"]["static_reachable_union_completeness"].get<double>(), 0.5);
}

TEST_F(RunEvaluatorTest, RejectedAndLatePeerMessagesAreTheAgentsCountsAtTheEnd) {
  const nlohmann::json summary = Score({});
  EXPECT_EQ(summary["robots"]["r1"]["rejected_samples"].get<unsigned>(), 2U);
  EXPECT_EQ(summary["robots"]["r2"]["rejected_samples"].get<unsigned>(), 0U);
  EXPECT_EQ(summary["robots"]["r1"]["peer_messages_late"].get<unsigned>(), 5U);
  EXPECT_EQ(summary["robots"]["r2"]["peer_messages_late"].get<unsigned>(), 0U);
}

TEST_F(RunEvaluatorTest, StepCpuTimeIsSummarizedByMedianAndP99) {
  const nlohmann::json summary = Score({});
  EXPECT_DOUBLE_EQ(summary["robots"]["r1"]["step_cpu_ms_median"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(summary["robots"]["r1"]["step_cpu_ms_p99"].get<double>(), 1.0 + 2.0 * 0.99);
  EXPECT_DOUBLE_EQ(summary["robots"]["r2"]["step_cpu_ms_median"].get<double>(), 0.0);
}

TEST_F(RunEvaluatorTest, PeerBytesArePerSimulatedSecondOfTheAgentsSteps) {
  const nlohmann::json summary = Score({});
  const double seconds = 1 * scenario_.run.dt_s;  // the last estimate is of step 1
  EXPECT_DOUBLE_EQ(summary["robots"]["r1"]["peer_bytes_sent_per_s"].get<double>(), 300.0 / seconds);
  EXPECT_DOUBLE_EQ(summary["robots"]["r1"]["peer_bytes_received_per_s"].get<double>(), 100.0 / seconds);
  EXPECT_DOUBLE_EQ(summary["robots"]["r2"]["peer_bytes_sent_per_s"].get<double>(), 0.0);
}

TEST_F(RunEvaluatorTest, EstimatorBytesAreTheRunsMostAndTheLast) {
  const nlohmann::json summary = Score({});
  EXPECT_EQ(summary["robots"]["r1"]["estimator_bytes"].get<std::uint64_t>(), 3000U);
  EXPECT_EQ(summary["robots"]["r1"]["estimator_bytes_final"].get<std::uint64_t>(), 2000U);
  EXPECT_EQ(summary["robots"]["r2"]["estimator_bytes"].get<std::uint64_t>(), 0U);
  EXPECT_EQ(summary["robots"]["r2"]["estimator_bytes_final"].get<std::uint64_t>(), 0U);
}

TEST_F(RunEvaluatorTest, AnAnnouncedFinalTrajectoryIsAwaitedAndScored) {
  RunEvaluator evaluator(scenario_, out_dir_);
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
  evaluator.AddFinalTrajectory("r1", 1, {{1, 0.1, {0.0, 0.1, 0.2}}});
  EXPECT_FALSE(evaluator.Complete());
  evaluator.AddFinalTrajectory("r1", 0, {{0, 0.0, {0.0, 0.0, 0.0}}});
  ASSERT_TRUE(evaluator.Complete()) << evaluator.Missing();
  const nlohmann::json summary = evaluator.Finish(0.0);
  // r1: its final trajectory is 0 and 0.1 m off, 0 and 0.2 rad; r2, a filter, is scored on its
  // online path.
  EXPECT_NEAR(summary["robots"]["r1"]["final_trajectory_rmse_m"].get<double>(), std::sqrt(0.01 / 2.0), 1e-12);
  EXPECT_NEAR(summary["robots"]["r1"]["final_heading_rmse_deg"].get<double>(),
              common::DegFromRad(std::sqrt(0.04 / 2.0)), 1e-9);
  EXPECT_NEAR(summary["robots"]["r1"]["position_rmse_m"].get<double>(), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(summary["robots"]["r2"]["final_trajectory_rmse_m"].get<double>(),
                   summary["robots"]["r2"]["position_rmse_m"].get<double>());
  EXPECT_DOUBLE_EQ(summary["robots"]["r2"]["final_heading_rmse_deg"].get<double>(),
                   summary["robots"]["r2"]["heading_rmse_deg"].get<double>());
  EXPECT_TRUE(std::filesystem::exists(out_dir_ + "/trajectories/r1_final.tum"));
}

// The steps of a two-robot run standing still: truth, both estimates and odometry of step k.
struct StillStep {
  common::GroundTruth truth;
  RobotEstimate r1, r2;
  common::Odometry odometry;
};
StillStep StillAt(std::uint32_t step) {
  StillStep s;
  s.truth.stamp.step = step;
  s.truth.stamp.time_s = 0.5 * step;
  s.truth.robots = {{"r1", {0.0, 0.0, 0.0}, false}, {"r2", {10.0, 0.0, 0.0}, false}};
  s.truth.landmarks = {{"1", {1.0, 0.0, 0.0}, false}, {"2", {11.0, 0.0, 0.0}, false}};
  s.truth.frames = {{"r1", {0.0, 0.0, 0.0}}, {"r2", {10.0, 0.0, 0.0}}};
  s.r1.step = s.r2.step = step;
  s.r1.time_s = s.r2.time_s = 0.5 * step;
  s.r1.pose = {0.01 * step, 0.0, 0.0};  // drifting away
  s.r1.landmarks = {{Eigen::Vector2d(1.0, 0.0), 1}};
  s.odometry.stamp.step = step;
  s.odometry.segments = {{0.5 * step, 0.5, 0.1, 0.0}};  // commanded forward, standing still
  return s;
}

std::vector<nlohmann::json> ReadLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<nlohmann::json> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  return lines;
}

TEST_F(RunEvaluatorTest, ItsMemoryDoesNotGrowWithTheRunAndTheViewIsOneLinePerStep) {
  scenario_.run.steps = 2000;
  RunEvaluator evaluator(scenario_, out_dir_);
  std::size_t most_pending = 0;
  for (std::uint32_t step = 0; step <= 2000; ++step) {
    const StillStep s = StillAt(step);
    if (step > 0) evaluator.AddOdometry("r1", s.odometry);
    if (step > 0) evaluator.AddOdometry("r2", s.odometry);
    evaluator.AddTruth(s.truth);
    evaluator.AddEstimate("r1", s.r1);
    evaluator.AddEstimate("r2", s.r2);
    most_pending = std::max(most_pending, evaluator.Pending());
  }
  ASSERT_TRUE(evaluator.Complete()) << evaluator.Missing();
  EXPECT_LE(most_pending, 3U);  // a step's truth and estimates at most, however long the run
  const nlohmann::json summary = evaluator.Finish(0.0);
  EXPECT_EQ(summary["robots"]["r1"]["steps_scored"].get<int>(), 2001);
  const auto lines = ReadLines(out_dir_ + "/view.jsonl");
  ASSERT_EQ(lines.size(), 2002U);  // the header, then steps 0..2000 in order
  EXPECT_EQ(lines[0]["scenario"], "run_evaluator_test");
  for (std::uint32_t step = 0; step <= 2000; step += 250) {
    EXPECT_EQ(lines[step + 1]["step"], step);
    EXPECT_EQ(lines[step + 1]["truth"]["step"], step);
    EXPECT_EQ(lines[step + 1]["estimates"]["r2"]["step"], step);
  }
}

TEST_F(RunEvaluatorTest, TheOrderInWhichDataArriveDoesNotChangeTheScores) {
  scenario_.run.steps = 40;
  std::vector<StillStep> steps;
  for (std::uint32_t step = 0; step <= 40; ++step) steps.push_back(StillAt(step));
  nlohmann::json in_order;
  {
    RunEvaluator evaluator(scenario_, out_dir_);
    for (const auto& s : steps) {
      if (s.truth.stamp.step > 0) evaluator.AddOdometry("r1", s.odometry);
      if (s.truth.stamp.step > 0) evaluator.AddOdometry("r2", s.odometry);
      evaluator.AddTruth(s.truth);
      evaluator.AddEstimate("r1", s.r1);
      evaluator.AddEstimate("r2", s.r2);
    }
    in_order = evaluator.Finish(0.0);
  }
  // r2's estimates all first, then r1's, each estimate before its truth and odometry, r1's
  // estimates of steps 5..9 sent twice (an agent that came back).
  RunEvaluator evaluator(scenario_, out_dir_);
  for (const auto& s : steps) evaluator.AddEstimate("r2", s.r2);
  for (const auto& s : steps) {
    evaluator.AddEstimate("r1", s.r1);
    if (s.truth.stamp.step >= 10 && s.truth.stamp.step < 15)
      evaluator.AddEstimate("r1", steps[s.truth.stamp.step - 5].r1);
    evaluator.AddTruth(s.truth);
    if (s.truth.stamp.step > 0) evaluator.AddOdometry("r2", s.odometry);
    if (s.truth.stamp.step > 0) evaluator.AddOdometry("r1", s.odometry);
  }
  ASSERT_TRUE(evaluator.Complete()) << evaluator.Missing();
  nlohmann::json shuffled = evaluator.Finish(0.0);
  for (const std::string id : {"r1", "r2"}) {
    for (const std::string key : {"position_rmse_m", "dead_reckoning_rmse_m", "landmark_rmse_m", "steps_scored"}) {
      EXPECT_EQ(shuffled["robots"][id][key], in_order["robots"][id][key]) << id << " " << key;
    }
  }
  EXPECT_GT(in_order["robots"]["r1"]["position_rmse_m"].get<double>(), 0.1);
  EXPECT_GT(in_order["robots"]["r1"]["dead_reckoning_rmse_m"].get<double>(), 1.0);
}

// A reader that falls too far behind loses the steps dropped from the writer's history; each
// stream still comes in order, so once every stream's last step is in, the run is complete and
// scored without them, and the loss is counted instead of waited for.
TEST_F(RunEvaluatorTest, StepsLostFromAStreamAreCountedNotWaitedFor) {
  scenario_.run.steps = 20;
  RunEvaluator evaluator(scenario_, out_dir_);
  for (std::uint32_t step = 0; step <= 20; ++step) {
    const StillStep s = StillAt(step);
    if (step != 7 && step != 8) evaluator.AddTruth(s.truth);
    if (step > 0 && step != 12) evaluator.AddOdometry("r1", s.odometry);
    if (step > 0) evaluator.AddOdometry("r2", s.odometry);
    if (step != 3) evaluator.AddEstimate("r1", s.r1);
    evaluator.AddEstimate("r2", s.r2);
    if (step < 20) {
      EXPECT_FALSE(evaluator.Complete()) << step;
    }
  }
  ASSERT_TRUE(evaluator.Complete()) << evaluator.Missing();
  EXPECT_EQ(evaluator.TruthStepsLost(), 2U);
  const nlohmann::json summary = evaluator.Finish(0.0);
  EXPECT_EQ(summary["truth_steps_lost"].get<int>(), 2);
  EXPECT_EQ(summary["robots"]["r1"]["odometry_steps_lost"].get<int>(), 1);
  EXPECT_EQ(summary["robots"]["r2"]["odometry_steps_lost"].get<int>(), 0);
  EXPECT_EQ(summary["robots"]["r1"]["steps_scored"].get<int>(), 18);  // not step 3, nor 7 and 8
  EXPECT_EQ(summary["robots"]["r2"]["steps_scored"].get<int>(), 19);
}

// Taken() counts what is new only: a sample sent again (a replayed history) does not make it
// grow, so the evaluator's bound on a run that is gone is not reset by replays.
TEST_F(RunEvaluatorTest, TakenGrowsWithNewMessagesOnlyNotWithReplays) {
  RunEvaluator evaluator(scenario_, out_dir_);
  EXPECT_EQ(evaluator.Taken(), 0U);
  const StillStep s0 = StillAt(0);
  const StillStep s1 = StillAt(1);
  evaluator.AddTruth(s0.truth);
  evaluator.AddEstimate("r1", s1.r1);
  EXPECT_EQ(evaluator.Taken(), 2U);
  evaluator.AddTruth(s0.truth);
  evaluator.AddEstimate("r1", s1.r1);
  EXPECT_EQ(evaluator.Taken(), 2U);
  evaluator.AddTruth(s1.truth);
  evaluator.AddOdometry("r2", s1.odometry);
  evaluator.AddFinalTrajectory("r1", 0, {});
  evaluator.AddFinalTrajectory("r1", 0, {});
  EXPECT_EQ(evaluator.Taken(), 5U);
}

}  // namespace
}  // namespace mrslam::evaluator
