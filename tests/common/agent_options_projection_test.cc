#include "common/config/agent_options_projection.h"

#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "common/config/scenario_options.h"
#include "tests/test_matchers.h"
#include "tests/test_paths.h"

namespace mrslam::common {
namespace {

ScenarioOptions Swarm() { return LoadScenario(testing::SourcePath("config/swarm_8.yaml"), {}); }

TEST(InitialPoseInOwnFrame, ComposesTheFrameInverse) {
  RobotOptions r;
  r.frame_in_world = {0.347, 2.209, -0.6194};
  r.initial_pose = {0.0, 0.0, 2.09};
  EXPECT_THAT(Compose(r.frame_in_world, InitialPoseInOwnFrame(r)),
              testing::IsNearlyPose(Pose2{0.0, 0.0, 2.09}, 1e-12, 1e-12));
}

TEST(AgentOptionsFor, TellsTheAgentItsIdItsStartInItsOwnFrameAndTheTeam) {
  const ScenarioOptions s = Swarm();
  ASSERT_GE(s.robots.size(), 3U);
  const robot_agent::AgentOptions a = AgentOptionsFor(s, s.robots[2].id);
  EXPECT_EQ(a.robot_id, s.robots[2].id);
  ASSERT_EQ(a.team.size(), s.robots.size());
  for (std::size_t i = 0; i < s.robots.size(); ++i) {
    EXPECT_EQ(a.team[i], s.robots[i].id);
    EXPECT_EQ(a.TeamIndex(s.robots[i].id), static_cast<int>(i));
  }
  EXPECT_EQ(a.TeamIndex("nobody"), -1);
  EXPECT_THAT(a.initial_pose, testing::IsNearlyPose(InitialPoseInOwnFrame(s.robots[2]), 1e-12, 1e-12));
  EXPECT_DOUBLE_EQ(a.dt_s, s.run.dt_s);
}

TEST(AgentOptionsFor, CarriesTheModelsAndSettingsTheScenarioGives) {
  ScenarioOptions s = Swarm();
  s.sensors.lidar.range_noise_sd_m = 0.123;
  s.noise.robot_process_var.x() = 0.0042;
  s.filter.type = "ekf_ela";
  s.filter.particles = 77;
  s.rendezvous.window_steps = 9;
  s.cooperation.max_history_steps = 31;
  s.cooperation.map_fusion = robot_agent::MapFusionRule::kAverage;
  const robot_agent::AgentOptions a = AgentOptionsFor(s, s.robots[0].id);
  EXPECT_DOUBLE_EQ(a.sensors.lidar.range_noise_sd_m, 0.123);
  EXPECT_DOUBLE_EQ(a.noise.robot_process_var.x(), 0.0042);
  EXPECT_EQ(a.filter.type, "ekf_ela");
  EXPECT_EQ(a.filter.particles, 77);
  EXPECT_EQ(a.rendezvous.window_steps, 9);
  EXPECT_EQ(a.cooperation.max_history_steps, 31);
  EXPECT_EQ(a.cooperation.map_fusion, robot_agent::MapFusionRule::kAverage);
}

TEST(AgentOptionsFor, RejectsARobotTheScenarioDoesNotHave) {
  EXPECT_THROW(AgentOptionsFor(Swarm(), "r99"), ScenarioError);
}

}  // namespace
}  // namespace mrslam::common
