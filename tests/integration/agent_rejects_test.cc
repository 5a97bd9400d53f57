// Multi-process: a robot_agent fed malformed samples (a NaN detection, a sample naming another
// robot, a sample of a step already processed) rejects and counts each, and goes on.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"
#include "tests/integration/child_process.h"

namespace mrslam {
namespace {

using std::chrono::seconds;
using testing::BinPath;
using testing::ChildProcess;
using testing::SourcePath;

constexpr int kDomain = 115;
constexpr int kSteps = 3;

class FakeSimulator {
 public:
  explicit FakeSimulator(dds::Participant& p)
      : lidar_(p, dds::LidarTopic("r1")),
        imu_(p, dds::ImuTopic("r1")),
        odometry_(p, dds::OdometryTopic("r1")),
        clock_(p, dds::kClockTopic),
        ack_(p, dds::AckTopic("r1")) {}

  void PublishStep(std::uint32_t k, bool nan_detection) {
    const common::Stamp stamp{"r1", k, 0.65 * k};
    common::LidarScan scan{stamp, {{stamp.time_s, 2.0, 0.1, -1}}, {}};
    if (nan_detection) scan.landmarks.push_back({stamp.time_s, std::numeric_limits<double>::quiet_NaN(), 0.0, -1});
    ASSERT_TRUE(lidar_.Write(dds::ToMsg(scan)));
    ASSERT_TRUE(imu_.Write(dds::ToMsg(common::ImuSamples{stamp, {{stamp.time_s, 0.2, 0.0, 0.2}}})));
    ASSERT_TRUE(odometry_.Write(dds::ToMsg(common::Odometry{stamp, {{stamp.time_s - 0.65, 0.65, 1.0, 0.2}}})));
    msg::StepClock c;
    c.stamp(dds::ToMsg(common::Stamp{"world", k, stamp.time_s}));
    c.total_steps(kSteps);
    c.last_step(k == kSteps);
    ASSERT_TRUE(clock_.Write(c));
  }
  void PublishForeignOdometry(std::uint32_t k) {
    ASSERT_TRUE(odometry_.Write(dds::ToMsg(common::Odometry{{"r2", k, 0.65 * k}, {{0.0, 0.65, 1.0, 0.2}}})));
  }
  void PublishStaleLidar(std::uint32_t k) {
    ASSERT_TRUE(lidar_.Write(dds::ToMsg(common::LidarScan{{"r1", k, 0.65 * k}, {}, {}})));
  }
  // Waits for the agent's acknowledgement of step k; returns its rejected-sample count.
  int WaitAck(std::uint32_t k) {
    msg::StepAck a;
    while (ack_.Take(&a, seconds(20))) {
      if (a.stamp().step() == k) return static_cast<int>(a.rejected_samples());
    }
    return -1;
  }

 private:
  dds::Writer<msg::LidarScanPubSubType> lidar_;
  dds::Writer<msg::ImuPubSubType> imu_;
  dds::Writer<msg::OdometryPubSubType> odometry_;
  dds::Writer<msg::StepClockPubSubType> clock_;
  dds::Reader<msg::StepAckPubSubType> ack_;
};

TEST(AgentRejectsTest, MalformedSamplesAreRejectedCountedAndTheAgentGoesOn) {
  unsetenv("MRSLAM_DOMAIN");
  const std::string dir = testing::MakeTempDir("mrslam-rejects");
  dds::Participant participant({kDomain, "fake_sim", false});
  FakeSimulator sim(participant);
  ChildProcess agent({BinPath("robot_agent"), "--scenario", SourcePath("config/paper_two_robots.yaml"), "--robot", "r1",
                      "--domain", std::to_string(kDomain), "--particles", "50"},
                     dir + "/agent.log");
  ASSERT_EQ(sim.WaitAck(0), 0) << testing::ReadFile(dir + "/agent.log");
  sim.PublishStep(1, /*nan_detection=*/true);
  EXPECT_EQ(sim.WaitAck(1), 1) << testing::ReadFile(dir + "/agent.log");
  sim.PublishStaleLidar(1);
  sim.PublishForeignOdometry(2);
  sim.PublishStep(2, false);
  EXPECT_EQ(sim.WaitAck(2), 3) << testing::ReadFile(dir + "/agent.log");
  sim.PublishStep(3, false);
  EXPECT_EQ(sim.WaitAck(3), 3);
  EXPECT_EQ(agent.WaitExit(seconds(20)), std::optional<int>(0)) << testing::ReadFile(dir + "/agent.log");
}

}  // namespace
}  // namespace mrslam
