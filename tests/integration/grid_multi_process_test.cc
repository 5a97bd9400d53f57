// The experiment grid's --multi-process mode: the same jobs run as separate processes
// (world_sim + one robot_agent per robot, over DDS, on a free domain the tool picks) score
// exactly what the in-process run scores, and the processes leave nothing behind.
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <string>
#include <vector>

#include "common/config/scenario_options.h"
#include "tests/integration/child_process.h"

namespace mrslam {
namespace {

using std::chrono::seconds;
using testing::BinPath;
using testing::ChildProcess;
using testing::SourcePath;

// The grid's rows without the last column (each run's wall time).
std::vector<std::string> RowsWithoutSeconds(const std::string& csv) {
  std::vector<std::string> rows;
  std::size_t start = 0;
  while (start < csv.size()) {
    const std::size_t end = csv.find('\n', start);
    const std::string line = csv.substr(start, end - start);
    rows.push_back(line.substr(0, line.rfind(',')));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return rows;
}

std::string RunGrid(const std::string& out, bool multi_process) {
  std::vector<std::string> argv = {BinPath("mrslam_grid"),
                                   "--scenario",
                                   SourcePath("config/dynamic_world.yaml"),
                                   "--out",
                                   out,
                                   "--runs",
                                   "2",
                                   "--frames",
                                   "40",
                                   "--dynamism",
                                   "0.5",
                                   "--speeds",
                                   "0.5",
                                   "--filters",
                                   "ekf,ekf_ela,fastslam",
                                   "--particles",
                                   "50"};
  if (multi_process) argv.push_back("--multi-process");
  ChildProcess grid(argv, out + ".log");
  EXPECT_EQ(grid.WaitExit(seconds(120)), std::optional<int>(0)) << testing::ReadFile(out + ".log");
  return testing::ReadFile(out + "/grid.csv");
}

TEST(GridMultiProcessTest, ScoresTheSameAsInProcess) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-grid");
  const std::string& dir = temp_dir.path();
  const auto in_process = RowsWithoutSeconds(RunGrid(dir + "/in", false));
  const auto multi_process = RowsWithoutSeconds(RunGrid(dir + "/mp", true));
  ASSERT_EQ(in_process.size(), 7u);  // header + 3 filters x 2 runs
  EXPECT_EQ(multi_process, in_process);
  // Every process's log is there: per run (one row each) world_sim and one robot_agent per robot.
  const auto robots = common::LoadScenario(SourcePath("config/dynamic_world.yaml"), {}).robots.size();
  std::size_t logs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir + "/mp/logs")) logs += entry.is_regular_file();
  EXPECT_EQ(logs, (in_process.size() - 1) * (1 + robots));
}

// A run whose agent dies is counted and left out; the grid goes on with the others, writes what
// it has and exits 3 naming the run.
TEST(GridMultiProcessTest, AFailedRunIsLeftOutAndTheOthersGoOn) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-grid-fails");
  const std::string& dir = temp_dir.path();
  // Long enough that the first run is still going when its agent is killed.
  ChildProcess grid(
      {BinPath("mrslam_grid"), "--scenario", SourcePath("config/dynamic_world.yaml"), "--out", dir, "--runs", "2",
       "--frames", "400", "--dynamism", "0.5", "--speeds", "0.5", "--filters", "ekf", "--multi-process"},
      dir + ".log");
  ASSERT_TRUE(grid.started());
  const auto children = testing::WaitForChildren(grid.pid(), 4, seconds(30));
  const pid_t victim = testing::FindProcess(children, {"robot_agent", "--robot r2", "--seed 1 "});
  ASSERT_NE(victim, 0) << testing::ReadFile(dir + ".log");
  const auto groups = testing::GroupsOf(children);
  ASSERT_EQ(kill(victim, SIGKILL), 0);

  EXPECT_EQ(grid.WaitExit(seconds(120)), std::optional<int>(3)) << testing::ReadFile(dir + ".log");
  const std::string log = testing::ReadFile(dir + ".log");
  EXPECT_NE(log.find("run 1 of ekf at dynamism 0.5, speed 0.5 m/s failed"), std::string::npos) << log;
  EXPECT_NE(log.find("1 of 2 runs failed"), std::string::npos) << log;
  EXPECT_TRUE(testing::NoneLeft(children, groups));
  const auto rows = RowsWithoutSeconds(testing::ReadFile(dir + "/grid.csv"));
  ASSERT_EQ(rows.size(), 2u);  // header + run 2
  EXPECT_EQ(rows[1].rfind("ekf,0.5,0.5,2,", 0), 0u) << rows[1];
  EXPECT_NE(testing::ReadFile(dir + "/tables.md").find("1 of 2 runs failed and are left out of the means"),
            std::string::npos);
  std::filesystem::remove(dir + ".log");
}

}  // namespace
}  // namespace mrslam
