// Multi-process: an ekf_ela robot_agent (r1) meets a peer (r2, played by this test over DDS):
// after the rendezvous r2's "landmark moved" notice crosses DDS on r2's topic into r1, and r1 drops
// that landmark from its map (and only that one).
#include <gtest/gtest.h>

#include <cmath>

#include "common/angles.h"
#include "robot_agent/cooperation/peer_messages.h"
#include "robot_agent/node/msg_conversion.h"
#include "tests/integration/child_process.h"
#include "tests/integration/fake_simulator.h"

namespace mrslam {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
using testing::BinPath;
using testing::ChildProcess;
using testing::FakeSimulator;
using testing::SourcePath;

constexpr int kDomain = 117;
constexpr std::uint32_t kSteps = 3;
constexpr double kDt = 0.65;
constexpr double kPi = common::kPi;

// r1 stands at the origin of G1 facing -x; landmark A at (5.5, 0) and B at (5.5, 1.5) behind it;
// r2 at (0, 3) facing +x, at the origin of G2, so T(G1 <- G2) = (0, 3, 0).
common::LidarScan ScanAtOrigin() {
  common::LidarScan scan;
  const auto see = [](double x, double y) {
    return common::LandmarkDetection{0.0, std::hypot(x, y), common::WrapAngle(std::atan2(y, x) - kPi), -1};
  };
  scan.landmarks = {see(5.5, 0.0), see(5.5, 1.5)};
  scan.robots = {{0.0, 3.0, common::WrapAngle(kPi / 2 - kPi), "r2"}};
  return scan;
}

std::vector<msg::Estimate> EstimatesUntil(dds::Reader<msg::EstimatePubSubType>& reader, std::uint32_t last) {
  std::vector<msg::Estimate> all;
  msg::Estimate e;
  while (reader.Take(&e, seconds(20))) {
    all.push_back(e);
    if (e.stamp().step() == last) break;
  }
  return all;
}

int ConfirmedLandmarks(const msg::Estimate& e) {
  int n = 0;
  for (const auto& l : e.landmarks()) n += l.tentative() ? 0 : 1;
  return n;
}

TEST(MovedNoticeTest, NoticeFromAPeerDropsThatLandmarkOnly) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-moved");
  const std::string& dir = temp_dir.path();
  dds::Participant participant({kDomain, "fake_sim_and_r2", false});
  FakeSimulator sim(participant, "r1", kSteps, kDt);
  dds::Writer<msg::RelativeMeasurementPubSubType> to_r1_relative(participant, dds::PeerTopic("r1", "r2", "relative"));
  dds::Writer<msg::LandmarkMovedNoticePubSubType> to_r1_moved(participant, dds::PeerTopic("r1", "r2", "moved"));
  dds::Reader<msg::EstimatePubSubType> estimates(participant, dds::EstimateTopic("r1"));
  ChildProcess agent({BinPath("robot_agent"), "--scenario", SourcePath("config/paper_two_robots.yaml"), "--robot", "r1",
                      "--domain", std::to_string(kDomain), "--filter", "ekf_ela", "--set",
                      "robots.0.pose=[0.0, 0.0, 3.141592653589793]", "--set", "rendezvous.enable_from_step=0"},
                     dir + "/agent.log");
  ASSERT_EQ(sim.WaitAck(0), 0) << testing::ReadFile(dir + "/agent.log");

  // Step 1: both robots see each other (r2's measurement of r1: range 3, bearing -pi/2).
  ASSERT_TRUE(sim.PublishStep(1, ScanAtOrigin(), 0.0, 0.0));
  robot_agent::cooperation::RelativeMeasurement m;
  m.header = {"r2", "r1", 1, kDt, 1};
  m.range_m = 3.0;
  m.bearing_rad = -kPi / 2;
  m.sender_pose = {0.0, 0.0, 0.0};
  m.sender_covariance = Eigen::Matrix3d::Identity() * 1e-4;
  ASSERT_TRUE(to_r1_relative.Write(robot_agent::ToMsg(m)));
  ASSERT_EQ(sim.WaitAck(1), 0) << testing::ReadFile(dir + "/agent.log");

  // Step 2: r1 applies r2's measurement (rendezvous), still sees both landmarks. r2 then says
  // that A, at (5.5, -3) in G2, moved.
  ASSERT_TRUE(sim.PublishStep(2, ScanAtOrigin(), 0.0, 0.0, {{"r2", 1}}));
  ASSERT_EQ(sim.WaitAck(2), 0) << testing::ReadFile(dir + "/agent.log");
  robot_agent::cooperation::LandmarkMovedNotice n;
  n.header = {"r2", "r1", 2, 2 * kDt, 2};
  n.position_in_sender = {5.5, -3.0};
  ASSERT_TRUE(to_r1_moved.Write(robot_agent::ToMsg(n)));

  // Step 3: r1 drives 0.65 m away (both landmarks now beyond its 6 m range, so not expected in
  // view) and applies the notice first.
  ASSERT_TRUE(sim.PublishStep(3, common::LidarScan{}, 1.0, 0.0, {{"r2", 1}}));
  ASSERT_EQ(sim.WaitAck(3), 0) << testing::ReadFile(dir + "/agent.log");
  ASSERT_EQ(agent.WaitExit(seconds(20)), std::optional<int>(0)) << testing::ReadFile(dir + "/agent.log");

  const auto all = EstimatesUntil(estimates, kSteps);
  ASSERT_EQ(all.size(), kSteps);
  EXPECT_EQ(all[1].rendezvous().size(), 1U);  // met r2 at step 2 (its step-1 measurement)
  ASSERT_EQ(ConfirmedLandmarks(all[1]), 2);
  ASSERT_EQ(ConfirmedLandmarks(all[2]), 1) << testing::ReadFile(dir + "/agent.log");
  for (const auto& l : all[2].landmarks()) {
    if (!l.tentative()) {
      EXPECT_NEAR(l.pose().y_m(), 1.5, 0.3);  // B stays, A is gone
    }
  }
}

}  // namespace
}  // namespace mrslam
