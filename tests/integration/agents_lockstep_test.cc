// Multi-process: world_sim and two robot_agent processes complete paper_two_robots.yaml in
// lockstep; each agent publishes an estimate for every step, in order, from its own frame, and
// places the other from both histories when they meet.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>

#include <fmt/format.h>

#include "common/config/scenario_options.h"
#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"
#include "tests/integration/child_process.h"

namespace mrslam {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
using testing::BinPath;
using testing::ChildProcess;
using testing::SourcePath;

constexpr int kDomain = 113;  // this test's own DDS domain

TEST(AgentsLockstepTest, TwoAgentsPublishAnEstimateForEveryStep) {
  unsetenv("MRSLAM_DOMAIN");
  const std::string scenario_path = SourcePath("config/paper_two_robots.yaml");
  const auto scenario = common::LoadScenario(scenario_path, {});
  const testing::TempDir temp_dir("mrslam-agents");
  const std::string& dir = temp_dir.path();
  const std::vector<std::string> common_args = {
      "--scenario", scenario_path, "--domain", std::to_string(kDomain), "--set", "filter.particles=200"};

  dds::Participant participant({kDomain, "agents_test", false});
  std::map<std::string, std::unique_ptr<dds::Reader<msg::EstimatePubSubType>>> readers;
  for (const auto& r : scenario.robots) {
    readers[r.id] = std::make_unique<dds::Reader<msg::EstimatePubSubType>>(participant, dds::EstimateTopic(r.id));
  }
  std::vector<std::string> ids;
  for (const auto& r : scenario.robots) ids.push_back(r.id);
  const auto agents = testing::StartAgents(ids, common_args, dir);
  const auto sim = testing::StartBin("world_sim", common_args, dir + "/world_sim.log");

  ASSERT_EQ(sim->WaitExit(seconds(120)), std::optional<int>(0)) << testing::ReadFile(dir + "/world_sim.log");
  for (std::size_t i = 0; i < agents.size(); ++i) {
    const auto& id = scenario.robots[i].id;
    const std::string log = (std::filesystem::path(dir) / (id + ".log")).string();
    EXPECT_EQ(agents[i]->WaitExit(seconds(30)), std::optional<int>(0)) << testing::ReadFile(log);
    // The robots meet: each agent's history crossed DDS with its snapshot and the other placed
    // it by the joint estimate.
    EXPECT_THAT(testing::ReadFile(log), ::testing::HasSubstr("joint transform from both histories")) << id;
  }
  for (const auto& r : scenario.robots) {
    std::vector<std::uint32_t> steps;
    msg::Estimate e, last;
    while (readers[r.id]->Take(&e, milliseconds(500))) {
      steps.push_back(e.stamp().step());
      EXPECT_EQ(e.stamp().robot_id(), r.id);
      EXPECT_TRUE(std::isfinite(e.pose().x_m()) && std::isfinite(e.pose().y_m()));
      EXPECT_EQ(e.filter(), "fastslam");
      last = e;
    }
    ASSERT_EQ(steps.size(), static_cast<std::size_t>(scenario.run.steps)) << r.id;
    for (std::size_t k = 0; k < steps.size(); ++k) EXPECT_EQ(steps[k], k + 1) << r.id;
    // Every rendezvous of the estimate stream is in the agent's log too.
    ASSERT_FALSE(last.rendezvous().empty()) << r.id;
    const std::string log = testing::ReadFile(dir + "/" + r.id + ".log");
    for (const auto& ev : last.rendezvous()) {
      EXPECT_THAT(log, ::testing::HasSubstr(fmt::format("rendezvous with {} at step {}: T({} <- {}) = (", ev.peer_id(),
                                                        ev.step(), r.id, ev.peer_id())))
          << r.id;
    }
  }
}

TEST(AgentsLockstepTest, UnknownRobotIdIsAOneLineError) {
  const testing::TempDir temp_dir("mrslam-agent-bad");
  const std::string& dir = temp_dir.path();
  ChildProcess agent({BinPath("robot_agent"), "--scenario", SourcePath("config/paper_two_robots.yaml"), "--robot", "r9",
                      "--domain", std::to_string(kDomain + 1)},
                     dir + "/agent.log");
  testing::ExpectOneLineError(agent, dir + "/agent.log", "unknown robot id 'r9'");
}

}  // namespace
}  // namespace mrslam
