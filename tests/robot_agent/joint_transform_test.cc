#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "robot_agent/cooperation/cooperation.h"
#include "robot_agent/cooperation/rendezvous.h"
#include "robot_agent/factory/filter_factory.h"
#include "robot_agent/filters/slam_filter.h"
#include "world_sim/source/step_source_factory.h"

// The joint estimate of the transform at a rendezvous (cooperation.joint_transform): two FastSLAM
// agents on paper_two_robots.yaml in one process, their peer messages passed by hand in lockstep.
namespace mrslam::robot_agent::cooperation {
namespace {

const std::string kPaperScenario = std::string(MRSLAM_TEST_SOURCE_DIR) + "/config/paper_two_robots.yaml";

struct Outcome {
  int joint[2] = {0, 0};                  // joint estimates made by r1, r2
  std::optional<FrameTransform> held[2];  // T(G1 <- G2) held by r1, T(G2 <- G1) held by r2
  common::Pose2 truth;                    // T(G1 <- G2)
};

// Runs both agents until both have made a joint estimate (or the run ends); the transforms held
// right then.
Outcome RunToTheFirstJointEstimate(const common::ScenarioOptions& o) {
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  const auto frames = source->Truth().frames;
  Outcome out;
  out.truth = common::Between(frames[0].second, frames[1].second);
  const std::string ids[2] = {o.robots[0].id, o.robots[1].id};
  std::unique_ptr<filters::SlamFilter> slams[2] = {factory::CreateFilter(common::AgentOptionsFor(o, ids[0]), o.seed),
                                                   factory::CreateFilter(common::AgentOptionsFor(o, ids[1]), o.seed)};
  Cooperation agents[2] = {Cooperation(common::AgentOptionsFor(o, ids[0])),
                           Cooperation(common::AgentOptionsFor(o, ids[1]))};
  PeerInbox inbox[2];
  for (int k = 0; k < o.run.steps; ++k) {
    const std::vector<common::SensorStep> steps = source->Step();
    PeerInbox next[2];
    for (int i = 0; i < 2; ++i) {
      agents[i].Receive(inbox[i], slams[i].get());
      slams[i]->Process(steps[i]);
      PeerOutbox sent = agents[i].AfterStep(steps[i], slams[i]->Estimate());
      next[1 - i] = std::move(sent);
    }
    for (int i = 0; i < 2; ++i) inbox[i] = std::move(next[i]);
    if (!agents[0].joint_estimates().empty() && !agents[1].joint_estimates().empty()) break;
  }
  for (int i = 0; i < 2; ++i) {
    out.joint[i] = static_cast<int>(agents[i].joint_estimates().size());
    for (const auto& t : agents[i].known_transforms()) {
      if (t.peer == ids[1 - i]) out.held[i] = t;
    }
  }
  return out;
}

common::ScenarioOptions Paper(std::vector<std::string> overrides) {
  overrides.push_back("filter.particles=200");
  return common::LoadScenario(kPaperScenario, overrides);
}

double HeadingError(const common::Pose2& a, const common::Pose2& b) {
  return std::abs(common::WrapAngle(a.heading - b.heading));
}

TEST(JointTransform, ExactWithoutNoise) {
  // Noise ten thousand times below the scenario's: both agents place each other exactly.
  const Outcome r = RunToTheFirstJointEstimate(
      Paper({"noise.robot_process_var=[1e-10, 1e-10, 1e-10]", "noise.landmark_process_var=[1e-10, 1e-10, 1e-10]",
             "sensors.lidar.range_noise_sd_m=1e-4", "sensors.lidar.bearing_noise_sd_rad=1e-4"}));
  ASSERT_EQ(r.joint[0], 1);
  ASSERT_EQ(r.joint[1], 1);
  ASSERT_TRUE(r.held[0] && r.held[1]);
  EXPECT_LT((r.held[0]->t_self_peer.Translation() - r.truth.Translation()).norm(), 1e-3);
  EXPECT_LT(HeadingError(r.held[0]->t_self_peer, r.truth), 1e-3);
  const common::Pose2 inverse = common::Inverse(r.truth);
  EXPECT_LT((r.held[1]->t_self_peer.Translation() - inverse.Translation()).norm(), 1e-3);
  EXPECT_LT(HeadingError(r.held[1]->t_self_peer, inverse), 1e-3);
}

TEST(JointTransform, BothSidesAgreeAndTheCovarianceCoversTheError) {
  // The scenario's noise, over seeds: the two agents solve the same problem from opposite
  // anchors, so their results are inverses; the error lies within the covariance.
  double nees = 0.0;
  int runs = 0;
  for (int seed = 1; seed <= 4; ++seed) {
    common::ScenarioOptions o = Paper({});
    o.seed = seed;
    const Outcome r = RunToTheFirstJointEstimate(o);
    ASSERT_EQ(r.joint[0], 1) << "seed " << seed;
    ASSERT_EQ(r.joint[1], 1) << "seed " << seed;
    ASSERT_TRUE(r.held[0] && r.held[1]);
    const common::Pose2 back = common::Inverse(r.held[1]->t_self_peer);
    EXPECT_LT((r.held[0]->t_self_peer.Translation() - back.Translation()).norm(), 1e-3) << "seed " << seed;
    EXPECT_LT(HeadingError(r.held[0]->t_self_peer, back), 1e-4) << "seed " << seed;
    const Eigen::Vector3d e(r.held[0]->t_self_peer.x - r.truth.x, r.held[0]->t_self_peer.y - r.truth.y,
                            common::WrapAngle(r.held[0]->t_self_peer.heading - r.truth.heading));
    nees += e.dot(r.held[0]->covariance.ldlt().solve(e));
    ++runs;
  }
  // The sum of 4 squared Mahalanobis distances (3 dof each): chi-square with 12 dof, 99.9 % below 32.9.
  EXPECT_LT(nees, 32.9);
  EXPECT_EQ(runs, 4);
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
