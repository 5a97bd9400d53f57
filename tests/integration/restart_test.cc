// Multi-process: with --restart, an agent killed with SIGKILL in the middle of a lockstep run is
// started again by the launcher, restores its latest snapshot, rejoins the run, and the run ends
// with the same numbers as an uninterrupted run of the same seed; the summary counts the restart.
// The DDS history is shorter than the step of the kill: only the snapshot can bring it back.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <signal.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/integration/child_process.h"
#include "tests/integration/launch_helpers.h"

namespace mrslam {
namespace {

using std::chrono::seconds;
using testing::ChildProcess;
using testing::FindProcess;
using ::testing::HasSubstr;
using testing::ReadFile;
using testing::WaitForChildren;

// This test's own DDS domains.
constexpr int kPlainDomain = 100;
constexpr int kRestartDomain = 101;

constexpr int kSteps = 150;
constexpr std::uint32_t kKillAfterStep = 25;

std::vector<std::string> LaunchArgs(const std::string& out, int domain, const std::vector<std::string>& extra) {
  std::vector<std::string> args = {"--no-plots",
                                   "--set",
                                   "run.steps=" + std::to_string(kSteps),
                                   "--set",
                                   "run.snapshot_every_steps=10",
                                   "--set",
                                   "run.history_steps=12"};
  args.insert(args.end(), extra.begin(), extra.end());
  return testing::TwoRobotLaunchArgs(out, domain, args);
}

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, false);
}

// The summary's numbers without what differs between any two runs (times, domain, restarts).
nlohmann::json Numbers(nlohmann::json summary) {
  for (const char* key :
       {"wall_seconds", "evaluator_wall_seconds", "dds_domain", "cpu_seconds", "cpu_cores_mean", "peak_rss_mib"})
    summary.erase(key);
  for (auto& [id, robot] : summary["robots"].items()) {
    // The peer traffic too: a restarted agent sends again what it sent after its snapshot.
    for (const char* key : {"step_cpu_ms_median", "step_cpu_ms_p99", "latency_us_median", "latency_us_p99",
                            "estimate_hop_us_median", "data_hop_us_median", "agent_overhead_us_median", "restarts",
                            "restart_comeback_s", "peer_bytes_sent_per_s", "peer_bytes_received_per_s"})
      robot.erase(key);
  }
  return summary;
}

TEST(RestartTest, AKilledAgentComesBackAndTheRunEqualsAnUninterruptedOne) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-restart");
  const std::string plain_out = temp_dir.path() + "/plain";
  const std::string restart_out = temp_dir.path() + "/restart";
  ChildProcess plain(LaunchArgs(plain_out, kPlainDomain, {}), temp_dir.path() + "/plain.log");
  ChildProcess restarted(LaunchArgs(restart_out, kRestartDomain, {"--restart", "2"}), temp_dir.path() + "/restart.log");
  ASSERT_TRUE(plain.started());
  ASSERT_TRUE(restarted.started());
  ASSERT_TRUE(testing::WaitForEstimateStep(kRestartDomain, "r2", kKillAfterStep, restarted, seconds(120)))
      << ReadFile(temp_dir.path() + "/restart.log");
  const auto children = WaitForChildren(restarted.pid(), 4, seconds(10));
  const pid_t victim = FindProcess(children, {"robot_agent", "--robot r2"});
  ASSERT_NE(victim, 0);
  ASSERT_EQ(kill(victim, SIGKILL), 0);

  ASSERT_EQ(restarted.WaitExit(seconds(300)), std::optional<int>(0)) << ReadFile(temp_dir.path() + "/restart.log");
  ASSERT_EQ(plain.WaitExit(seconds(300)), std::optional<int>(0)) << ReadFile(temp_dir.path() + "/plain.log");
  const std::string output = ReadFile(temp_dir.path() + "/restart.log");
  EXPECT_THAT(output, HasSubstr("robot_agent_r2"));
  EXPECT_THAT(output, HasSubstr("restarting it (restart 1 of 2)"));
  EXPECT_THAT(ReadFile(restart_out + "/logs/robot_agent_r2.log"), HasSubstr("restored the snapshot of step"));
  EXPECT_FALSE(std::filesystem::exists(restart_out + "/snapshots")) << "the snapshots outlive the run";

  const auto summary = ReadJson(restart_out + "/summary.json");
  ASSERT_TRUE(summary.is_object());
  EXPECT_EQ(summary["robots"]["r2"]["restarts"], 1);
  EXPECT_EQ(summary["robots"]["r1"]["restarts"], 0);
  EXPECT_EQ(summary["robots"]["r2"]["restart_comeback_s"].size(), 1u);  // it came back
  EXPECT_TRUE(summary["robots"]["r1"]["restart_comeback_s"].empty());
  EXPECT_THAT(output, HasSubstr("robot_agent_r2 is back at step"));
  EXPECT_EQ(summary["robots"]["r2"]["steps_scored"], kSteps);
  EXPECT_EQ(Numbers(summary), Numbers(ReadJson(plain_out + "/summary.json")));
  const std::string metrics = ReadFile(restart_out + "/metrics.csv");
  EXPECT_FALSE(metrics.empty());
  EXPECT_EQ(metrics, ReadFile(plain_out + "/metrics.csv")) << "the per-step numbers differ";
}

}  // namespace
}  // namespace mrslam
