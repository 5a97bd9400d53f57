#include "scripts/batch/joint_oracle.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/angles.h"
#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "robot_agent/smoother/batch_smoother.h"
#include "scripts/batch/joint_graph_oracle.h"
#include "scripts/batch/oracle_reference.h"
#include "world_sim/evaluator/metrics.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::batch {
namespace {

common::ScenarioOptions Scenario(const std::string& file, std::vector<std::string> overrides = {}) {
  overrides.push_back("sensors.lidar.report_identity=true");
  return common::LoadScenario(std::string(MRSLAM_TEST_SOURCE_DIR) + "/config/" + file, overrides);
}

// One seed of a scenario: every robot's position RMSE in its own frame over the run, alone (its
// oracle reference, --reference) and with the joint oracle (--reference --joint).
struct Errors {
  std::vector<double> alone, joint;
  bool identical = true;  // every step's joint estimate equal to the lone one, to the last bit
};
Errors RunSeed(common::ScenarioOptions o, int seed) {
  o.seed = seed;
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  const auto frames = source->Truth().frames;
  const int n = static_cast<int>(o.robots.size());
  JointOracle joint(o, frames);
  std::vector<std::unique_ptr<robot_agent::smoother::BatchSmoother>> alone;
  alone.reserve(n);
  for (int i = 0; i < n; ++i) alone.push_back(MakeOracleReference(o, FieldStatics(o), {i}, {}, 0));
  std::vector<std::vector<double>> alone_m(n), joint_m(n);
  Errors e;
  for (int k = 1; k <= o.run.steps; ++k) {
    const std::vector<common::SensorStep> steps = source->Step();
    const common::GroundTruth truth = source->Truth();
    joint.Process(steps);
    for (int i = 0; i < n; ++i) {
      alone[i]->Process(steps[i]);
      const Eigen::Vector2d own =
          common::Compose(common::Inverse(frames[i].second), truth.robots[i].pose).Translation();
      alone_m[i].push_back((alone[i]->Pose().Translation() - own).norm());
      joint_m[i].push_back((joint.Of(i).Pose().Translation() - own).norm());
      e.identical = e.identical && joint.Of(i).Pose().Vector() == alone[i]->Pose().Vector();
    }
  }
  for (int i = 0; i < n; ++i) {
    e.alone.push_back(evaluator::Rmse(alone_m[i]));
    e.joint.push_back(evaluator::Rmse(joint_m[i]));
  }
  return e;
}

TEST(JointOracle, IsEachRobotsReferenceWithoutContact) {
  // Contacts count from rendezvous.enable_from_step on: past the run's end, none. Every step's
  // estimate is then the robot's own reference, to the last bit; with contacts it is not.
  const Errors apart = RunSeed(Scenario("paper_two_robots.yaml", {"rendezvous.enable_from_step=1000"}), 1);
  EXPECT_TRUE(apart.identical);
  EXPECT_EQ(apart.joint, apart.alone);
  EXPECT_FALSE(RunSeed(Scenario("paper_two_robots.yaml"), 1).identical);
}

TEST(JointOracle, EachSmootherHoldsWhatItsContactsHandedOver) {
  // swarm_8 (a landmark_field: its static landmarks), 30 steps: after every step, robot i's
  // smoother holds robot j's data up to s_ij, and some robot holds a robot it never met itself.
  common::ScenarioOptions o = Scenario("swarm_8.yaml", {"run.steps=30"});
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  JointOracle joint(o, source->Truth().frames);
  const int n = static_cast<int>(o.robots.size());
  std::vector<std::vector<bool>> met(n, std::vector<bool>(n, false));
  for (int k = 1; k <= o.run.steps; ++k) {
    const std::vector<common::SensorStep> steps = source->Step();
    for (const auto& [a, b] : Contacts(steps, {"r1", "r2", "r3", "r4", "r5", "r6", "r7", "r8"}, k, 0)) {
      met[a][b] = met[b][a] = true;
    }
    joint.Process(steps);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) ASSERT_EQ(joint.SmootherHeld(i, j), joint.Sets().Held(i, j)) << i << " " << j;
    }
  }
  int through_others = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) through_others += i != j && !met[i][j] && joint.Sets().Held(i, j) > 0 ? 1 : 0;
  }
  EXPECT_GT(through_others, 0);
}

