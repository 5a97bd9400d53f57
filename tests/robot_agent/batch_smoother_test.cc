#include "robot_agent/smoother/batch_smoother.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "robot_agent/factory/filter_factory.h"
#include "robot_agent/filters/slam_filter.h"
#include "scripts/batch/oracle_reference.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::robot_agent::smoother {
namespace {

const std::string kPaperScenario = std::string(MRSLAM_TEST_SOURCE_DIR) + "/config/paper_two_robots.yaml";

common::ScenarioOptions PaperScenario(std::vector<std::string> overrides = {}) {
  overrides.push_back("sensors.lidar.report_identity=true");
  return common::LoadScenario(kPaperScenario, overrides);
}

// Position RMSE over a run of robot r1 in its own frame, for the reference and (if filter_type is
// not empty) for that filter on the same data.
struct RunErrors {
  double reference = 0.0, filter = 0.0, dead_reckoning = 0.0;
  double worst_reference = 0.0, worst_landmark = 0.0;
};
RunErrors RunR1(const common::ScenarioOptions& options, bool with_filter) {
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(options);
  const common::Pose2 frame = source->Truth().frames.at(0).second;
  BatchSmoother reference = batch::OracleSmoother(options, {0});
  std::unique_ptr<robot_agent::filters::SlamFilter> filter;
  if (with_filter) filter = robot_agent::factory::CreateFilter(common::AgentOptionsFor(options, "r1"), options.seed);
  common::Pose2 dead_reckoning = common::InitialPoseInOwnFrame(options.robots[0]);
  RunErrors e;
  for (int k = 0; k < options.run.steps; ++k) {
    const common::SensorStep step = source->Step().at(0);
    const common::GroundTruth truth = source->Truth();
    const common::Pose2 own = common::Compose(common::Inverse(frame), truth.robots[0].pose);
    reference.Process(step);
    const double err = (reference.Pose().Translation() - own.Translation()).norm();
    e.reference += err * err;
    e.worst_reference = std::max(e.worst_reference, err);
    for (const auto& [position, id] : reference.Landmarks()) {
      for (const auto& l : truth.landmarks) {
        if (std::stoi(l.id) != id) continue;
        const Eigen::Vector2d true_own = common::Compose(common::Inverse(frame), l.pose).Translation();
        e.worst_landmark = std::max(e.worst_landmark, (position - true_own).norm());
      }
    }
    if (filter) {
      filter->Process(step);
      e.filter += (filter->Estimate().pose.Translation() - own.Translation()).squaredNorm();
    }
    for (const auto& s : step.odometry.segments) {
      dead_reckoning = common::UnicycleStep(dead_reckoning, s.v_mps, s.w_radps, s.dt_s);
    }
    e.dead_reckoning += (dead_reckoning.Translation() - own.Translation()).squaredNorm();
  }
  e.reference = std::sqrt(e.reference / options.run.steps);
  e.filter = std::sqrt(e.filter / options.run.steps);
  e.dead_reckoning = std::sqrt(e.dead_reckoning / options.run.steps);
  return e;
}

TEST(BatchSmoother, IsExactWithoutNoise) {
  // Noise a million times below the scenario's: the MAP path and landmarks are the true ones.
  const common::ScenarioOptions o = PaperScenario(
      {"noise.robot_process_var=[1e-12, 1e-12, 1e-12]", "noise.landmark_process_var=[1e-12, 1e-12, 1e-12]",
       "sensors.lidar.range_noise_sd_m=1e-6", "sensors.lidar.bearing_noise_sd_rad=1e-6"});
  const RunErrors e = RunR1(o, /*with_filter=*/false);
  EXPECT_LT(e.worst_reference, 1e-3);
  EXPECT_LT(e.worst_landmark, 1e-3);
  EXPECT_GT(e.worst_landmark, 0.0);  // landmarks were seen and scored
}

TEST(BatchSmoother, BeatsTheParticleFilterOnTheSameData) {
  // The reference is the yardstick of the FastSLAM accuracy target: on average over seeds it
  // must do better than the filter, and far better than dead reckoning.
  double reference = 0.0, filter = 0.0, dead_reckoning = 0.0;
  for (int seed = 1; seed <= 5; ++seed) {
    common::ScenarioOptions o = PaperScenario();
    o.seed = seed;
    const RunErrors e = RunR1(o, /*with_filter=*/true);
    reference += e.reference / 5;
    filter += e.filter / 5;
    dead_reckoning += e.dead_reckoning / 5;
  }
  EXPECT_LT(reference, filter);
  EXPECT_LT(reference, 0.5 * dead_reckoning);
}

TEST(BatchSmoother, PlacesASecondRobotFromTheDataNotFromItsGuess) {
  // Both robots in r1's frame, r2's first pose started 0.5 m and 10 deg off: with little noise,
  // their common landmarks and detections of each other put it where it is.
  const common::ScenarioOptions o = PaperScenario(
      {"noise.robot_process_var=[1e-10, 1e-10, 1e-10]", "noise.landmark_process_var=[1e-10, 1e-10, 1e-10]",
       "sensors.lidar.range_noise_sd_m=1e-4", "sensors.lidar.bearing_noise_sd_rad=1e-4"});
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  const auto frames = source->Truth().frames;
  // r2's first pose in G1: T(G1 <- G2) applied to its first pose in G2.
  const common::Pose2 truth =
      common::Compose(common::Between(frames[0].second, frames[1].second), common::InitialPoseInOwnFrame(o.robots[1]));
  const common::Pose2 guess = common::Compose(truth, {0.3, -0.4, 0.17});
  BatchSmoother reference = batch::OracleSmoother(o, {0, 1}, {guess}, /*robot_detections_from_step=*/14);
  for (int k = 0; k < 20; ++k) reference.Process(source->Step());
  EXPECT_LT((reference.FirstPose(1).Translation() - truth.Translation()).norm(), 1e-3);
  EXPECT_LT(std::abs(common::WrapAngle(reference.FirstPose(1).heading - truth.heading)), 1e-3);
}

// Two robots' sensor steps and true poses in the first robot's frame, steps 1..n.
struct TwoRobotRun {
  std::vector<std::vector<common::SensorStep>> steps{2};
  std::vector<std::vector<common::Pose2>> truth{2};  // in G1
  common::Pose2 first_pose_2;                        // r2's first pose in G1
};
TwoRobotRun RecordTwoRobots(const common::ScenarioOptions& o, int n) {
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  const auto frames = source->Truth().frames;
  TwoRobotRun run;
  run.first_pose_2 =
      common::Compose(common::Between(frames[0].second, frames[1].second), common::InitialPoseInOwnFrame(o.robots[1]));
  for (int k = 0; k < n; ++k) {
    const std::vector<common::SensorStep> steps = source->Step();
    const common::GroundTruth truth = source->Truth();
    for (int r = 0; r < 2; ++r) {
      run.steps[r].push_back(steps[r]);
      run.truth[r].push_back(common::Compose(common::Inverse(frames[0].second), truth.robots[r].pose));
    }
  }
  return run;
}

TEST(BatchSmoother, OneRobotAtATimeIsTheSameProblemWhenStepsAreEqual) {
  // Add(r, step) for each robot in turn builds the problem Add(steps) builds: the same solution
  // to the last bit, step by step.
  const common::ScenarioOptions o = PaperScenario();
  const TwoRobotRun run = RecordTwoRobots(o, 40);
  const common::Pose2 guess = common::Compose(run.first_pose_2, {0.3, -0.4, 0.1});
  BatchSmoother together = batch::OracleSmoother(o, {0, 1}, {guess}, 14);
  BatchSmoother apart = batch::OracleSmoother(o, {0}, {}, 14);
  ASSERT_EQ(apart.AddRobot({o.robots[1].id, guess}), 1);
  for (int k = 0; k < 40; ++k) {
    together.Process({run.steps[0][k], run.steps[1][k]});
    apart.Add(0, run.steps[0][k]);
    apart.Add(1, run.steps[1][k]);
    apart.Solve();
    for (int r = 0; r < 2; ++r) {
      ASSERT_EQ(apart.Steps(r), k + 1);
      EXPECT_EQ(apart.Pose(r).Vector(), together.Pose(r).Vector()) << "step " << k + 1;
    }
    ASSERT_EQ(apart.Landmarks().size(), together.Landmarks().size());
    for (std::size_t l = 0; l < apart.Landmarks().size(); ++l) {
      EXPECT_EQ(apart.Landmarks()[l].first, together.Landmarks()[l].first);
    }
  }
}

TEST(BatchSmoother, RobotsHoldingDifferentStepsAreExactWithoutNoise) {
  // Noise a million times below the scenario's: r1 holds steps 1..20 and r2 steps 1..40 (its
  // first pose started 0.5 m and 10 deg off; its landmark readings of steps 1..10 removed, so
  // that it sights the moving landmarks later than r1), added one robot after the other in
  // either order (r1 first: the landmarks' chains grow forward to r2's readings; r2 first:
  // backward to r1's): every pose and landmark is the true one.
  const common::ScenarioOptions o = PaperScenario(
      {"noise.robot_process_var=[1e-12, 1e-12, 1e-12]", "noise.landmark_process_var=[1e-12, 1e-12, 1e-12]",
       "sensors.lidar.range_noise_sd_m=1e-6", "sensors.lidar.bearing_noise_sd_rad=1e-6"});
  TwoRobotRun run = RecordTwoRobots(o, 40);
  for (int k = 0; k < 10; ++k) run.steps[1][k].lidar.landmarks.clear();
  const int held[2] = {20, 40};
  for (const bool first_robot_first : {true, false}) {
    BatchSmoother reference =
        batch::OracleSmoother(o, {0, 1}, {common::Compose(run.first_pose_2, {0.3, -0.4, 0.17})}, 14);
    for (const int r : first_robot_first ? std::vector<int>{0, 1} : std::vector<int>{1, 0}) {
      for (int k = 0; k < held[r]; ++k) {
        reference.Add(r, run.steps[r][k]);
        if ((k + 1) % 5 == 0) reference.Solve();
      }
    }
    reference.Solve();
    for (int r = 0; r < 2; ++r) {
      ASSERT_EQ(reference.Steps(r), held[r]);
      const std::vector<common::Pose2>& path = reference.Path(r);
      for (int t = 1; t <= held[r]; ++t) {
        EXPECT_LT((path[t].Translation() - run.truth[r][t - 1].Translation()).norm(), 1e-3)
            << "robot " << r << " step " << t << (first_robot_first ? "" : ", r2's data first");
      }
    }
    EXPECT_LT((reference.FirstPose(1).Translation() - run.first_pose_2.Translation()).norm(), 1e-3);
    const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
    const auto frame = source->Truth().frames[0].second;
    for (int k = 0; k < 40; ++k) source->Step();
    const common::GroundTruth truth = source->Truth();
    int scored = 0;
    for (const auto& [position, id] : reference.Landmarks()) {
      for (const auto& l : truth.landmarks) {
        if (std::stoi(l.id) != id) continue;
        EXPECT_LT((position - common::Compose(common::Inverse(frame), l.pose).Translation()).norm(), 1e-3) << id;
        ++scored;
      }
    }
    EXPECT_GT(scored, 0);
  }
}

TEST(BatchSmoother, StartsAMoversHeadingFromSightingsAtTwoSteps) {
  // Both robots read each landmark first at the same step (their first), so the first two
  // sightings are at one step; the heading is started from the next sighting at another step.
  // Nearly without noise and before any solve, each landmark's chain then runs along its true
  // path (from a heading of 0 it would run off, 0.26-0.39 m per step).
  const common::ScenarioOptions o = PaperScenario(
      {"noise.robot_process_var=[1e-12, 1e-12, 1e-12]", "noise.landmark_process_var=[1e-12, 1e-12, 1e-12]",
       "sensors.lidar.range_noise_sd_m=1e-6", "sensors.lidar.bearing_noise_sd_rad=1e-6"});
  const TwoRobotRun run = RecordTwoRobots(o, 10);
  for (int r = 0; r < 2; ++r) ASSERT_EQ(run.steps[r][0].lidar.landmarks.size(), o.landmarks.size());
  BatchSmoother reference = batch::OracleSmoother(o, {0, 1}, {run.first_pose_2}, 14);
  for (int k = 0; k < 10; ++k) reference.Add({run.steps[0][k], run.steps[1][k]});
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  const auto frame = source->Truth().frames[0].second;
  for (int k = 0; k < 10; ++k) source->Step();
  const common::GroundTruth truth = source->Truth();
  ASSERT_EQ(reference.Landmarks().size(), o.landmarks.size());
  for (const auto& [position, id] : reference.Landmarks()) {
    for (const auto& l : truth.landmarks) {
      if (std::stoi(l.id) != id) continue;
      EXPECT_LT((position - common::Compose(common::Inverse(frame), l.pose).Translation()).norm(), 0.05) << id;
    }
  }
}

TEST(BatchSmoother, FirstPoseCovarianceCoversTheError) {
  // With the scenario's noise: the second robot's first pose against the truth, whitened by the
  // covariance the solver reports, over seeds.
  double nees = 0.0;
  constexpr int kSeeds = 5;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    common::ScenarioOptions o = PaperScenario();
    o.seed = seed;
    const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
    const auto frames = source->Truth().frames;
    const common::Pose2 truth = common::Compose(common::Between(frames[0].second, frames[1].second),
                                                common::InitialPoseInOwnFrame(o.robots[1]));
    BatchSmoother reference =
        batch::OracleSmoother(o, {0, 1}, {common::Compose(truth, {0.3, -0.4, 0.1})}, /*robot_detections_from_step=*/14);
    for (int k = 0; k < 20; ++k) reference.Process(source->Step());
    const common::Pose2& x = reference.FirstPose(1);
    const Eigen::Vector3d e(x.x - truth.x, x.y - truth.y, common::WrapAngle(x.heading - truth.heading));
    nees += e.dot(reference.FirstPoseCovariance(1).ldlt().solve(e));
  }
  // Chi-square with 15 dof: 99.8 % of it within [4.3, 34.3].
  EXPECT_GT(nees, 4.3);
  EXPECT_LT(nees, 34.3);
}

