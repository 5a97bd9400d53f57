// mrslam_batch's references on a scenario whose landmarks come from a landmark_field (swarm_8):
// they know the field's static landmarks. --transform-reference's JSON holds each met pair's
// transform per seed, the one its error is measured of; --smoother's the frames it places.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/angles.h"
#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "tests/integration/child_process.h"

namespace mrslam {
namespace {

using std::chrono::seconds;
using testing::BinPath;
using testing::ChildProcess;
using testing::SourcePath;

// mrslam_batch on a scenario (swarm_8 unless said), seed 1, with the given steps and mode flag;
// its JSON (empty, and the test failed, if it did not exit 0).
nlohmann::json RunBatch(int steps, const std::string& mode, const std::string& scenario = "config/swarm_8.yaml",
                        const std::vector<std::string>& more = {}) {
  const testing::TempDir temp_dir("mrslam-batch");
  const std::string json_path = temp_dir.path() + "/batch.json";
  const std::string log = temp_dir.path() + "/batch.log";
  std::vector<std::string> argv = {BinPath("mrslam_batch"),
                                   "--scenario",
                                   SourcePath(scenario),
                                   "--seeds",
                                   "1..1",
                                   "--set",
                                   "run.steps=" + std::to_string(steps),
                                   mode,
                                   "--json",
                                   json_path};
  argv.insert(argv.end(), more.begin(), more.end());
  ChildProcess batch(argv, log);
  const std::optional<int> exit_code = batch.WaitExit(seconds(300));
  EXPECT_EQ(exit_code, std::optional<int>(0)) << testing::ReadFile(log);
  return exit_code == std::optional<int>(0) ? nlohmann::json::parse(testing::ReadFile(json_path)) : nlohmann::json{};
}

TEST(BatchTransformReferenceTest, PlacesAMetPairOnALandmarkField) {
  // Seed 1's r1 and r2 meet at step 4.
  const nlohmann::json json = RunBatch(20, "--transform-reference");
  ASSERT_TRUE(json.contains("pairs"));
  const auto& pair = json.at("pairs").at("r1<-r2");
  ASSERT_EQ(pair.at("seeds").get<std::vector<std::uint64_t>>(), std::vector<std::uint64_t>{1});
  const auto t = pair.at("joint_transform").at(0).get<std::array<double, 3>>();
  const auto scenario = common::LoadScenario(SourcePath("config/swarm_8.yaml"), {});
  const common::Pose2 truth = common::Between(scenario.robots[0].frame_in_world, scenario.robots[1].frame_in_world);
  const double error_m = std::hypot(t[0] - truth.x, t[1] - truth.y);
  const double error_deg = common::DegFromRad(std::abs(common::WrapAngle(t[2] - truth.heading)));
  EXPECT_LT(error_m, 0.2);
  EXPECT_LT(error_deg, 2.0);
  EXPECT_NEAR(pair.at("joint_error_m").at(0).get<double>(), error_m, 1e-9);
  EXPECT_NEAR(pair.at("joint_error_deg").at(0).get<double>(), error_deg, 1e-9);
  // The reverse pair holds the inverse transform.
  const auto back = json.at("pairs").at("r2<-r1").at("joint_transform").at(0).get<std::array<double, 3>>();
  const common::Pose2 composed = common::Compose({t[0], t[1], t[2]}, {back[0], back[1], back[2]});
  EXPECT_NEAR(composed.x, 0.0, 1e-9);
  EXPECT_NEAR(composed.y, 0.0, 1e-9);
  EXPECT_NEAR(common::WrapAngle(composed.heading), 0.0, 1e-9);
}

// --smoother on the same field: the JSON holds each seed's frames as the joint smoother of every
// robot's data places them in the first robot's frame.
TEST(BatchSmootherTest, PlacesEveryFrameOnALandmarkField) {
  const nlohmann::json json = RunBatch(40, "--smoother");
  ASSERT_TRUE(json.contains("joint_frames"));
  const auto frames = json.at("joint_frames").at("1").get<std::vector<std::array<double, 3>>>();
  const auto scenario = common::LoadScenario(SourcePath("config/swarm_8.yaml"), {});
  ASSERT_EQ(frames.size(), scenario.robots.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const common::Pose2 truth = common::Between(scenario.robots[0].frame_in_world, scenario.robots[i].frame_in_world);
    EXPECT_LT(std::hypot(frames[i][0] - truth.x, frames[i][1] - truth.y), 0.5) << scenario.robots[i].id;
    EXPECT_LT(common::DegFromRad(std::abs(common::WrapAngle(frames[i][2] - truth.heading))), 5.0)
        << scenario.robots[i].id;
  }
}

// --slip-recovery judges the step 30 steps after the first landmark reading that follows the
// slip; a slip of nothing is recovered from, a real one leaves a larger error than the same seed
// without it.
TEST(BatchSlipRecoveryTest, JudgesTheStepAfterTheNextReading) {
  const nlohmann::json none =
      RunBatch(150, "--slip-recovery", "config/slip.yaml", {"--set", "robots.0.slips.0.displacement=[0.0, 0.0, 0.0]"});
  ASSERT_TRUE(none.contains("robots"));
  const auto& r1 = none.at("robots").at("r1");
  EXPECT_EQ(r1.at("slip_step").get<int>(), 83);
  EXPECT_EQ(r1.at("judged_step").at(0).get<int>(), 84 + 30);  // the field is dense: a reading at 84
  EXPECT_EQ(r1.at("recovered").get<int>(), 1);
  EXPECT_DOUBLE_EQ(r1.at("error_m").at(0).get<double>(), r1.at("error_without_slip_m").at(0).get<double>());
  const nlohmann::json slipped = RunBatch(150, "--slip-recovery", "config/slip.yaml");
  const auto& s1 = slipped.at("robots").at("r1");
  EXPECT_GT(s1.at("error_m").at(0).get<double>(), s1.at("error_without_slip_m").at(0).get<double>());
  EXPECT_FALSE(slipped.at("robots").contains("r2"));  // r2 does not slip
}

}  // namespace
}  // namespace mrslam
