// Multi-process: a robot_agent rejects and counts by kind what it must not take — malformed
// samples (a NaN detection, a sample naming another robot), stale ones (a step already
// processed), scans written by a participant other than the simulator, a step clock from a second
// participant, a peer message naming a sender other than its topic's — and goes on with the
// simulator's samples. Input that makes the run's numbers doubtful ends the agent with an error
// naming the kind, unless --allow-rejected.
#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

#include "robot_agent/cooperation/peer_messages.h"
#include "robot_agent/node/msg_conversion.h"
#include "tests/integration/child_process.h"
#include "tests/integration/fake_simulator.h"

namespace mrslam {
namespace {

using std::chrono::seconds;
using testing::ChildProcess;
using testing::FakeSimulator;

// Each test on a DDS domain of its own (ctest runs them in parallel).
constexpr int kMalformedDomain = 141;
constexpr int kAllowedDomain = 146;
constexpr int kForeignDomain = 147;
constexpr int kPeerSenderDomain = 144;
constexpr int kUnannouncedDomain = 148;
constexpr int kLateLockstepDomain = 103;
constexpr int kLateRealtimeDomain = 104;
constexpr std::uint32_t kSteps = 3;
constexpr double kDt = 0.65;

common::LidarScan OneLandmark(bool with_nan_detection) {
  common::LidarScan scan{{}, {{0.0, 2.0, 0.1, -1}}, {}};
  if (with_nan_detection) scan.landmarks.push_back({0.0, std::numeric_limits<double>::quiet_NaN(), 0.0, -1});
  return scan;
}

// A well-formed relative measurement of step 1 to r1, its header naming `sender`.
msg::RelativeMeasurement MeasurementOfStep1(const std::string& sender) {
  robot_agent::cooperation::RelativeMeasurement m;
  m.header = {sender, "r1", 1, kDt, 1};
  m.range_m = 3.0;
  m.sender_covariance = Eigen::Matrix3d::Identity() * 1e-4;
  return robot_agent::ToMsg(m);
}

std::vector<std::string> AgentCommand(int domain, bool allow_rejected) {
  std::vector<std::string> extra = {"--particles", "50"};
  if (allow_rejected) extra.emplace_back("--allow-rejected");
  return testing::R1AgentCommand(domain, extra);
}

// Steps 1..3 with a NaN detection at step 1, then a stale sensor step 1 and a sensor step naming
// r2 before step 2: 2 malformed and 1 stale. Returns the agent's exit status.
std::optional<int> RunWithMalformedSamples(int domain, bool allow_rejected, const std::string& dir) {
  dds::Participant participant({domain, "fake_sim", false});
  FakeSimulator sim(participant, "r1", kSteps, kDt);
  ChildProcess agent(AgentCommand(domain, allow_rejected), dir + "/agent.log");
  EXPECT_EQ(sim.WaitAck(0), 0) << testing::ReadFile(dir + "/agent.log");
  EXPECT_TRUE(sim.PublishStep(1, OneLandmark(true), 1.0, 0.2));
  EXPECT_EQ(sim.WaitAck(1), 1) << testing::ReadFile(dir + "/agent.log");
  EXPECT_TRUE(sim.PublishSensors(sim.SensorStepOf(sim.StampOf(1), {}, 1.0, 0.2)));      // stale
  EXPECT_TRUE(sim.PublishSensors(sim.SensorStepOf({"r2", 2, 2 * kDt}, {}, 1.0, 0.2)));  // not r1's
  EXPECT_TRUE(sim.PublishStep(2, OneLandmark(false), 1.0, 0.2));
  EXPECT_EQ(sim.WaitAck(2), 3) << testing::ReadFile(dir + "/agent.log");
  EXPECT_TRUE(sim.PublishStep(3, OneLandmark(false), 1.0, 0.2));
  EXPECT_EQ(sim.WaitAck(3), 3);
  return agent.WaitExit(seconds(20));
}

TEST(AgentRejectsTest, MalformedSamplesAreRejectedCountedAndFailTheRun) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-rejects");
  const std::optional<int> status = RunWithMalformedSamples(kMalformedDomain, false, temp_dir.path());
  const std::string log = testing::ReadFile(temp_dir.path() + "/agent.log");
  ASSERT_TRUE(status.has_value()) << log;
  EXPECT_NE(*status, 0) << log;
  EXPECT_NE(log.find("agent r1 rejected 2 malformed, 1 stale input(s)"), std::string::npos) << log;
}

TEST(AgentRejectsTest, WithAllowRejectedTheAgentGoesOnAndEndsNormally) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-rejects");
  EXPECT_EQ(RunWithMalformedSamples(kAllowedDomain, true, temp_dir.path()), std::optional<int>(0))
      << testing::ReadFile(temp_dir.path() + "/agent.log");
}