TEST(BatchSmoother, PoseCovarianceCoversTheCurrentPosesError) {
  // One robot alone, its current pose after 40 steps against the truth in its own frame, whitened
  // by the covariance the solver reports, over seeds.
  double nees = 0.0;
  constexpr int kSeeds = 20;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    common::ScenarioOptions o = PaperScenario();
    o.seed = seed;
    const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
    BatchSmoother reference = batch::OracleSmoother(o, {0});
    EXPECT_EQ(reference.PoseCovariance(0), Eigen::Matrix3d::Zero());  // the known first pose
    for (int k = 0; k < 40; ++k) reference.Add({source->Step()[0]});
    reference.Solve();
    const common::GroundTruth truth = source->Truth();
    const common::Pose2 t = common::Compose(common::Inverse(truth.frames[0].second), truth.robots[0].pose);
    const common::Pose2& x = reference.Pose(0);
    const Eigen::Vector3d e(x.x - t.x, x.y - t.y, common::WrapAngle(x.heading - t.heading));
    nees += e.dot(reference.PoseCovariance(0).ldlt().solve(e));
  }
  // Chi-square with 60 dof: 99.8 % of it within [31.7, 99.7] (Wilson-Hilferty).
  EXPECT_GT(nees, 31.7);
  EXPECT_LT(nees, 99.7);
}

