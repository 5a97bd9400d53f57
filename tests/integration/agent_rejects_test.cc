// Multi-process: a robot_agent fed malformed samples (a NaN detection, a sample naming another
// robot, a sample of a step already processed) rejects and counts each, and goes on.
#include <gtest/gtest.h>

#include <limits>

#include "tests/integration/child_process.h"
#include "tests/integration/fake_simulator.h"

namespace mrslam {
namespace {

using std::chrono::seconds;
using testing::BinPath;
using testing::ChildProcess;
using testing::FakeSimulator;
using testing::SourcePath;

constexpr int kDomain = 115;
constexpr std::uint32_t kSteps = 3;
constexpr double kDt = 0.65;

common::LidarScan OneLandmark(bool with_nan_detection) {
  common::LidarScan scan{{}, {{0.0, 2.0, 0.1, -1}}, {}};
  if (with_nan_detection) scan.landmarks.push_back({0.0, std::numeric_limits<double>::quiet_NaN(), 0.0, -1});
  return scan;
}

TEST(AgentRejectsTest, MalformedSamplesAreRejectedCountedAndTheAgentGoesOn) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-rejects");
  const std::string& dir = temp_dir.path();
  dds::Participant participant({kDomain, "fake_sim", false});
  FakeSimulator sim(participant, "r1", kSteps, kDt);
  ChildProcess agent({BinPath("robot_agent"), "--scenario", SourcePath("config/paper_two_robots.yaml"), "--robot", "r1",
                      "--domain", std::to_string(kDomain), "--particles", "50"},
                     dir + "/agent.log");
  ASSERT_EQ(sim.WaitAck(0), 0) << testing::ReadFile(dir + "/agent.log");
  ASSERT_TRUE(sim.PublishStep(1, OneLandmark(true), 1.0, 0.2));
  EXPECT_EQ(sim.WaitAck(1), 1) << testing::ReadFile(dir + "/agent.log");
  ASSERT_TRUE(sim.PublishLidar(common::LidarScan{sim.StampOf(1), {}, {}}));  // stale
  common::Odometry foreign;                                                  // not r1's
  foreign.stamp = {"r2", 2, 2 * kDt};
  foreign.segments.push_back({kDt, kDt, 1.0, 0.2});
  ASSERT_TRUE(sim.PublishOdometry(foreign));
  ASSERT_TRUE(sim.PublishStep(2, OneLandmark(false), 1.0, 0.2));
  EXPECT_EQ(sim.WaitAck(2), 3) << testing::ReadFile(dir + "/agent.log");
  ASSERT_TRUE(sim.PublishStep(3, OneLandmark(false), 1.0, 0.2));
  EXPECT_EQ(sim.WaitAck(3), 3);
  EXPECT_EQ(agent.WaitExit(seconds(20)), std::optional<int>(0)) << testing::ReadFile(dir + "/agent.log");
}

}  // namespace
}  // namespace mrslam
