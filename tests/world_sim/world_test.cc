#include "world_sim/core/world.h"

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "common/angles.h"
#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "tests/test_paths.h"
#include "tests/world_sim/world_test_util.h"

namespace mrslam::world_sim {
namespace {

using common::kPi;
using testing::QuietScenario;
using testing::StaticLandmark;

// Floating-point noise of a few hundred composed steps; not a statistical tolerance.
constexpr double kExact = 1e-9;

std::string SourceDir() { return mrslam::testing::SourcePath("."); }

// Circumcentre of three points.
Eigen::Vector2d Circumcentre(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const double d = 2.0 * (a.x() * (b.y() - c.y()) + b.x() * (c.y() - a.y()) + c.x() * (a.y() - b.y()));
  const double a2 = a.squaredNorm(), b2 = b.squaredNorm(), c2 = c.squaredNorm();
  return {(a2 * (b.y() - c.y()) + b2 * (c.y() - a.y()) + c2 * (a.y() - b.y())) / d,
          (a2 * (c.x() - b.x()) + b2 * (a.x() - c.x()) + c2 * (b.x() - a.x())) / d};
}

// Every number and string a step produced, printed exactly: equal text <=> identical streams.
std::string Dump(const std::vector<common::SensorStep>& steps, const common::GroundTruth& truth) {
  std::ostringstream s;
  s << std::hexfloat;
  for (const auto& st : steps) {
    s << st.lidar.stamp.robot_id << st.lidar.stamp.step << ' ' << st.lidar.stamp.time_s << '\n';
    for (const auto& d : st.lidar.landmarks) {
      s << d.time_s << ' ' << d.range_m << ' ' << d.bearing_rad << ' ' << d.landmark_id << '\n';
    }
    for (const auto& d : st.lidar.robots) {
      s << d.time_s << ' ' << d.range_m << ' ' << d.bearing_rad << ' ' << d.seen_robot_id << '\n';
    }
    for (const auto& r : st.imu.readings) {
      s << r.time_s << ' ' << r.gyro_z_radps << ' ' << r.accel_x_mps2 << ' ' << r.accel_y_mps2 << '\n';
    }
    for (const auto& o : st.odometry.segments) {
      s << o.time_s << ' ' << o.dt_s << ' ' << o.v_mps << ' ' << o.w_radps << '\n';
    }
  }
  for (const auto* list : {&truth.robots, &truth.landmarks}) {
    for (const auto& e : *list) {
      s << e.id << ' ' << e.pose.x << ' ' << e.pose.y << ' ' << e.pose.heading << ' ' << e.moving << '\n';
    }
  }
  return s.str();
}

std::string RunAndDump(const common::ScenarioOptions& options, int steps) {
  World world(options);
  std::string out;
  for (int k = 0; k < steps; ++k) {
    const auto sensed = world.Step();
    out += Dump(sensed, world.Truth());
  }
  return out;
}

TEST(WorldTest, NoiselessUnicycleRunsOnTheClosedFormCircle) {
  auto o = QuietScenario();
  const double v = 1.0, w = 0.5, dt = o.run.dt_s;
  o.robots[0].initial_pose = {1.0, -2.0, 0.3};
  o.robots[0].control.v_mps = v;
  o.robots[0].control.w_radps = w;
  World world(o);
  std::vector<Eigen::Vector2d> points{o.robots[0].initial_pose.Translation()};
  for (int k = 0; k < 300; ++k) {
    world.Step();
    points.push_back(world.Truth().robots[0].pose.Translation());
  }
  // Each step is a chord of length v dt turning by w dt: the circle through the visited points
  // has radius R = v dt / (2 sin(w dt / 2)) and a fixed centre.
  const double radius = v * dt / (2.0 * std::sin(w * dt / 2.0));
  const Eigen::Vector2d centre = Circumcentre(points[0], points[1], points[2]);
  for (std::size_t k = 0; k < points.size(); ++k) {
    EXPECT_NEAR((points[k] - centre).norm(), radius, kExact) << "point " << k;
  }
  const std::size_t n = points.size();
  EXPECT_LT((Circumcentre(points[n - 3], points[n - 2], points[n - 1]) - centre).norm(), kExact);
  EXPECT_NEAR(world.Truth().robots[0].pose.heading, common::WrapAngle(0.3 + 300 * w * dt), kExact);
}

TEST(WorldTest, ProcessNoiseMatchesConfiguredCovariance) {
  auto o = QuietScenario();
  o.robots[0].control.v_mps = 0.8;
  o.robots[0].control.w_radps = -0.3;
  o.noise.robot_process_var = {0.01, 0.02, 0.005};
  World world(o);
  std::vector<double> ex, ey, eh;
  common::Pose2 previous = o.robots[0].initial_pose;
  for (int k = 0; k < 2000; ++k) {
    world.Step();
    const common::Pose2 now = world.Truth().robots[0].pose;
    // n_k = x_k - f(x_{k-1}, u_k).
    const common::Pose2 predicted = common::UnicycleStep(previous, 0.8, -0.3, o.run.dt_s);
    ex.push_back(now.x - predicted.x);
    ey.push_back(now.y - predicted.y);
    eh.push_back(common::WrapAngle(now.heading - predicted.heading));
    previous = now;
  }
  EXPECT_TRUE(testing::VarianceMatches(ex, 0.01));
  EXPECT_TRUE(testing::VarianceMatches(ey, 0.02));
  EXPECT_TRUE(testing::VarianceMatches(eh, 0.005));
  EXPECT_TRUE(testing::MeanMatches(ex, 0.0, 0.1));
}

TEST(WorldTest, ScheduleRunsSegmentsBackToBackThenStops) {
  auto o = QuietScenario();
  auto& c = o.robots[0].control;
  c.type = common::ControlType::kSchedule;
  c.segments = {{1.0, 0.0, 0.5}, {0.0, 1.0, 0.3}};
  World world(o);
  for (int k = 1; k <= 12; ++k) {
    const auto sensed = world.Step();
    ASSERT_EQ(sensed[0].odometry.segments.size(), 1u);
    const auto& seg = sensed[0].odometry.segments[0];
    // Steps 1-5 cover [0, 0.5) s, steps 6-8 [0.5, 0.8) s, then the robot stands still.
    const double v = k <= 5 ? 1.0 : 0.0, w = (k >= 6 && k <= 8) ? 1.0 : 0.0;
    EXPECT_DOUBLE_EQ(seg.v_mps, v) << "step " << k;
    EXPECT_DOUBLE_EQ(seg.w_radps, w) << "step " << k;
    EXPECT_NEAR(seg.time_s, (k - 1) * o.run.dt_s, kExact);
    EXPECT_DOUBLE_EQ(seg.dt_s, o.run.dt_s);
  }
  const common::Pose2 end = world.Truth().robots[0].pose;
  EXPECT_NEAR(end.x, 0.5, kExact);
  EXPECT_NEAR(end.y, 0.0, kExact);
  EXPECT_NEAR(end.heading, 0.3, kExact);
}

TEST(WorldTest, ASlipMovesTheTruePoseButNotTheOdometry) {
  auto o = QuietScenario();
  auto& c = o.robots[0].control;
  c.type = common::ControlType::kSchedule;
  c.segments = {{1.0, 0.0, 0.3}};  // 3 steps forward, then standing still
  o.robots[0].slips = {{5, {1.0, 0.5, common::kPi / 4}}};
  World world(o);
  for (int k = 1; k <= 8; ++k) {
    const auto sensed = world.Step();
    const common::Pose2 pose = world.Truth().robots[0].pose;
    EXPECT_DOUBLE_EQ(sensed[0].odometry.segments[0].v_mps, k <= 3 ? 1.0 : 0.0) << "step " << k;
    EXPECT_DOUBLE_EQ(sensed[0].odometry.segments[0].w_radps, 0.0) << "step " << k;
    // From (0.3, 0, 0): 1 m forward, 0.5 m left and 45 degrees at the end of step 5.
    EXPECT_NEAR(pose.x, k < 5 ? 0.1 * std::min(k, 3) : 1.3, kExact) << "step " << k;
    EXPECT_NEAR(pose.y, k < 5 ? 0.0 : 0.5, kExact) << "step " << k;
    EXPECT_NEAR(pose.heading, k < 5 ? 0.0 : common::kPi / 4, kExact) << "step " << k;
  }
}

class ArcTest : public ::testing::TestWithParam<bool> {};

TEST_P(ArcTest, SweepsTheConfiguredAngleOnTheConfiguredCircle) {
  const bool left = GetParam();
  auto o = QuietScenario();
  auto& c = o.robots[0].control;
  c.type = common::ControlType::kArc;
  c.radius_m = 2.0;
  c.speed_mps = 1.0;
  c.sweep_rad = kPi / 2.0;
  c.turn_left = left;
  const double w = (left ? 1.0 : -1.0) * c.speed_mps / c.radius_m, dt = o.run.dt_s;
  // Active while |w| (k-1) dt < sweep: ceil(sweep / (|w| dt)) steps.
  const int active = static_cast<int>(std::ceil(c.sweep_rad / (std::abs(w) * dt)));
  World world(o);
  for (int k = 1; k <= active + 10; ++k) {
    const auto seg = world.Step()[0].odometry.segments.at(0);
    EXPECT_DOUBLE_EQ(seg.v_mps, k <= active ? 1.0 : 0.0) << "step " << k;
    EXPECT_DOUBLE_EQ(seg.w_radps, k <= active ? w : 0.0) << "step " << k;
  }
  const common::Pose2 end = world.Truth().robots[0].pose;
  EXPECT_NEAR(end.heading, active * w * dt, kExact);
  // On the chord circle of radius v dt / (2 sin(w dt / 2)) centred on the turning side.
  const double radius = dt / (2.0 * std::sin(std::abs(w) * dt / 2.0));
  const Eigen::Vector2d p1 = common::UnicycleStep({}, 1.0, w, dt).Translation();
  const Eigen::Vector2d p2 = common::UnicycleStep({p1.x(), p1.y(), w * dt}, 1.0, w, dt).Translation();
  const Eigen::Vector2d centre = Circumcentre({0.0, 0.0}, p1, p2);
  EXPECT_NEAR((end.Translation() - centre).norm(), radius, kExact);
  EXPECT_GT(left ? centre.y() : -centre.y(), 0.0);
}

INSTANTIATE_TEST_SUITE_P(LeftAndRight, ArcTest, ::testing::Bool());

TEST(WorldTest, ImuAgreesWithANoiselessConstantTurn) {
  auto o = QuietScenario();
  o.robots[0].control.v_mps = 1.0;
  o.robots[0].control.w_radps = 0.5;
  o.sensors.imu.readings_per_step = 4;
  World world(o);
  for (int k = 1; k <= 50; ++k) {
    const auto imu = world.Step()[0].imu;
    EXPECT_EQ(imu.stamp.step, static_cast<std::uint32_t>(k));
    ASSERT_EQ(imu.readings.size(), 4u);
    for (int i = 0; i < 4; ++i) {
      const auto& r = imu.readings[i];
      EXPECT_NEAR(r.time_s, (k - 1) * 0.1 + (i + 1) * 0.1 / 4, kExact);
      EXPECT_NEAR(r.gyro_z_radps, 0.5, kExact);
      // From rest to 1 m/s during step 1, then constant speed.
      EXPECT_NEAR(r.accel_x_mps2, k == 1 ? 1.0 / 0.1 : 0.0, kExact);
      EXPECT_NEAR(r.accel_y_mps2, 1.0 * 0.5, kExact);  // v w
    }
  }
}

TEST(WorldTest, ImuNoiseHasTheConfiguredMeanAndVariance) {
  auto o = QuietScenario();
  o.robots[0].control.v_mps = 1.0;
  o.robots[0].control.w_radps = 0.5;
  o.sensors.imu.gyro_noise_sd_radps = 0.01;
  o.sensors.imu.accel_noise_sd_mps2 = 0.05;
  World world(o);
  std::vector<double> gyro, gyro_err, ax_err, ay_err;
  world.Step();  // step 1: the acceleration from rest
  for (int k = 0; k < 2000; ++k) {
    const auto r = world.Step()[0].imu.readings.at(0);
    gyro.push_back(r.gyro_z_radps);
    gyro_err.push_back(r.gyro_z_radps - 0.5);
    ax_err.push_back(r.accel_x_mps2);
    ay_err.push_back(r.accel_y_mps2 - 0.5);
  }
  EXPECT_TRUE(testing::MeanMatches(gyro, 0.5, 0.01));
  EXPECT_TRUE(testing::VarianceMatches(gyro_err, 0.01 * 0.01));
  EXPECT_TRUE(testing::VarianceMatches(ax_err, 0.05 * 0.05));
  EXPECT_TRUE(testing::VarianceMatches(ay_err, 0.05 * 0.05));
}

TEST(WorldTest, ImuSeesASpeedChangeAndCanBeDisabled) {
  auto o = QuietScenario();
  auto& c = o.robots[0].control;
  c.type = common::ControlType::kSchedule;
  c.segments = {{1.0, 0.0, 0.3}, {2.0, 0.0, 0.3}};
  World world(o);
  EXPECT_NEAR(world.Step()[0].imu.readings.at(0).accel_x_mps2, 1.0 / 0.1, kExact);  // from rest
  EXPECT_NEAR(world.Step()[0].imu.readings.at(0).accel_x_mps2, 0.0, kExact);
  world.Step();
  // (v_4 - v_3) / dt = (2 - 1) / 0.1.
  EXPECT_NEAR(world.Step()[0].imu.readings.at(0).accel_x_mps2, 10.0, 1e-6);

  o.sensors.imu.enabled = false;
  World quiet(o);
  EXPECT_TRUE(quiet.Step()[0].imu.readings.empty());
}

TEST(WorldTest, OdometryNoiseMatchesConfiguredVariance) {
  auto o = QuietScenario();
  o.robots[0].control.v_mps = 0.5;
  o.robots[0].control.w_radps = 0.1;
  o.sensors.odometry.v_noise_sd_mps = 0.1;
  o.sensors.odometry.w_noise_sd_radps = 0.05;
  World world(o);
  std::vector<double> ev, ew;
  for (int k = 0; k < 2000; ++k) {
    const auto seg = world.Step()[0].odometry.segments.at(0);
    ev.push_back(seg.v_mps - 0.5);
    ew.push_back(seg.w_radps - 0.1);
  }
  EXPECT_TRUE(testing::VarianceMatches(ev, 0.01));
  EXPECT_TRUE(testing::VarianceMatches(ew, 0.0025));
  EXPECT_TRUE(testing::MeanMatches(ev, 0.0, 0.1));
}

TEST(WorldTest, SameSeedGivesIdenticalStreamsAndAnotherSeedDiffers) {
  for (const char* file : {"dynamic_world.yaml", "paper_two_robots.yaml"}) {
    SCOPED_TRACE(file);
    const auto options =
        common::LoadScenario(SourceDir() + "/config/" + file, {"sensors.lidar.detection_probability=0.8"});
    const std::string a = RunAndDump(options, 40);
    EXPECT_EQ(a, RunAndDump(options, 40));
    auto other = options;
    other.seed = options.seed + 1;
    EXPECT_NE(a, RunAndDump(other, 40));
  }
}

TEST(WorldTest, TruthHasEveryEntity) {
  const auto options = common::LoadScenario(SourceDir() + "/config/dynamic_world.yaml", {});
  World world(options);
  EXPECT_EQ(world.step(), 0u);
  world.Step();
  world.Step();
  const auto truth = world.Truth();
  EXPECT_EQ(truth.stamp.robot_id, "world");
  EXPECT_EQ(truth.stamp.step, 2u);
  EXPECT_NEAR(truth.stamp.time_s, 2 * options.run.dt_s, kExact);
  EXPECT_NEAR(world.time_s(), 2 * options.run.dt_s, kExact);

  ASSERT_EQ(truth.robots.size(), options.robots.size());
  ASSERT_EQ(truth.frames.size(), options.robots.size());
  for (std::size_t i = 0; i < options.robots.size(); ++i) {
    EXPECT_EQ(truth.robots[i].id, options.robots[i].id);
    EXPECT_TRUE(truth.robots[i].moving);
    EXPECT_EQ(truth.frames[i].first, options.robots[i].id);
    EXPECT_EQ(truth.frames[i].second.x, options.robots[i].frame_in_world.x);
    EXPECT_EQ(truth.frames[i].second.heading, options.robots[i].frame_in_world.heading);
  }
  const auto landmarks = ExpandLandmarks(options);
  ASSERT_EQ(truth.landmarks.size(), landmarks.size());
  for (std::size_t i = 0; i < landmarks.size(); ++i) {
    EXPECT_EQ(truth.landmarks[i].id, std::to_string(landmarks[i].id));
    EXPECT_EQ(truth.landmarks[i].moving, landmarks[i].motion.model != common::LandmarkMotionModel::kStatic);
    if (!truth.landmarks[i].moving) {
      EXPECT_EQ(truth.landmarks[i].pose.x, landmarks[i].pose.x);
      EXPECT_EQ(truth.landmarks[i].pose.y, landmarks[i].pose.y);
    }
  }
}

TEST(WorldTest, StampsCarryRobotStepAndTime) {
  auto o = QuietScenario();
  common::RobotOptions r2;
  r2.id = "r2";
  r2.initial_pose = {3.0, 0.0, 0.0};
  o.robots.push_back(r2);
  o.landmarks.push_back(StaticLandmark(1, 1.0, 1.0));
  World world(o);
  for (std::uint32_t k = 1; k <= 3; ++k) {
    const auto sensed = world.Step();
    ASSERT_EQ(sensed.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
      const std::string id = o.robots[i].id;
      for (const auto* stamp : {&sensed[i].lidar.stamp, &sensed[i].imu.stamp, &sensed[i].odometry.stamp}) {
        EXPECT_EQ(stamp->robot_id, id);
        EXPECT_EQ(stamp->step, k);
        EXPECT_NEAR(stamp->time_s, k * o.run.dt_s, kExact);
      }
      ASSERT_EQ(sensed[i].lidar.landmarks.size(), 1u);
      EXPECT_NEAR(sensed[i].lidar.landmarks[0].time_s, k * o.run.dt_s, kExact);
    }
  }
}

}  // namespace
}  // namespace mrslam::world_sim
