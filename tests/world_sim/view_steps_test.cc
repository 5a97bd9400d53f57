#include "world_sim/evaluator/view_steps.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace mrslam::evaluator {
namespace {

using nlohmann::json;

common::GroundTruth TruthAt(std::uint32_t step) {
  common::GroundTruth truth;
  truth.stamp.step = step;
  truth.stamp.time_s = 0.5 * step;
  truth.robots = {{"r1", {1.0 + step, 2.0, 0.5}, false}};
  truth.landmarks = {{"7", {3.0, -1.0, 0.0}, true}};
  return truth;
}

RobotEstimate EstimateAt(std::uint32_t step) {
  RobotEstimate e;
  e.step = step;
  e.time_s = 0.5 * step;
  e.pose = {0.1 * step, -0.2, 0.3};
  e.covariance << 0.04, 0.01, 0.0, 0.01, 0.09, 0.0, 0.0, 0.0, 0.0025;
  MapLandmark l;
  l.position_m = {2.0, 3.0};
  l.covariance_m2 << 0.5, 0.1, 0.1, 0.25;
  l.landmark_id = 7;
  l.moving = true;
  l.heading_rad = 1.0;
  l.v_mps = 0.4;
  e.shown_landmarks = {l};
  e.frames_known = {"r2"};
  e.rendezvous = {{"r2", 3, {}}};
  e.rejected_samples = 2;
  e.step_cpu_ms = 1.25;
  return e;
}

TEST(ViewStepsTest, HeaderNamesEveryRobotAndThePoseOfItsFrameInTheWorld) {
  common::ScenarioOptions scenario;
  scenario.name = "s";
  scenario.run.steps = 12;
  scenario.robots.resize(2);
  scenario.robots[0].id = "r1";
  scenario.robots[1].id = "r2";
  scenario.robots[1].frame_in_world = {0.347, 2.209, -0.6194};
  const json header = ViewHeader(scenario);
  EXPECT_EQ(header["scenario"], "s");
  EXPECT_EQ(header["steps"], 12);
  ASSERT_EQ(header["robots"].size(), 2U);
  EXPECT_EQ(header["robots"][1]["id"], "r2");
  EXPECT_EQ(header["robots"][1]["frame"], json::array({0.347, 2.209, -0.6194}));
}

TEST(ViewStepsTest, StepHoldsTheTruthEstimatesMapsAndScans) {
  const common::GroundTruth truth = TruthAt(4);
  const RobotEstimate estimate = EstimateAt(4);
  common::LidarScan scan;
  scan.landmarks = {{2.0, 1.5, 0.25, -1}};
  ViewStepInput input;
  input.step = 4;
  input.time_s = 2.0;
  input.truth = &truth;
  input.estimates = {{"r1", &estimate}, {"r2", nullptr}};
  input.scans = {{"r1", &scan}};
  const json step = ViewStep(input);
  EXPECT_EQ(step["step"], 4);
  EXPECT_EQ(step["truth"]["step"], 4);
  EXPECT_EQ(step["truth"]["robots"]["r1"], json::array({5.0, 2.0, 0.5}));
  EXPECT_EQ(step["truth"]["landmarks"][0], json::array({"7", 3.0, -1.0, 1}));
  const json& r1 = step["estimates"]["r1"];
  EXPECT_FALSE(step["estimates"].contains("r2"));  // no estimate yet
  EXPECT_EQ(r1["pose"], json::array({0.4, -0.2, 0.3}));
  EXPECT_EQ(r1["cov"], json::array({0.04, 0.01, 0.09, 0.0025}));
  EXPECT_EQ(r1["landmarks"][0], json::array({2.0, 3.0, 0.5, 0.1, 0.25, 1, 1.0, 0.4, 7}));
  EXPECT_EQ(r1["frames_known"], json::array({"r2"}));
  EXPECT_EQ(r1["rendezvous"][0], json::array({"r2", 3}));
  EXPECT_EQ(r1["rejected"], 2);
  EXPECT_EQ(r1["cpu_ms"], 1.25);
  EXPECT_EQ(step["lidar"]["r1"][0], json::array({1.5, 0.25}));  // range, bearing
}

TEST(ViewStepsTest, NumbersKeepSixSignificantDigits) {
  RobotEstimate estimate = EstimateAt(1);
  estimate.pose = {123.456789, 1.23456789e-5, -0.333333333};
  ViewStepInput input;
  input.estimates = {{"r1", &estimate}};
  EXPECT_EQ(ViewStep(input)["estimates"]["r1"]["pose"], json::array({123.457, 1.23457e-5, -0.333333}));
  EXPECT_TRUE(ViewStep(input)["truth"].is_null());
}

}  // namespace
}  // namespace mrslam::evaluator
