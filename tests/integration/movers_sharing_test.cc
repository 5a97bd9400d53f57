// Multi-process: smoother agents on paper_two_robots (two robots, two moving landmarks of known
// kinematics) sharing their raw measurements, against the same seeds alone. With the joint
// estimate among movers the robots end nearer the truth than alone, and stay consistent.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/integration/child_process.h"
#include "tests/integration/launch_helpers.h"

namespace mrslam {
namespace {

using std::chrono::seconds;
using testing::ChildProcess;
using testing::ReadFile;

constexpr int kSharingDomain = 114;  // this test's own DDS domains
constexpr int kAloneDomain = 115;
constexpr int kSeeds = 4;

// Runs seeds 1..kSeeds of paper_two_robots with smoother agents into out; the summaries by seed.
std::vector<nlohmann::json> RunSeeds(const std::string& out, int domain, const std::vector<std::string>& extra) {
  std::vector<std::string> args = {"--seeds", "1.." + std::to_string(kSeeds), "--no-plots", "--set",
                                   "filter.type=smoother"};
  args.insert(args.end(), extra.begin(), extra.end());
  const std::vector<std::string> argv = testing::TwoRobotLaunchArgs(out, domain, args);
  ChildProcess launcher(argv, out + ".log");
  EXPECT_EQ(launcher.WaitExit(seconds(300)), std::optional<int>(0)) << ReadFile(out + ".log");
  std::vector<nlohmann::json> summaries;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    summaries.push_back(nlohmann::json::parse(ReadFile(out + "/seed-" + std::to_string(seed) + "/summary.json")));
  }
  return summaries;
}

TEST(MoversSharingTest, RobotsThatShareEndNearerTheTruthThanAlone) {
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-movers");
  const auto sharing =
      RunSeeds(temp_dir.path() + "/sharing", kSharingDomain, {"--set", "cooperation.share_factors=true"});
  const auto alone =
      RunSeeds(temp_dir.path() + "/alone", kAloneDomain, {"--set", "rendezvous.enable_from_step=100000000"});
  ASSERT_EQ(sharing.size(), alone.size());
  // Position RMSE over every robot-seed, pooled: each robot's mean square error, averaged.
  double sharing_ms = 0.0, alone_ms = 0.0;
  for (std::size_t i = 0; i < sharing.size(); ++i) {
    for (const std::string id : {"r1", "r2"}) {
      const auto& s = sharing[i]["robots"][id];
      sharing_ms += std::pow(s["position_rmse_m"].get<double>(), 2);
      alone_ms += std::pow(alone[i]["robots"][id]["position_rmse_m"].get<double>(), 2);
      EXPECT_GT(s["mean_nees"].get<double>(), 0.0) << "seed " << i + 1 << " " << id;
      EXPECT_LT(s["mean_nees"].get<double>(), 10.0) << "seed " << i + 1 << " " << id;
    }
  }
  EXPECT_LT(std::sqrt(sharing_ms), 0.8 * std::sqrt(alone_ms))
      << std::sqrt(sharing_ms) << " against " << std::sqrt(alone_ms) << " alone";
  // The agents said so: the joint estimate among movers was solved.
  EXPECT_NE(ReadFile(temp_dir.path() + "/sharing/seed-1/logs/robot_agent_r1.log").find("joint estimate at step"),
            std::string::npos);
}

}  // namespace
}  // namespace mrslam