// Another participant writes sensor steps on r1's topic for every step before the simulator does
// (the spoof that used to displace the real ones): the agent takes the simulator's, counts one
// foreign-writer rejection per step, and fails the run.
TEST(AgentRejectsTest, SensorStepsFromAnotherParticipantAreNotTakenAndFailTheRun) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-rejects");
  const std::string log_path = temp_dir.path() + "/agent.log";
  dds::Participant participant({kForeignDomain, "fake_sim", false});
  dds::Participant outsider_participant({kForeignDomain, "outsider", false});
  FakeSimulator sim(participant, "r1", kSteps, kDt);
  FakeSimulator outsider(outsider_participant, "r1", kSteps, kDt);
  ChildProcess agent(AgentCommand(kForeignDomain, false), log_path);
  ASSERT_EQ(sim.WaitAck(0), 0) << testing::ReadFile(log_path);
  for (std::uint32_t k = 1; k <= kSteps; ++k) {
    common::LidarScan forged = OneLandmark(false);
    forged.landmarks.push_back({outsider.StampOf(k).time_s, 7.0, -1.0, -1});
    ASSERT_TRUE(outsider.PublishSensors(outsider.SensorStepOf(outsider.StampOf(k), forged, 3.0, -0.5)));
  }
  ASSERT_TRUE(outsider.WaitSensorsDelivered());
  for (std::uint32_t k = 1; k <= kSteps; ++k) {
    ASSERT_TRUE(sim.PublishStep(k, OneLandmark(false), 1.0, 0.2));
    EXPECT_EQ(sim.WaitAck(k), static_cast<int>(k)) << testing::ReadFile(log_path);
  }
  const std::optional<int> status = agent.WaitExit(seconds(20));
  const std::string log = testing::ReadFile(log_path);
  ASSERT_TRUE(status.has_value()) << log;
  EXPECT_NE(*status, 0) << log;
  EXPECT_NE(log.find("rejected 3 foreign-writer input(s)"), std::string::npos) << log;
}

// A peer message on r2's topic into r1 whose header names another sender (r3) is not taken: it
// counts as malformed and fails the run.
// A peer message of step 1 that comes after the agent processed step 3: in lockstep stale
// (rejected and counted, the run goes on: the agent waited for what the clock announced), in
// realtime late (applied at the next step and counted as late). Returns the agent's log.
std::string RunWithALatePeerMessage(int domain, const std::string& mode, const std::string& dir) {
  constexpr std::uint32_t kLateSteps = 5;
  dds::Participant participant({domain, "fake_sim_and_r2", false});
  FakeSimulator sim(participant, "r1", kLateSteps, kDt);
  dds::Writer<msg::RelativeMeasurementPubSubType> from_r2(participant, dds::PeerTopic("r1", "r2", "relative"));
  dds::Reader<msg::EstimatePubSubType> estimates(participant, dds::EstimateTopic("r1"));
  // Step k done: its acknowledgement in lockstep; in realtime (where the agent acknowledges only
  // that it is ready) its estimate.
  const auto wait_step = [&](std::uint32_t k) {
    if (mode == "lockstep") return sim.WaitAck(k) >= 0;
    msg::Estimate e;
    while (estimates.Take(&e, seconds(20))) {
      if (e.stamp().step() == k) return true;
    }
    return false;
  };
  ChildProcess agent(testing::R1AgentCommand(domain, {"--particles", "50", "--set", "run.mode=" + mode}),
                     dir + "/agent.log");
  EXPECT_EQ(sim.WaitAck(0), 0) << testing::ReadFile(dir + "/agent.log");
  for (std::uint32_t k = 1; k <= kLateSteps; ++k) {
    if (k == 4) {
      EXPECT_TRUE(from_r2.Write(MeasurementOfStep1("r2")));
      EXPECT_TRUE(from_r2.WaitForAcknowledgments(seconds(20)));
    }
    EXPECT_TRUE(sim.PublishStep(k, OneLandmark(false), 1.0, 0.2));
    EXPECT_TRUE(wait_step(k)) << testing::ReadFile(dir + "/agent.log");
  }
  EXPECT_EQ(agent.WaitExit(seconds(20)), std::optional<int>(0)) << testing::ReadFile(dir + "/agent.log");
  return testing::ReadFile(dir + "/agent.log");
}

