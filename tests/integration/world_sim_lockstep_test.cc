// Multi-process: world_sim in lockstep with fake agents that acknowledge each step; a test
// subscriber receives every step of every topic exactly once, in order, with the values the
// simulation core computes for the same scenario and seed. In realtime, the robots' data are
// spread over the step (run.stagger_robots).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>

#include "common/config/scenario_options.h"
#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"
#include "tests/integration/child_process.h"
#include "world_sim/core/world.h"

namespace mrslam {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
using testing::BinPath;
using testing::ChildProcess;
using testing::SourcePath;

constexpr int kDomain = 111;  // this test's own DDS domain
constexpr int kSteps = 15;

bool SameLidar(const common::LidarScan& a, const common::LidarScan& b) {
  if (a.landmarks.size() != b.landmarks.size() || a.robots.size() != b.robots.size()) return false;
  for (std::size_t i = 0; i < a.landmarks.size(); ++i) {
    const auto &x = a.landmarks[i], &y = b.landmarks[i];
    if (x.range_m != y.range_m || x.bearing_rad != y.bearing_rad || x.landmark_id != y.landmark_id) return false;
  }
  for (std::size_t i = 0; i < a.robots.size(); ++i) {
    const auto &x = a.robots[i], &y = b.robots[i];
    if (x.range_m != y.range_m || x.bearing_rad != y.bearing_rad || x.seen_robot_id != y.seen_robot_id) return false;
  }
  return true;
}
bool SameOdometry(const common::Odometry& a, const common::Odometry& b) {
  if (a.segments.size() != b.segments.size()) return false;
  for (std::size_t i = 0; i < a.segments.size(); ++i) {
    if (a.segments[i].v_mps != b.segments[i].v_mps || a.segments[i].w_radps != b.segments[i].w_radps ||
        a.segments[i].dt_s != b.segments[i].dt_s)
      return false;
  }
  return true;
}
bool SameImu(const common::ImuSamples& a, const common::ImuSamples& b) {
  if (a.readings.size() != b.readings.size()) return false;
  for (std::size_t i = 0; i < a.readings.size(); ++i) {
    if (a.readings[i].gyro_z_radps != b.readings[i].gyro_z_radps ||
        a.readings[i].accel_x_mps2 != b.readings[i].accel_x_mps2 ||
        a.readings[i].accel_y_mps2 != b.readings[i].accel_y_mps2)
      return false;
  }
  return true;
}

// Drains a reader after the run: every message it ever received, in arrival order.
template <typename R, typename M>
std::vector<M> TakeAll(R& reader) {
  std::vector<M> all;
  M m;
  while (reader.Take(&m, milliseconds(200))) all.push_back(m);
  return all;
}

TEST(WorldSimLockstepTest, EveryTopicEveryStepOnceInOrderWithCoreValues) {
  unsetenv("MRSLAM_DOMAIN");
  const std::string scenario_path = SourcePath("config/paper_two_robots.yaml");
  auto scenario = common::LoadScenario(scenario_path, {"run.steps=" + std::to_string(kSteps)});
  const testing::TempDir temp_dir("mrslam-lockstep");
  const std::string& dir = temp_dir.path();

  dds::Participant participant({kDomain, "lockstep_test", false});
  struct RobotReaders {
    std::unique_ptr<dds::Reader<msg::SensorStepPubSubType>> sensors;
    std::unique_ptr<dds::Writer<msg::StepAckPubSubType>> ack;  // the fake agent
  };
  std::map<std::string, RobotReaders> robots;
  for (const auto& r : scenario.robots) {
    auto& rr = robots[r.id];
    rr.sensors = std::make_unique<dds::Reader<msg::SensorStepPubSubType>>(participant, dds::SensorTopic(r.id));
    rr.ack = std::make_unique<dds::Writer<msg::StepAckPubSubType>>(participant, dds::AckTopic(r.id));
  }
  dds::Reader<msg::GroundTruthPubSubType> truth_reader(participant, dds::kTruthTopic);
  dds::Reader<msg::StepClockPubSubType> clock_reader(participant, dds::kClockTopic);

  ChildProcess sim({BinPath("world_sim"), "--scenario", scenario_path, "--domain", std::to_string(kDomain), "--steps",
                    std::to_string(kSteps)},
                   dir + "/world_sim.log");
  ASSERT_TRUE(sim.started());

  auto ack = [&](std::uint32_t step) {
    for (auto& [id, rr] : robots) {
      msg::StepAck a;
      a.stamp().robot_id(id);
      a.stamp().step(step);
      ASSERT_TRUE(rr.ack->Write(a));
    }
  };
  ack(0);
  std::vector<std::uint32_t> clock_steps;
  for (int k = 1; k <= kSteps; ++k) {
    msg::StepClock c;
    ASSERT_TRUE(clock_reader.Take(&c, seconds(20))) << "no clock for step " << k << "; log:\n"
                                                    << testing::ReadFile(dir + "/world_sim.log");
    clock_steps.push_back(c.stamp().step());
    EXPECT_EQ(c.last_step(), k == kSteps);
    ack(c.stamp().step());
  }
  ASSERT_EQ(sim.WaitExit(seconds(30)), std::optional<int>(0)) << testing::ReadFile(dir + "/world_sim.log");
  for (int k = 1; k <= kSteps; ++k) EXPECT_EQ(clock_steps[k - 1], static_cast<std::uint32_t>(k));

  // The same scenario and seed, stepped in-process.
  world_sim::World world(scenario);
  std::vector<common::GroundTruth> expected_truth{world.Truth()};
  std::vector<std::vector<common::SensorStep>> expected;
  for (int k = 1; k <= kSteps; ++k) {
    expected.push_back(world.Step());
    expected_truth.push_back(world.Truth());
  }
  for (std::size_t i = 0; i < scenario.robots.size(); ++i) {
    const auto& id = scenario.robots[i].id;
    auto& rr = robots[id];
    const auto sensors = TakeAll<decltype(*rr.sensors), msg::SensorStep>(*rr.sensors);
    ASSERT_EQ(sensors.size(), static_cast<std::size_t>(kSteps)) << id;
    for (int k = 1; k <= kSteps; ++k) {
      const auto& want = expected[static_cast<std::size_t>(k - 1)][i];
      const auto got = dds::FromMsg(sensors[static_cast<std::size_t>(k - 1)]);
      EXPECT_EQ(got.lidar.stamp.step, static_cast<std::uint32_t>(k)) << id;
      EXPECT_EQ(got.lidar.stamp.robot_id, id);
      EXPECT_TRUE(SameLidar(got.lidar, want.lidar)) << id << " lidar step " << k;
      EXPECT_TRUE(SameImu(got.imu, want.imu)) << id << " imu step " << k;
      EXPECT_TRUE(SameOdometry(got.odometry, want.odometry)) << id << " odometry step " << k;
    }
  }
  const auto truth = TakeAll<decltype(truth_reader), msg::GroundTruth>(truth_reader);
  ASSERT_EQ(truth.size(), static_cast<std::size_t>(kSteps + 1));  // step 0 and every step
  for (int k = 0; k <= kSteps; ++k) {
    const auto got = dds::FromMsg(truth[static_cast<std::size_t>(k)]);
    const auto& want = expected_truth[static_cast<std::size_t>(k)];
    EXPECT_EQ(got.stamp.step, static_cast<std::uint32_t>(k));
    ASSERT_EQ(got.robots.size(), want.robots.size());
    ASSERT_EQ(got.landmarks.size(), want.landmarks.size());
    for (std::size_t j = 0; j < want.robots.size(); ++j) {
      EXPECT_EQ(got.robots[j].pose.x, want.robots[j].pose.x);
      EXPECT_EQ(got.robots[j].pose.heading, want.robots[j].pose.heading);
    }
    for (std::size_t j = 0; j < want.landmarks.size(); ++j) {
      EXPECT_EQ(got.landmarks[j].pose.y, want.landmarks[j].pose.y);
      EXPECT_EQ(got.landmarks[j].moving, want.landmarks[j].moving);
    }
  }
}

TEST(WorldSimRealtimeTest, StaggeredRobotsGetTheirDataSpreadOverTheStep) {
  // Realtime, eight robots, 200 ms steps: robot i's data are written at least i/8 of a step
  // after robot 0's (a clock that is late is never early), in every step.
  unsetenv("MRSLAM_DOMAIN");
  constexpr int kRealtimeDomain = 116;
  constexpr int kRealtimeSteps = 3;
  constexpr double kPeriodMs = 200.0;
  const std::string scenario_path = SourcePath("config/swarm_8.yaml");
  const std::vector<std::string> sets = {"run.mode=realtime", "run.dt_s=0.2", "run.realtime_factor=1"};
  const auto scenario = common::LoadScenario(scenario_path, sets);
  const testing::TempDir temp_dir("mrslam-staggered");
  dds::Participant participant({kRealtimeDomain, "staggered_test", false});
  std::vector<std::unique_ptr<dds::Reader<msg::SensorStepPubSubType>>> sensors;
  std::vector<std::unique_ptr<dds::Writer<msg::StepAckPubSubType>>> acks;
  for (const auto& r : scenario.robots) {
    sensors.push_back(std::make_unique<dds::Reader<msg::SensorStepPubSubType>>(participant, dds::SensorTopic(r.id)));
    acks.push_back(std::make_unique<dds::Writer<msg::StepAckPubSubType>>(participant, dds::AckTopic(r.id)));
  }
  std::vector<std::string> argv = {BinPath("world_sim"),
                                   "--scenario",
                                   scenario_path,
                                   "--domain",
                                   std::to_string(kRealtimeDomain),
                                   "--steps",
                                   std::to_string(kRealtimeSteps)};
  for (const auto& set : sets) argv.insert(argv.end(), {"--set", set});
  ChildProcess sim(argv, temp_dir.path() + "/world_sim.log");
  ASSERT_TRUE(sim.started());
  for (std::size_t i = 0; i < acks.size(); ++i) {
    msg::StepAck a;
    a.stamp().robot_id(scenario.robots[i].id);
    ASSERT_TRUE(acks[i]->Write(a));  // ready
  }
  // written[i][k - 1]: when robot i's sensor step k was written.
  std::vector<std::vector<std::int64_t>> written(sensors.size());
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    msg::SensorStep o;
    dds::SampleTimes times;
    while (written[i].size() < kRealtimeSteps && sensors[i]->Take(&o, seconds(20), nullptr, &times)) {
      written[i].push_back(times.written_ns);
    }
    ASSERT_EQ(written[i].size(), static_cast<std::size_t>(kRealtimeSteps))
        << testing::ReadFile(temp_dir.path() + "/world_sim.log");
  }
  ASSERT_EQ(sim.WaitExit(seconds(30)), std::optional<int>(0)) << testing::ReadFile(temp_dir.path() + "/world_sim.log");
  const double n = static_cast<double>(sensors.size());
  for (int k = 0; k < kRealtimeSteps; ++k) {
    for (std::size_t i = 1; i < sensors.size(); ++i) {
      const double after_ms = static_cast<double>(written[i][k] - written[0][k]) * 1e-6;
      // Robot 0's data leave right after the step's clock; allow it 5 ms of lateness.
      EXPECT_GE(after_ms, static_cast<double>(i) / n * kPeriodMs - 5.0) << "robot " << i << " step " << k + 1;
    }
  }
}

