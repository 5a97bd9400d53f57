// One run's processes as the launcher and the grid start and supervise them: the command lines
// and how a supervised run ends (with stand-in processes: /bin/sh).
#include "scripts/launch/simulation_run.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace mrslam::launch {
namespace {

using ::testing::ElementsAre;

// A stand-in child: /bin/sh -c script.
std::vector<std::string> Shell(const std::string& script) { return {"/bin/sh", "-c", script}; }

class SimulationRunTest : public ::testing::Test {
 protected:
  SimulationRunTest()
      : dir_(std::filesystem::temp_directory_path() / ("simulation_run_test_" + std::to_string(getpid()))) {
    std::filesystem::create_directories(dir_);
  }
  ~SimulationRunTest() override {
    children_.StopAll(std::chrono::seconds(1));
    std::filesystem::remove_all(dir_);
  }
  void Start(const std::string& name, const std::string& script) {
    children_.Start(name, Shell(script), (dir_ / (name + ".log")).string());
  }
  RunEnd Supervise(const RunLimits& limits, const RestartPolicy& restart = {}) {
    return SuperviseRun(
        &children_, limits, stop_,
        [this] {
          ++ticks_;
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
        },
        restart);
  }
  // A stand-in agent that fails (exit 3) the first `failures` times it runs, then ends well;
  // each run appends a line to its log.
  std::string FailingAgent(int failures) const {
    const std::string count = (dir_ / "runs").string();
    return "n=$(cat " + count + " 2>/dev/null || echo 0); echo $((n + 1)) > " + count + "; echo run $n; [ $n -ge " +
           std::to_string(failures) + " ] && exit 0; exit 3";
  }