TEST(AgentRejectsTest, APeerMessageOfAPastStepIsStaleInLockstepAndAppliedLateInRealtime) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir lockstep_dir("mrslam-late");
  const std::string lockstep = RunWithALatePeerMessage(kLateLockstepDomain, "lockstep", lockstep_dir.path());
  EXPECT_NE(lockstep.find("rejected (stale): peer message of step 1 from r2"), std::string::npos) << lockstep;
  EXPECT_NE(lockstep.find("rejected: 1 stale, peer messages applied a step late: 0"), std::string::npos) << lockstep;
  const testing::TempDir realtime_dir("mrslam-late");
  const std::string realtime = RunWithALatePeerMessage(kLateRealtimeDomain, "realtime", realtime_dir.path());
  EXPECT_EQ(realtime.find("rejected (stale)"), std::string::npos) << realtime;
  EXPECT_NE(realtime.find("peer messages applied a step late: 1"), std::string::npos) << realtime;
}

TEST(AgentRejectsTest, PeerMessageNamingAnotherSenderThanItsTopicIsMalformed) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-rejects");
  const std::string log_path = temp_dir.path() + "/agent.log";
  dds::Participant participant({kPeerSenderDomain, "fake_sim_and_r2", false});
  FakeSimulator sim(participant, "r1", kSteps, kDt);
  dds::Writer<msg::RelativeMeasurementPubSubType> from_r2(participant, dds::PeerTopic("r1", "r2", "relative"));
  ChildProcess agent(AgentCommand(kPeerSenderDomain, false), log_path);
  ASSERT_EQ(sim.WaitAck(0), 0) << testing::ReadFile(log_path);
  ASSERT_TRUE(sim.PublishStep(1, OneLandmark(false), 1.0, 0.2));
  ASSERT_EQ(sim.WaitAck(1), 0) << testing::ReadFile(log_path);
  ASSERT_TRUE(from_r2.Write(MeasurementOfStep1("r3")));
  ASSERT_TRUE(from_r2.WaitForAcknowledgments(seconds(20)));
  for (std::uint32_t k = 2; k <= kSteps; ++k) {
    ASSERT_TRUE(sim.PublishStep(k, OneLandmark(false), 1.0, 0.2));
    EXPECT_EQ(sim.WaitAck(k), 1) << testing::ReadFile(log_path);
  }
  const std::optional<int> status = agent.WaitExit(seconds(20));
  const std::string log = testing::ReadFile(log_path);
  ASSERT_TRUE(status.has_value()) << log;
  EXPECT_NE(*status, 0) << log;
  EXPECT_NE(log.find("peer message from 'r3' on r2's topic"), std::string::npos) << log;
  EXPECT_NE(log.find("agent r1 rejected 1 malformed input(s)"), std::string::npos) << log;
}

// In lockstep the step clock announces how many peer messages each sender wrote to each
// recipient during the step before. A well-formed message from "r2" that the simulator never
// counted (r2 sent nothing) was written by someone else: contested, and the run fails.
TEST(AgentRejectsTest, APeerMessageTheClockDidNotAnnounceIsContested) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-rejects");
  const std::string log_path = temp_dir.path() + "/agent.log";
  dds::Participant participant({kUnannouncedDomain, "fake_sim", false});
  dds::Participant outsider({kUnannouncedDomain, "outsider", false});
  FakeSimulator sim(participant, "r1", kSteps, kDt);
  dds::Writer<msg::RelativeMeasurementPubSubType> as_r2(outsider, dds::PeerTopic("r1", "r2", "relative"));
  ChildProcess agent(AgentCommand(kUnannouncedDomain, false), log_path);
  ASSERT_EQ(sim.WaitAck(0), 0) << testing::ReadFile(log_path);
  ASSERT_TRUE(sim.PublishStep(1, OneLandmark(false), 1.0, 0.2));
  ASSERT_EQ(sim.WaitAck(1), 0) << testing::ReadFile(log_path);
  ASSERT_TRUE(as_r2.Write(MeasurementOfStep1("r2")));
  ASSERT_TRUE(as_r2.WaitForAcknowledgments(seconds(20)));
  for (std::uint32_t k = 2; k <= kSteps; ++k) {
    ASSERT_TRUE(sim.PublishStep(k, OneLandmark(false), 1.0, 0.2));  // announcing no peer message
    EXPECT_EQ(sim.WaitAck(k), 1) << testing::ReadFile(log_path);
  }
  const std::optional<int> status = agent.WaitExit(seconds(20));
  const std::string log = testing::ReadFile(log_path);
  ASSERT_TRUE(status.has_value()) << log;
  EXPECT_NE(*status, 0) << log;
  EXPECT_NE(log.find("1 peer message(s) of step 1 from r2 where the simulator counted 0"), std::string::npos) << log;
  EXPECT_NE(log.find("agent r1 rejected 1 contested input(s)"), std::string::npos) << log;
}

}  // namespace
}  // namespace mrslam
