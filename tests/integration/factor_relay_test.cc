// Multi-process: raw measurements shared peer to peer on tests/integration/data/three_robots.yaml
// (r2 and r3 meet at once, r1 and r2 half a lap later; r1 and r3 never). r3's steps reach r1
// through r2 as r3 recorded them, no byte flows between r1 and r3, r1's joint estimate over what
// it holds places r3's path, and the summary reports each agent's peer traffic.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <Eigen/LU>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "robot_agent/cooperation/held_factors.h"
#include "robot_agent/cooperation/joint_estimate.h"
#include "tests/integration/child_process.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam {
namespace {

using robot_agent::cooperation::HeldFactors;
using robot_agent::cooperation::ReadHeldFactors;
using std::chrono::seconds;
using testing::ChildProcess;
using testing::ReadFile;

constexpr int kDomain = 102;  // this test's own DDS domain

TEST(FactorRelayTest, ARobotsStepsReachOneItNeverMetThroughAThird) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-relay");
  const std::string out = temp_dir.path() + "/out";
  ChildProcess launcher(
      {testing::BinPath("mrslam_launch"), "--scenario", testing::SourcePath("tests/integration/data/three_robots.yaml"),
       "--out", out, "--domain", std::to_string(kDomain), "--no-plots", "--set", "cooperation.share_factors=true"},
      temp_dir.path() + "/launch.log");
  ASSERT_TRUE(launcher.started());
  ASSERT_EQ(launcher.WaitExit(seconds(300)), std::optional<int>(0)) << ReadFile(temp_dir.path() + "/launch.log");

  std::map<std::string, HeldFactors> held;
  for (const std::string id : {"r1", "r2", "r3"})
    held[id] = ReadHeldFactors(robot_agent::cooperation::HeldFactorsPath(out + "/factors", id));
  // r1 holds r3's steps from the first on, each as r3 itself recorded it.
  const auto& own = held["r3"].logs.at("r3").steps;
  ASSERT_EQ(held["r1"].logs.count("r3"), 1U) << "r3's steps did not reach r1";
  const auto& relayed = held["r1"].logs.at("r3").steps;
  EXPECT_GE(relayed.size(), 10U);
  ASSERT_LE(relayed.size(), own.size());
  for (std::size_t i = 0; i < relayed.size(); ++i) {
    EXPECT_EQ(relayed[i].lidar.stamp.step, i + 1);
    ASSERT_EQ(relayed[i].odometry.segments.size(), own[i].odometry.segments.size()) << "step " << i + 1;
    EXPECT_EQ(relayed[i].lidar.landmarks.size(), own[i].lidar.landmarks.size()) << "step " << i + 1;
    EXPECT_EQ(relayed[i].lidar.robots.size(), own[i].lidar.robots.size()) << "step " << i + 1;
    if (!own[i].odometry.segments.empty()) {
      EXPECT_EQ(relayed[i].odometry.segments[0].v_mps, own[i].odometry.segments[0].v_mps);
    }
  }
  EXPECT_EQ(held["r1"].logs.at("r1").first_pose.x, held["r2"].logs.at("r1").first_pose.x);
  // Not a byte between r1 and r3; r2 talked to both.
  for (const auto& [a, b] : std::vector<std::pair<std::string, std::string>>{{"r1", "r3"}, {"r3", "r1"}}) {
    EXPECT_EQ(held[a].bytes_sent_to.count(b), 0U) << a << " sent to " << b;
    EXPECT_EQ(held[a].bytes_received_from.count(b), 0U) << a << " heard from " << b;
  }
  EXPECT_GT(held["r2"].bytes_sent_to["r1"], 0U);
  EXPECT_GT(held["r2"].bytes_sent_to["r3"], 0U);

  // r1 places r3 through r2: r3's frame in r1's joint estimate lies within the 99.9% ellipsoid
  // of its covariance around the true one.
  const common::ScenarioOptions scenario =
      common::LoadScenario(testing::SourcePath("tests/integration/data/three_robots.yaml"), {});
  const auto joint =
      robot_agent::cooperation::SolveJoint(common::AgentOptionsFor(scenario, "r1"), "r1", held["r1"].logs);
  EXPECT_TRUE(joint.not_placed.empty());
  const auto frames = world_sim::MakeStepSource(scenario)->Truth().frames;
  const common::Pose2 truth = common::Compose(common::Inverse(frames.at(0).second), frames.at(2).second);
  bool placed_r3 = false;
  for (const auto& f : joint.frames) {
    if (f.robot != "r3") continue;
    placed_r3 = true;
    const Eigen::Vector3d e(f.t_self_robot.x - truth.x, f.t_self_robot.y - truth.y,
                            common::WrapAngle(f.t_self_robot.heading - truth.heading));
    EXPECT_LT(e.dot(f.covariance.inverse() * e), 16.27) << e.transpose();
  }
  EXPECT_TRUE(placed_r3);

  std::ifstream in(out + "/summary.json");
  const auto summary = nlohmann::json::parse(in, nullptr, false);
  ASSERT_TRUE(summary.is_object());
  for (const std::string id : {"r1", "r2", "r3"}) {
    const auto& r = summary["robots"][id];
    EXPECT_GT(r["peer_bytes_sent_per_s"].get<double>(), 0.0) << id;
    EXPECT_GT(r["peer_bytes_received_per_s"].get<double>(), 0.0) << id;
    EXPECT_EQ(r["rejected_samples"].get<int>(), 0) << id;
  }
  // The estimates tell which of r3's steps reached r1: all it holds at the end.
  EXPECT_EQ(summary["robots"]["r1"]["data_held"]["r3"].get<std::size_t>(), relayed.size());
}

}  // namespace
}  // namespace mrslam