// r1's whole path as a smoother solved every 15 steps holds it, from the given steps.
std::vector<common::Pose2> SmoothedPath(const common::ScenarioOptions& o,
                                        const std::vector<common::SensorStep>& steps) {
  BatchSmoother reference = batch::OracleSmoother(o, {0});
  for (std::size_t k = 0; k < steps.size(); ++k) {
    reference.Add({steps[k]});
    if ((k + 1) % 15 == 0 || k + 1 == steps.size()) reference.Solve();
  }
  return reference.Path(0);
}

double LargestDifference(const std::vector<common::Pose2>& a, const std::vector<common::Pose2>& b) {
  double out = 0.0;
  for (std::size_t t = 0; t < a.size(); ++t) out = std::max(out, (a[t].Translation() - b[t].Translation()).norm());
  return out;
}

TEST(BatchSmoother, LeavesOutAReadingBeyondTheOutlierGate) {
  common::ScenarioOptions o = PaperScenario();
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  std::vector<common::SensorStep> clean;
  clean.reserve(o.run.steps);
  for (int k = 0; k < o.run.steps; ++k) clean.push_back(source->Step().at(0));
  std::vector<common::SensorStep> corrupted = clean, without = clean;
  std::size_t k = 50;
  while (corrupted.at(k).lidar.landmarks.empty()) ++k;
  corrupted[k].lidar.landmarks[0].range_m += 3.0;  // ~100 sd off
  without[k].lidar.landmarks.erase(without[k].lidar.landmarks.begin());

  // No gate: the corrupted reading moves the path.
  EXPECT_GT(LargestDifference(SmoothedPath(o, clean), SmoothedPath(o, corrupted)), 0.01);
  // With the filters' gate, it is left out: the solution is that of the data without it (which
  // differs from the clean data's by the genuine reading's information).
  o.filter.outlier_gate_probability = 0.9999;
  const std::vector<common::Pose2> gated = SmoothedPath(o, corrupted);
  EXPECT_LT(LargestDifference(SmoothedPath(o, without), gated), 1e-6);
  EXPECT_GT(LargestDifference(SmoothedPath(o, clean), gated), 1e-3);
}