TEST(WorldSimLockstepTest, SilentAgentMakesTheSimulatorExitNamingIt) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-silent");
  const std::string& dir = temp_dir.path();
  ChildProcess sim({BinPath("world_sim"), "--scenario", SourcePath("config/paper_two_robots.yaml"), "--domain",
                    std::to_string(kDomain + 1), "--steps", "3", "--set", "run.ack_timeout_s=1", "--agents", "r2"},
                   dir + "/world_sim.log");
  const auto code = sim.WaitExit(seconds(20));
  ASSERT_TRUE(code.has_value());
  EXPECT_NE(*code, 0);
  EXPECT_THAT(testing::ReadFile(dir + "/world_sim.log"), ::testing::HasSubstr("agent 'r2' did not acknowledge"));
}

TEST(WorldSimLockstepTest, BadScenarioExitsNonZeroWithOneLineReason) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-bad");
  const std::string& dir = temp_dir.path();
  ChildProcess sim({BinPath("world_sim"), "--scenario", SourcePath("config/paper_two_robots.yaml"), "--set",
                    "sensors.lidar.range_noise_sd_m=-1"},
                   dir + "/world_sim.log");
  testing::ExpectOneLineError(sim, dir + "/world_sim.log", "sensors.lidar.range_noise_sd_m");
}

}  // namespace
}  // namespace mrslam
