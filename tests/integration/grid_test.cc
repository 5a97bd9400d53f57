// The experiment grid (mrslam_grid). Its --multi-process mode: the same jobs run as separate
// processes (world_sim + one robot_agent per robot, over DDS, on a free domain the tool picks)
// score exactly what the in-process run scores, and the processes leave nothing behind. Its
// ekf_oracle: the ekf without the movers' detections.
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <sstream>
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

// A CSV row's fields.
std::vector<std::string> Fields(const std::string& row) {
  std::vector<std::string> fields;
  std::stringstream in(row);
  std::string field;
  while (std::getline(in, field, ',')) fields.push_back(field);
  return fields;
}

// mrslam_grid on paper B's world, writing to out, with more arguments.
std::vector<std::string> GridArgs(const std::string& out, const std::vector<std::string>& more) {
  std::vector<std::string> argv = {BinPath("mrslam_grid"), "--scenario", SourcePath("config/dynamic_world.yaml"),
                                   "--out", out};
  argv.insert(argv.end(), more.begin(), more.end());
  return argv;
}

std::string RunGrid(const std::string& out, bool multi_process) {
  std::vector<std::string> argv = GridArgs(out, {"--runs", "2", "--frames", "40", "--dynamism", "0.5", "--speeds",
                                                 "0.5", "--filters", "ekf,ekf_ela,fastslam", "--particles", "50"});
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
  ChildProcess grid(GridArgs(dir, {"--runs", "2", "--frames", "400", "--dynamism", "0.5", "--speeds", "0.5",
                                   "--filters", "ekf", "--multi-process"}),
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

// ekf_oracle is the ekf fed the static landmarks' detections only: without movers it scores
// exactly what the ekf scores; among movers its map holds no stale copies of them. It runs
// in-process only.
TEST(GridTest, OracleIsTheEkfWithoutTheMoversDetections) {
  const testing::TempDir temp_dir("mrslam-grid-oracle");
  const std::string& dir = temp_dir.path();
  ChildProcess grid(GridArgs(dir, {"--runs", "2", "--frames", "40", "--dynamism", "0", "0.5", "--speeds", "0.1",
                                   "--filters", "ekf,ekf_oracle"}),
                    dir + "/grid.log");
  ASSERT_EQ(grid.WaitExit(seconds(120)), std::optional<int>(0)) << testing::ReadFile(dir + "/grid.log");
  const auto rows = RowsWithoutSeconds(testing::ReadFile(dir + "/grid.csv"));
  ASSERT_EQ(rows.size(), 9u);  // header + 2 cells x 2 runs x 2 filters, ekf then ekf_oracle per run
  for (std::size_t r = 1; r < rows.size(); r += 2) {
    std::vector<std::string> ekf = Fields(rows[r]), oracle = Fields(rows[r + 1]);
    ASSERT_EQ(ekf[0], "ekf");
    ASSERT_EQ(oracle[0], "ekf_oracle");
    if (ekf[1] == "0") {
      ekf.erase(ekf.begin());
      oracle.erase(oracle.begin());
      EXPECT_EQ(oracle, ekf);  // no movers: the same scans, the same filter
    } else {
      EXPECT_LT(std::stod(oracle[4]), 0.5 * std::stod(ekf[4])) << rows[r] << "\n" << rows[r + 1];  // landmark RMSE
    }
  }

  ChildProcess multi(GridArgs(dir + "/mp", {"--filters", "ekf_oracle", "--multi-process"}), dir + "/mp.log");
  testing::ExpectOneLineError(multi, dir + "/mp.log", "ekf_oracle runs in-process only");
}

}  // namespace
}  // namespace mrslam