TEST(JointOracle, SolvedAtSampledStepsOnlyIsTheSameEstimateThere) {
  // paper_two_robots seed 1: an oracle that is handed every step but solves every 10th only (a
  // long run's reference, mrslam_batch --every) has at those steps the estimate of the one that
  // solves every step: the MAP estimate of the same data, from a colder start.
  const common::ScenarioOptions o = Scenario("paper_two_robots.yaml");
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  JointOracle every(o, source->Truth().frames), sampled(o, source->Truth().frames);
  for (int k = 1; k <= o.run.steps; ++k) {
    const std::vector<common::SensorStep> steps = source->Step();
    every.Process(steps);
    sampled.Process(steps, k % 10 == 0);
    if (k % 10 != 0) continue;
    for (int i = 0; i < 2; ++i) {
      const common::Pose2 a = every.Of(i).Pose(), b = sampled.Of(i).Pose();
      EXPECT_LT((a.Translation() - b.Translation()).norm(), 1e-3) << "step " << k << " robot " << i;
      EXPECT_LT(std::abs(common::WrapAngle(a.heading - b.heading)), 1e-3) << "step " << k << " robot " << i;
    }
  }
}

TEST(JointGraphOracle, IsTheJointOracleOnAStaticWorld) {
  // swarm_8 without movers, 60 steps, solved every 10th: the agents' joint graph over what each
  // robot holds (keyframes, corrections estimated) places every robot where the oracle smoother
  // of the same data does, to within a small part of the error both make (about 0.13 m).
  const common::ScenarioOptions o = Scenario("swarm_8.yaml", {"landmark_field.moving_fraction=0", "run.steps=60"});
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  JointOracle oracle(o, source->Truth().frames);
  JointGraphOracle graph(o);
  double largest = 0.0;
  for (int k = 1; k <= o.run.steps; ++k) {
    const std::vector<common::SensorStep> steps = source->Step();
    const bool solve = k % 10 == 0;
    oracle.Process(steps, solve);
    graph.Process(steps, solve);
    if (!solve) continue;
    for (int i = 0; i < static_cast<int>(o.robots.size()); ++i) {
      largest = std::max(largest, (oracle.Of(i).Pose().Translation() - graph.Pose(i).Translation()).norm());
    }
  }
  EXPECT_LT(largest, 0.02);
}

TEST(JointGraphOracle, RefusesMoversAndReadingsWithoutIdentities) {
  EXPECT_THROW(JointGraphOracle(Scenario("swarm_8.yaml")), std::invalid_argument);
  EXPECT_THROW(JointGraphOracle(common::LoadScenario(std::string(MRSLAM_TEST_SOURCE_DIR) + "/config/swarm_8.yaml",
                                                     {"landmark_field.moving_fraction=0"})),
               std::invalid_argument);
}

TEST(JointOracle, IsNoWorseThanAloneInMedianOverSeeds) {
  // paper_two_robots (the robots meet from step 14 on), seeds 1..10, both robots: the median over
  // the 20 robot-seeds of (position RMSE with the joint oracle - position RMSE alone) is at most
  // zero. (Per robot over 10 seeds the difference lies within the seeds' spread; the record,
  // docs/results/joint-oracle.md, has 20 seeds.)
  constexpr int kSeeds = 10;
  const common::ScenarioOptions o = Scenario("paper_two_robots.yaml");
  std::vector<double> differences;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const Errors e = RunSeed(o, seed);
    for (int i = 0; i < 2; ++i) differences.push_back(e.joint[i] - e.alone[i]);
  }
  EXPECT_LE(evaluator::Median(differences), 0.0);
}

}  // namespace
}  // namespace mrslam::batch
