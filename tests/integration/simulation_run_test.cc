// One run's processes as the launcher and the grid start and supervise them: the command lines
// and how a supervised run ends (with stand-in processes: /bin/sh).
#include "scripts/launch/simulation_run.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
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
  RunEnd Supervise(const RunLimits& limits) {
    return SuperviseRun(&children_, limits, stop_, [this] {
      ++ticks_;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    });
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

}  // namespace
}  // namespace mrslam::launch
