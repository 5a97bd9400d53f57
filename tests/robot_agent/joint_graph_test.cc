#include "robot_agent/smoother/joint_graph.h"

#include <map>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/LU>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "robot_agent/cooperation/joint_tracker.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::robot_agent::smoother {
namespace {

// Three robots among static landmarks: r2 and r3 meet at once, r1 and r2 half a lap later, r1
// and r3 never.
const std::string kThreeRobots = std::string(MRSLAM_TEST_SOURCE_DIR) + "/tests/integration/data/three_robots.yaml";

common::ScenarioOptions ThreeRobots(int seed, std::vector<std::string> overrides = {}) {
  overrides.push_back("seed=" + std::to_string(seed));
  overrides.push_back("sensors.lidar.report_identity=true");
  return common::LoadScenario(kThreeRobots, overrides);
}

common::ScenarioOptions Noiseless(int seed) {
  return ThreeRobots(seed, {"noise.robot_process_var=[1e-12, 1e-12, 1e-12]", "sensors.lidar.range_noise_sd_m=1e-6",
                            "sensors.lidar.bearing_noise_sd_rad=1e-6", "sensors.odometry.v_noise_sd_mps=0",
                            "sensors.odometry.w_noise_sd_radps=0"});
}

// Every robot's steps as shared (landmark readings labelled identity + 1) and its true poses and
// frame in r1's frame.
struct SimRun {
  std::vector<std::vector<common::SensorStep>> steps;
  std::vector<std::vector<common::Pose2>> truth;  // per robot, steps 0..n
  std::vector<common::Pose2> frames;              // T(G_r1 <- G_r)
  std::vector<common::Pose2> first_poses;
};

SimRun Simulate(const common::ScenarioOptions& o) {
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  const std::size_t n = o.robots.size();
  SimRun run;
  run.steps.resize(n);
  run.truth.resize(n);
  const common::GroundTruth start = source->Truth();
  const common::Pose2 to_r1 = common::Inverse(start.frames.at(0).second);
  for (std::size_t r = 0; r < n; ++r) {
    run.frames.push_back(common::Compose(to_r1, start.frames.at(r).second));
    run.first_poses.push_back(common::InitialPoseInOwnFrame(o.robots[r]));
  }
  const auto record_truth = [&](const common::GroundTruth& t) {
    for (std::size_t r = 0; r < n; ++r) run.truth[r].push_back(common::Compose(to_r1, t.robots[r].pose));
  };
  record_truth(start);
  for (int k = 0; k < o.run.steps; ++k) {
    std::vector<common::SensorStep> steps = source->Step();
    for (std::size_t r = 0; r < n; ++r) {
      for (auto& d : steps[r].lidar.landmarks) d.landmark_id += 1;
      run.steps[r].push_back(steps[r]);
    }
    record_truth(source->Truth());
  }
  return run;
}

std::vector<JointGraph::RobotLog> Logs(const common::ScenarioOptions& o, const SimRun& run,
                                       const std::vector<int>& order) {
  std::vector<JointGraph::RobotLog> logs;
  logs.reserve(order.size());
  for (const int r : order) logs.push_back({o.robots[r].id, run.first_poses[r], &run.steps[r]});
  return logs;
}

double PositionError(const JointGraph& graph, int index, const SimRun& run, int r) {
  double worst = 0.0;
  for (const auto& [step, pose] : graph.Path(index)) {
    worst = std::max(worst, (pose.Translation() - run.truth[r][step].Translation()).norm());
  }
  return worst;
}

TEST(JointGraph, IsExactWithoutNoiseAndPlacesARobotThroughAnother) {
  const common::ScenarioOptions o = Noiseless(1);
  const SimRun run = Simulate(o);
  JointGraph graph(common::AgentOptionsFor(o, "r1"), Logs(o, run, {0, 1, 2}));
  graph.Solve();
  for (int r = 0; r < 3; ++r) {
    ASSERT_TRUE(graph.Placed(r)) << r;
    EXPECT_LT(PositionError(graph, r, run, r), 1e-3) << r;
    const common::Pose2 frame = graph.Frame(r);
    EXPECT_NEAR(frame.x, run.frames[r].x, 1e-3) << r;
    EXPECT_NEAR(frame.y, run.frames[r].y, 1e-3) << r;
    EXPECT_NEAR(common::WrapAngle(frame.heading - run.frames[r].heading), 0.0, 1e-4) << r;
  }
  EXPECT_EQ(graph.Outliers(), 0);
}

TEST(JointGraph, LeavesOutARobotNothingLinks) {
  // r1 and r3 never detect each other, and r2's data, which would link them, is not held.
  const common::ScenarioOptions o = Noiseless(1);
  const SimRun run = Simulate(o);
  JointGraph graph(common::AgentOptionsFor(o, "r1"), Logs(o, run, {0, 2}));
  graph.Solve();
  EXPECT_TRUE(graph.Placed(0));
  EXPECT_FALSE(graph.Placed(1));
  EXPECT_TRUE(graph.Path(1).empty());
}

TEST(JointGraph, DoesNotDependOnTheOrderTheOthersAreHeldIn) {
  const common::ScenarioOptions o = ThreeRobots(2);
  const SimRun run = Simulate(o);
  JointGraph a(common::AgentOptionsFor(o, "r1"), Logs(o, run, {0, 1, 2}));
  JointGraph b(common::AgentOptionsFor(o, "r1"), Logs(o, run, {0, 2, 1}));
  a.Solve();
  b.Solve();
  const auto pa = a.Path(0), pb = b.Path(0);
  ASSERT_EQ(pa.size(), pb.size());
  for (std::size_t k = 0; k < pa.size(); ++k) {
    EXPECT_NEAR(pa[k].second.x, pb[k].second.x, 1e-6);
    EXPECT_NEAR(pa[k].second.y, pb[k].second.y, 1e-6);
    EXPECT_NEAR(common::WrapAngle(pa[k].second.heading - pb[k].second.heading), 0.0, 1e-6);
  }
}

TEST(JointGraph, WarmStartedFromAnEarlierGraphReachesTheSameSolution) {
  // r1 holds the first 60 steps of each robot, solves, then all 110 and solves again from there.
  // (A gate so wide that it leaves nothing out: a reading at its edge can fall either way
  // depending on the way to the solution, and both are fixed points.)
  const common::ScenarioOptions o = ThreeRobots(4, {"filter.smoother.reading_gate_probability=0.9999999999"});
  const SimRun run = Simulate(o);
  SimRun early = run;
  for (auto& steps : early.steps) steps.resize(60);
  const auto options = common::AgentOptionsFor(o, "r1");
  JointGraph before(options, Logs(o, early, {0, 1, 2}));
  before.Solve();
  JointGraph warm(options, Logs(o, run, {0, 1, 2}));
  warm.WarmStart(before);
  warm.Solve();
  JointGraph cold(options, Logs(o, run, {0, 1, 2}));
  cold.Solve();
  EXPECT_EQ(cold.Outliers(), 0);
  for (int r = 0; r < 3; ++r) {
    const auto pw = warm.Path(r), pc = cold.Path(r);
    ASSERT_EQ(pw.size(), pc.size()) << r;
    for (std::size_t k = 0; k < pw.size(); ++k) {
      EXPECT_NEAR(pw[k].second.x, pc[k].second.x, 1e-6) << r << " " << k;
      EXPECT_NEAR(pw[k].second.y, pc[k].second.y, 1e-6) << r << " " << k;
      EXPECT_NEAR(common::WrapAngle(pw[k].second.heading - pc[k].second.heading), 0.0, 1e-6) << r << " " << k;
    }
  }
}

TEST(JointGraph, FramesAreConsistentWithTheirCovariances) {
  // The frames of r2 and r3 over seeds: their normalized estimation error squared (3 dof) has a
  // mean of 3 when the covariances are right; over 20 draws it falls in [1.6, 4.8] with 99%.
  double nees = 0.0;
  int n = 0;
  for (int seed = 1; seed <= 10; ++seed) {
    const common::ScenarioOptions o = ThreeRobots(seed);
    const SimRun run = Simulate(o);
    JointGraph graph(common::AgentOptionsFor(o, "r1"), Logs(o, run, {0, 1, 2}));
    graph.Solve();
    for (int r = 1; r < 3; ++r) {
      ASSERT_TRUE(graph.Placed(r));
      const common::Pose2 f = graph.Frame(r);
      const Eigen::Vector3d e(f.x - run.frames[r].x, f.y - run.frames[r].y,
                              common::WrapAngle(f.heading - run.frames[r].heading));
      nees += e.dot(graph.FrameCovariance(r).inverse() * e);
      ++n;
    }
  }
  nees /= n;
  EXPECT_GT(nees, 1.6);
  EXPECT_LT(nees, 4.8);
}

TEST(JointGraph, AWrongCorrespondenceDoesNotMoveTheFrames) {
  // r2's readings of one landmark, relabelled as another that it also sees, over a stretch of its
  // run: the gate leaves them out, and the frames stay within their uncertainty of those without.
  const common::ScenarioOptions o = ThreeRobots(3);
  const SimRun clean = Simulate(o);
  SimRun forged = clean;
  int relabelled = 0;
  for (int t = 20; t < 60; ++t) {
    for (auto& d : forged.steps[1][t].lidar.landmarks) {
      if (d.landmark_id % 5 == 0) {
        d.landmark_id += 1;
        ++relabelled;
      }
    }
  }
  ASSERT_GT(relabelled, 5);
  JointGraph a(common::AgentOptionsFor(o, "r1"), Logs(o, clean, {0, 1, 2}));
  JointGraph b(common::AgentOptionsFor(o, "r1"), Logs(o, forged, {0, 1, 2}));
  a.Solve();
  b.Solve();
  EXPECT_GE(b.Outliers(), relabelled - a.Outliers());
  for (int r = 1; r < 3; ++r) {
    const common::Pose2 fa = a.Frame(r), fb = b.Frame(r);
    const Eigen::Vector3d d(fb.x - fa.x, fb.y - fa.y, common::WrapAngle(fb.heading - fa.heading));
    EXPECT_LT(d.dot(a.FrameCovariance(r).inverse() * d), 1.0) << r;
  }
}

TEST(JointTracker, MovesTheFiltersEstimateOntoTheJointEstimate) {
  // r1's "filter" is its dead reckoning; every robot's steps reach r1 as they are made. Each
  // solve (every 5 s, 10 steps) moves the estimate onto the joint graph's, which every robot's
  // readings correct.
  const common::ScenarioOptions o = ThreeRobots(5, {"cooperation.share_factors=true", "cooperation.joint_every_s=5"});
  const SimRun run = Simulate(o);
  const auto options = common::AgentOptionsFor(o, "r1");
  ASSERT_TRUE(cooperation::JointTracker::Enabled(options));
  cooperation::JointTracker tracker(options);
  std::map<std::string, cooperation::FactorLog> logs;
  for (int r = 0; r < 3; ++r) logs[o.robots[r].id].first_pose = run.first_poses[r];
  filters::FilterEstimate estimate;
  estimate.pose = run.first_poses[0];
  double dead_reckoning = 0.0, corrected = 0.0;
  std::uint64_t received = 0;
  for (int k = 1; k <= o.run.steps; ++k) {
    for (int r = 0; r < 3; ++r) logs[o.robots[r].id].steps.push_back(run.steps[r][k - 1]);
    received += 2;
    for (const auto& s : run.steps[0][k - 1].odometry.segments) {
      estimate.pose = common::UnicycleStep(estimate.pose, s.v_mps, s.w_radps, s.dt_s);
    }
    tracker.AfterStep(k, estimate, logs, received);
    const common::Pose2 truth = run.truth[0][k];
    dead_reckoning += (estimate.pose.Translation() - truth.Translation()).squaredNorm();
    corrected += (tracker.Corrected(estimate).pose.Translation() - truth.Translation()).squaredNorm();
  }
  dead_reckoning = std::sqrt(dead_reckoning / o.run.steps);
  corrected = std::sqrt(corrected / o.run.steps);
  EXPECT_EQ(tracker.solves(), o.run.steps / 10);
  EXPECT_LT(corrected, 0.5 * dead_reckoning) << corrected << " against " << dead_reckoning;
  // The final solve, warm-started, places every robot.
  EXPECT_TRUE(tracker.Final(logs).not_placed.empty());
}

}  // namespace
}  // namespace mrslam::robot_agent::smoother