  std::filesystem::path dir_;
  ProcessSupervisor children_;
  std::atomic<bool> stop_{false};
  int ticks_ = 0;
};

TEST(ChildCommandTest, TheRunsFlagsThenTheExtraOnes) {
  const RunArgs run{"s.yaml", 7, 3, {"a=1", "b=2"}, true, "debug"};
  const std::vector<std::string> argv = ChildCommand(run, "world_sim", {"--wait-readers", "1"});
  EXPECT_EQ(argv.front(), ExecutableDir() + "/world_sim");
  EXPECT_THAT(std::vector<std::string>(argv.begin() + 1, argv.end()),
              ElementsAre("--scenario", "s.yaml", "--domain", "7", "--seed", "3", "--set", "a=1", "--set", "b=2",
                          "--shm", "--log-level", "debug", "--wait-readers", "1"));
  const std::vector<std::string> plain = ChildCommand({"s.yaml", 7, 3, {}, false, ""}, "evaluator", {});
  EXPECT_THAT(std::vector<std::string>(plain.begin() + 1, plain.end()),
              ElementsAre("--scenario", "s.yaml", "--domain", "7", "--seed", "3"));
}

TEST_F(SimulationRunTest, DoneWhenEveryChildHasEndedWell) {
  Start("world_sim", "exit 0");
  Start("robot_agent_r1", "sleep 0.2");
  EXPECT_EQ(Supervise({}).kind, RunEnd::Kind::kDone);
  EXPECT_GT(ticks_, 0);
  EXPECT_EQ(children_.running(), 0);
}

TEST_F(SimulationRunTest, TheFirstFailureEndsTheSupervision) {
  Start("robot_agent_r1", "exit 3");
  Start("world_sim", "sleep 30");
  const RunEnd end = Supervise({});
  ASSERT_EQ(end.kind, RunEnd::Kind::kFailed);
  ASSERT_TRUE(end.failure.has_value());
  EXPECT_EQ(end.failure->name, "robot_agent_r1");
  EXPECT_EQ(end.failure->exit_code, 3);
  EXPECT_THAT(children_.RunningNames(), ElementsAre("world_sim"));  // left for the caller to stop
}

TEST_F(SimulationRunTest, TimeoutsAndStop) {
  Start("world_sim", "sleep 30");
  EXPECT_EQ(Supervise({std::chrono::steady_clock::now(), 0.2}).kind, RunEnd::Kind::kTimedOut);
  stop_ = true;
  EXPECT_EQ(Supervise({}).kind, RunEnd::Kind::kStopped);
}

TEST_F(SimulationRunTest, TheOthersMustFinishSoonAfterTheSimulator) {
  Start("world_sim", "exit 0");
  Start("robot_agent_r1", "sleep 30");
  EXPECT_EQ(Supervise({std::chrono::steady_clock::now(), 0.0, std::chrono::seconds(0)}).kind,
            RunEnd::Kind::kDrainTimedOut);
}

TEST_F(SimulationRunTest, ADeadAgentIsRestartedWithTheSameCommandUpToTheLimit) {
  Start("robot_agent_r1", FailingAgent(2));
  Start("world_sim", "sleep 3");
  std::vector<int> told;
  const RunEnd end = Supervise({}, {2,
                                    [&](const ChildExit& e, int n) {
                                      EXPECT_EQ(e.name, "robot_agent_r1");
                                      EXPECT_EQ(e.exit_code, 3);
                                      told.push_back(n);
                                    },
                                    nullptr});
  EXPECT_EQ(end.kind, RunEnd::Kind::kDone);
  EXPECT_THAT(told, ElementsAre(1, 2));
  EXPECT_EQ(end.restarts.at("robot_agent_r1"), 2);
  // The restarted agent's output follows the dead one's in the same log.
  EXPECT_EQ(TailOfFile((dir_ / "robot_agent_r1.log").string(), 10), "run 0\nrun 1\nrun 2\n");
}

TEST_F(SimulationRunTest, AnAgentDeadOnceMoreThanTheLimitFailsTheRun) {
  Start("robot_agent_r1", FailingAgent(2));
  Start("world_sim", "sleep 30");
  const RunEnd end = Supervise({}, {1, nullptr, nullptr});
  ASSERT_EQ(end.kind, RunEnd::Kind::kFailed);
  EXPECT_EQ(end.failure->name, "robot_agent_r1");
  EXPECT_EQ(end.restarts.at("robot_agent_r1"), 1);
}

TEST_F(SimulationRunTest, OnlyAgentsAreRestartedAndOnlyWhileTheSimulatorRuns) {
  Start("evaluator", "exit 4");
  Start("world_sim", "sleep 30");
  RunEnd end = Supervise({}, {3, nullptr, nullptr});
  ASSERT_EQ(end.kind, RunEnd::Kind::kFailed);
  EXPECT_EQ(end.failure->name, "evaluator");
  EXPECT_TRUE(end.restarts.empty());
  children_.StopAll(std::chrono::seconds(1));

  Start("world_sim", "exit 0");
  Start("robot_agent_r2", "sleep 0.3; exit 5");
  end = Supervise({}, {3, nullptr, nullptr});
  ASSERT_EQ(end.kind, RunEnd::Kind::kFailed);
  EXPECT_EQ(end.failure->name, "robot_agent_r2");
  EXPECT_TRUE(end.restarts.empty());
}

TEST_F(SimulationRunTest, AnAgentsDeathTheCallerLetsGoIsNeitherRestartedNorAFailure) {
  Start("robot_agent_r1", "kill -9 $$");
  Start("world_sim", "sleep 0.5");
  RestartPolicy policy{1, [](const ChildExit&, int) { ADD_FAILURE() << "restarted"; },
                       [](const ChildExit& e) {
                         EXPECT_EQ(e.signal, 9);
                         return true;
                       }};
  const RunEnd end = Supervise({}, policy);
  EXPECT_EQ(end.kind, RunEnd::Kind::kDone);
  EXPECT_TRUE(end.restarts.empty());
}

TEST(ProcessSupervisorTest, OnlyAnEndedChildCanBeRestarted) {
  ProcessSupervisor children;
  EXPECT_THROW(children.Restart("robot_agent_r1"), std::runtime_error);
  children.Start("robot_agent_r1", {"/bin/sh", "-c", "sleep 30"}, "/dev/null");
  EXPECT_THROW(children.Restart("robot_agent_r1"), std::runtime_error);
}

}  // namespace
}  // namespace mrslam::launch