TEST(BatchSmoother, EstimatesTheOdometryErrorsTheCalibrationLeaves) {
  // The robot moves as commanded, but its calibration says 0.9 x the speed and 1.1 x the turn
  // rate: with little noise the smoother finds the speed factor that undoes it, 1 / 0.9, and the
  // turn rate the robot moves at (its command is a constant 0.2 rad/s, so factor and bias are not
  // told apart: their priors split the correction).
  common::ScenarioOptions o =
      PaperScenario({"noise.robot_process_var=[1e-8, 1e-8, 1e-8]", "noise.landmark_process_var=[1e-8, 1e-8, 1e-8]",
                     "sensors.lidar.range_noise_sd_m=1e-3", "sensors.lidar.bearing_noise_sd_rad=1e-3",
                     "filter.odometry_scale=0.9", "filter.odometry_turn_scale=1.1"});
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  BatchSmoother reference = batch::OracleSmoother(o, {0});
  reference.EstimateOdometryCalibration();
  for (int k = 1; k <= 40; ++k) {
    reference.Add({source->Step().at(0)});
    if (k % 5 == 0) reference.Solve();
  }
  const Eigen::Vector3d c = reference.OdometryCorrection(0);
  EXPECT_NEAR(c(0), 1.0 / 0.9, 1e-3);
  EXPECT_NEAR(c(1) * 1.1 * 0.2 + c(2), 0.2, 1e-4);
  EXPECT_GT(std::abs(c(1) - 1.0), 1e-3);  // both share the correction
  EXPECT_GT(std::abs(c(2)), 1e-3);
}

TEST(BatchSmoother, RejectsWhatItCannotModel) {
  const common::ScenarioOptions field =
      common::LoadScenario(std::string(MRSLAM_TEST_SOURCE_DIR) + "/config/dynamic_world.yaml", {});
  EXPECT_THROW(batch::OracleSmoother(field, {0}), std::invalid_argument);

  const common::ScenarioOptions anonymous = common::LoadScenario(kPaperScenario, {});
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(anonymous);
  BatchSmoother reference = batch::OracleSmoother(anonymous, {0});
  common::SensorStep step;
  do {
    step = source->Step().at(0);
  } while (step.lidar.landmarks.empty());
  EXPECT_THROW(reference.Process(step), std::invalid_argument);
}

}  // namespace
}  // namespace mrslam::robot_agent::smoother
