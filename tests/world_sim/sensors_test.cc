#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "common/angles.h"
#include "common/se2.h"
#include "tests/world_sim/world_test_util.h"
#include "world_sim/core/world.h"

namespace mrslam::world_sim {
namespace {

using common::kPi;
using testing::QuietScenario;
using testing::StaticLandmark;
using ::testing::UnorderedElementsAre;

// A landmark at range r and bearing b from the origin facing +x.
common::LandmarkOptions At(int id, double range_m, double bearing_rad) {
  return StaticLandmark(id, range_m * std::cos(bearing_rad), range_m * std::sin(bearing_rad));
}

common::ScenarioOptions GatingScenario() {
  auto o = QuietScenario();
  o.sensors.lidar.max_range_m = 5.0;
  o.sensors.lidar.min_range_m = 0.5;
  o.sensors.lidar.fov_rad = kPi / 2.0;  // |b| <= pi/4
  const double edge = kPi / 4.0, eps = 1e-3;
  o.landmarks = {At(1, 5.0 - eps, 0.0),   At(2, 5.0 + eps, 0.0),   At(3, 0.5 - eps, 0.3),
                 At(4, 0.5 + eps, -0.3),  At(5, 3.0, edge - eps),  At(6, 3.0, edge + eps),
                 At(7, 3.0, -edge + eps), At(8, 3.0, -edge - eps), At(9, 3.0, kPi)};
  return o;
}

TEST(LidarTest, GatesOnRangeAndFieldOfView) {
  const auto o = GatingScenario();
  World world(o);
  const auto scan = world.Step()[0].lidar;
  std::vector<int> ids;
  for (const auto& d : scan.landmarks) ids.push_back(d.landmark_id);
  EXPECT_THAT(ids, UnorderedElementsAre(1, 4, 5, 7));
  for (const auto& d : scan.landmarks) {
    // Noise-free: the true range and bearing.
    const auto& l = o.landmarks[d.landmark_id - 1];
    const auto z = common::MeasureRangeBearing({}, l.pose.Translation());
    EXPECT_NEAR(d.range_m, z.range_m, 1e-12);
    EXPECT_NEAR(d.bearing_rad, z.bearing_rad, 1e-12);
  }
}

TEST(LidarTest, HidesIdentityUnlessReported) {
  auto o = GatingScenario();
  o.sensors.lidar.report_identity = false;
  World world(o);
  const auto scan = world.Step()[0].lidar;
  ASSERT_EQ(scan.landmarks.size(), 4u);
  for (const auto& d : scan.landmarks) EXPECT_EQ(d.landmark_id, -1);
}

TEST(LidarTest, DetectsOtherRobotsInRangeAndFieldOfView) {
  auto o = QuietScenario();
  o.sensors.lidar.fov_rad = kPi;  // the front half-plane
  o.sensors.lidar.robot_detection_range_m = 4.0;
  common::RobotOptions r2, r3, r4;
  r2.id = "r2";
  r2.initial_pose = {3.0, 0.0, 0.0};  // faces away from r1: sees nothing behind
  r3.id = "r3";
  r3.initial_pose = {4.5, 0.0, kPi};  // out of r1's robot range; sees r2 at 1.5 m ahead
  r4.id = "r4";
  r4.initial_pose = {-1.0, 0.0, 0.0};  // behind r1; sees r1 and r2 ahead
  o.robots.push_back(r2);
  o.robots.push_back(r3);
  o.robots.push_back(r4);
  World world(o);
  const auto sensed = world.Step();
  auto seen = [&](std::size_t i) {
    std::vector<std::string> ids;
    for (const auto& d : sensed[i].lidar.robots) ids.push_back(d.seen_robot_id);
    return ids;
  };
  EXPECT_THAT(seen(0), UnorderedElementsAre("r2"));
  EXPECT_THAT(seen(1), UnorderedElementsAre("r3"));
  EXPECT_THAT(seen(2), UnorderedElementsAre("r2"));
  EXPECT_THAT(seen(3), UnorderedElementsAre("r1", "r2"));
  const auto& d = sensed[0].lidar.robots.at(0);
  EXPECT_NEAR(d.range_m, 3.0, 1e-12);
  EXPECT_NEAR(d.bearing_rad, 0.0, 1e-12);
  EXPECT_NEAR(d.time_s, o.run.dt_s, 1e-12);
}

TEST(LidarTest, MeasurementNoiseMatchesConfiguredCovariance) {
  auto o = QuietScenario();
  o.sensors.lidar.range_noise_sd_m = 0.05;
  o.sensors.lidar.bearing_noise_sd_rad = 0.02;
  for (int i = 0; i < 8; ++i) o.landmarks.push_back(At(i + 1, 3.0, -kPi + i * kPi / 4.0 + 0.1));
  World world(o);
  std::vector<double> er, eb;
  for (int k = 0; k < 500; ++k) {
    const auto scan = world.Step()[0].lidar;
    for (const auto& d : scan.landmarks) {
      const auto& l = o.landmarks.at(d.landmark_id - 1);
      const auto z = common::MeasureRangeBearing({}, l.pose.Translation());
      er.push_back(d.range_m - z.range_m);
      eb.push_back(common::WrapAngle(d.bearing_rad - z.bearing_rad));
    }
  }
  ASSERT_EQ(er.size(), 4000u);
  EXPECT_TRUE(testing::VarianceMatches(er, 0.05 * 0.05));
  EXPECT_TRUE(testing::VarianceMatches(eb, 0.02 * 0.02));
  EXPECT_TRUE(testing::MeanMatches(er, 0.0, 0.05));
  EXPECT_TRUE(testing::MeanMatches(eb, 0.0, 0.02));
}

TEST(LidarTest, DetectionProbabilityThinsDetections) {
  auto o = QuietScenario();
  const double p = 0.7;
  o.sensors.lidar.detection_probability = p;
  for (int i = 0; i < 8; ++i) o.landmarks.push_back(At(i + 1, 2.0, i * kPi / 4.0));
  World world(o);
  const int steps = 500;
  double detected = 0.0;
  for (int k = 0; k < steps; ++k) detected += world.Step()[0].lidar.landmarks.size();
  // Binomial: |k/n - p| <= z sqrt(p (1 - p) / n).
  const double n = 8.0 * steps;
  EXPECT_NEAR(detected / n, p, testing::kZ999 * std::sqrt(p * (1.0 - p) / n));
}

TEST(LidarTest, DetectionOrderCarriesNoIdentity) {
  auto o = QuietScenario();
  for (int i = 0; i < 8; ++i) o.landmarks.push_back(At(i + 1, 2.0, i * kPi / 4.0));
  World world(o);
  std::set<std::vector<int>> orders;
  std::map<int, int> first_position_count;
  for (int k = 0; k < 200; ++k) {
    std::vector<int> ids;
    const auto scan = world.Step()[0].lidar;
    for (const auto& d : scan.landmarks) ids.push_back(d.landmark_id);
    ASSERT_THAT(ids, UnorderedElementsAre(1, 2, 3, 4, 5, 6, 7, 8));
    orders.insert(ids);
    ++first_position_count[ids[0]];
  }
  // 200 uniform shuffles of 8 items: repeats are rare and every id leads some scan.
  EXPECT_GT(orders.size(), 190u);
  EXPECT_EQ(first_position_count.size(), 8u);
}

}  // namespace
}  // namespace mrslam::world_sim
