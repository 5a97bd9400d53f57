#include "robot_agent/filters/fastslam.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <set>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "robot_agent/factory/filter_factory.h"
#include "robot_agent/filters/slam_filter.h"
#include "tests/robot_agent/tiny_world.h"

namespace mrslam::robot_agent::filters {
namespace {

using factory::CreateFilter;
using testing::AddLandmark;
using testing::OneRobotScenario;
using testing::TinyWorld;

// Pose NEES e^T P^-1 e, e = truth - estimate (heading wrapped).
double PoseNees(const FilterEstimate& e, const common::Pose2& truth) {
  const Eigen::Vector3d d(truth.x - e.pose.x, truth.y - e.pose.y, common::WrapAngle(truth.heading - e.pose.heading));
  return d.dot(e.covariance.ldlt().solve(d));
}

const MapLandmark* Nearest(const FilterEstimate& e, const Eigen::Vector2d& p) {
  const MapLandmark* best = nullptr;
  for (const auto& l : e.landmarks) {
    if (!best || (l.mean.head<2>() - p).norm() < (best->mean.head<2>() - p).norm()) best = &l;
  }
  return best;
}

// Eight static landmarks around a robot driving a circle of radius 5 m.
common::ScenarioOptions StaticScenario(int particles) {
  common::ScenarioOptions o = OneRobotScenario(1.0, 0.2, particles);
  o.robots[0].initial_pose = {0.0, -5.0, 0.0};
  for (int i = 0; i < 8; ++i) {
    const double a = i * common::kPi / 4.0;
    AddLandmark(&o, i + 1, {(i % 2 ? 3.0 : 7.0) * std::cos(a), (i % 2 ? 3.0 : 7.0) * std::sin(a), 0.0});
  }
  o.filter.landmark_kinematics = robot_agent::LandmarkKinematics::kStatic;
  return o;
}

// FastSLAM 2.0 with 1000 particles: over seeds, the average pose NEES at each of the first 50
// steps stays within the two-sided 99.9% chi-square interval of its distribution (S seeds:
// S * ANEES ~ chi2(3 S)) at 90% of the steps, and its mean over the steps lies within the 99%
// interval. (FastSLAM's slow loss of consistency through resampling makes it drift upwards;
// FastSLAM 1.0 with these precise sensors degenerates sooner and is not held to this.)
TEST(FastSlam, StaticLandmarksPoseIsConsistent) {
  constexpr int kSeeds = 40, kSteps = 50;
  // chi2(120) quantiles divided by 40 (Wilson-Hilferty): 0.5% and 99.5%: [2.25, 3.89];
  // 0.05% and 99.95%: [1.89, 4.44].
  constexpr double kLow = 2.25, kHigh = 3.89, kStepLow = 1.89, kStepHigh = 4.44;
  std::vector<double> anees(kSteps, 0.0);
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const common::ScenarioOptions o = StaticScenario(1000);
    TinyWorld world(o, seed);
    const auto filter = CreateFilter(common::AgentOptionsFor(o, "r1"), seed);
    for (int k = 0; k < kSteps; ++k) {
      filter->Process(world.Step());
      anees[k] += PoseNees(filter->Estimate(), world.robot()) / kSeeds;
    }
  }
  int outside = 0;
  double mean = 0.0;
  for (int k = 0; k < kSteps; ++k) {
    outside += anees[k] < kStepLow || anees[k] > kStepHigh;
    mean += anees[k] / kSteps;
  }
  EXPECT_LE(outside, kSteps / 10);
  EXPECT_GT(mean, kLow);
  EXPECT_LT(mean, kHigh);
}

// The motion prior carries the odometry's (v, w) noise (sensors.odometry) through the step,
// G Q_u G^T, besides the process noise Q: with nothing to see, the particles' spread after one
// step is that covariance (4000 particles: a variance within 10%, over 4 standard errors).
TEST(FastSlam, MotionPriorCarriesTheOdometryNoise) {
  common::ScenarioOptions o = OneRobotScenario(1.0, 0.4, 4000);
  o.run.dt_s = 1.0;
  o.sensors.odometry.v_noise_sd_mps = 0.2;
  o.sensors.odometry.w_noise_sd_radps = 0.1;
  o.noise.robot_process_var = Eigen::Vector3d::Constant(1e-4);
  TinyWorld world(o, 1);
  const auto filter = CreateFilter(common::AgentOptionsFor(o, "r1"), 1);
  filter->Process(world.Step());
  // From (0, 0, 0) with h = w dt = 0.4: G = [dt cos h, -v dt^2 sin h; dt sin h, v dt^2 cos h; 0, dt].
  const double h = 0.4;
  Eigen::Matrix<double, 3, 2> g;
  g << std::cos(h), -std::sin(h), std::sin(h), std::cos(h), 0.0, 1.0;
  const Eigen::Matrix3d expected =
      g * Eigen::Vector2d(0.04, 0.01).asDiagonal() * g.transpose() + Eigen::Matrix3d::Identity() * 1e-4;
  const Eigen::Matrix3d c = filter->Estimate().covariance;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(c(i, i), expected(i, i), 0.1 * expected(i, i)) << i;
    for (int j = 0; j < i; ++j) {
      // Correlations within 0.1 of the expected ones.
      EXPECT_NEAR(c(i, j) / std::sqrt(c(i, i) * c(j, j)), expected(i, j) / std::sqrt(expected(i, i) * expected(j, j)),
                  0.1)
          << i << ", " << j;
    }
  }
}

TEST(FastSlam, StaticMapConvergesToTheLandmarks) {
  const common::ScenarioOptions o = StaticScenario(200);
  TinyWorld world(o, 7);
  const auto filter = CreateFilter(common::AgentOptionsFor(o, "r1"), 7);
  for (int k = 0; k < 40; ++k) filter->Process(world.Step());
  const FilterEstimate e = filter->Estimate();
  ASSERT_EQ(e.landmarks.size(), 8u);
  for (const auto& truth : world.landmarks()) {
    const MapLandmark* l = Nearest(e, truth.Translation());
    // Within 4 standard deviations of the map's own uncertainty, pose error included.
    const double sd = std::sqrt(l->covariance.topLeftCorner<2, 2>().trace() + e.covariance.trace());
    EXPECT_LT((l->mean.head<2>() - truth.Translation()).norm(), 4.0 * sd);
    EXPECT_FALSE(l->tentative);
    EXPECT_EQ(l->motion, LandmarkMotionKind::kStatic);
  }
}

// Paper A's world (docs/models.md): the robot on a circle among two unicycle landmarks whose
// (v, w) are known as candidates, 6 m lidar, dt 0.65 s.
common::ScenarioOptions PaperAScenario() {
  common::ScenarioOptions o = OneRobotScenario(1.0, 0.2, 500);
  o.run.dt_s = 0.65;
  o.robots[0].initial_pose = {-0.2, -0.5, 1.23};
  o.sensors.lidar.max_range_m = 6.0;
  o.sensors.lidar.range_noise_sd_m = o.sensors.lidar.bearing_noise_sd_rad = std::sqrt(0.001);
  o.noise.robot_process_var = o.noise.landmark_process_var = Eigen::Vector3d::Constant(0.001);
  AddLandmark(&o, 1, {-1.5, -1.0, 1.22}, 0.4, 0.2);
  AddLandmark(&o, 2, {2.5, -1.5, 2.09}, 0.6, 0.2);
  o.filter.landmark_kinematics = robot_agent::LandmarkKinematics::kKnownCandidates;
  o.filter.known_kinematics = {{0.4, 0.2}, {0.6, 0.2}};
  return o;
}

// Position RMSE of a filter over the first `steps` steps of a TinyWorld run.
double FilterPositionRmse(const common::ScenarioOptions& o, std::uint64_t seed, int steps) {
  TinyWorld world(o, seed);
  const auto filter = CreateFilter(common::AgentOptionsFor(o, "r1"), seed);
  double sq = 0.0;
  for (int k = 0; k < steps; ++k) {
    filter->Process(world.Step());
    sq += (filter->Estimate().pose.Translation() - world.robot().Translation()).squaredNorm() / steps;
  }
  return std::sqrt(sq);
}

// The IMU motion source (gyro for w, accel_x integrated for v, from rest) in paper A's world,
// where two moving landmarks are all there is to see: the speed is part of each particle, so
// over 10 seeds the position error stays within 25% of that of the filter driven by the exact
// commands, and under half of the error of integrating the IMU alone (its speed error is a
// random walk of sd 0.0325 m/s per step here). A speed integrated once for all particles drifts
// with the dead reckoning and fails both.
TEST(FastSlam, ImuMotionSourceStaysWithTheLandmarks) {
  constexpr int kSeeds = 10, kSteps = 100;
  double imu_sum = 0.0, odometry_sum = 0.0, dead_reckoning_sum = 0.0;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    common::ScenarioOptions o = PaperAScenario();
    o.filter.motion_source = robot_agent::MotionSource::kImu;
    o.sensors.imu = {true, 1, 0.01, 0.05};
    imu_sum += FilterPositionRmse(o, seed, kSteps);
    odometry_sum += FilterPositionRmse(PaperAScenario(), seed, kSteps);

    TinyWorld world(o, seed);
    common::Pose2 dead_reckoning = o.robots[0].initial_pose;
    double v = 0.0, sq = 0.0;
    for (int k = 0; k < kSteps; ++k) {
      const common::ImuReading r = world.Step().imu.readings.at(0);
      v += r.accel_x_mps2 * o.run.dt_s;
      dead_reckoning = common::UnicycleStep(dead_reckoning, v, r.gyro_z_radps, o.run.dt_s);
      sq += (dead_reckoning.Translation() - world.robot().Translation()).squaredNorm() / kSteps;
    }
    dead_reckoning_sum += std::sqrt(sq);
  }
  EXPECT_LT(imu_sum, 1.25 * odometry_sum);
  EXPECT_LT(imu_sum, 0.5 * dead_reckoning_sum);
}

// A landmark on a circle (v = 0.5 m/s, w = 0.15 rad/s) among static ones, with the constant
// turn rate model: it is tracked, and its v and w are estimated; the static ones come out still.
TEST(FastSlam, ConstantTurnRateEstimatesSpeedAndTurnRate) {
  constexpr double kV = 0.5, kW = 0.15;
  for (int seed = 1; seed <= 5; ++seed) {
    common::ScenarioOptions o = OneRobotScenario(0.0, 0.0, 300);
    o.robots[0].initial_pose = {-2.0, 0.0, 0.0};
    o.sensors.lidar.max_range_m = 12.0;  // the moving landmark stays in view
    AddLandmark(&o, 1, {0.0, 2.0, 0.0}, kV, kW);
    AddLandmark(&o, 2, {3.0, -3.0, 0.0});
    AddLandmark(&o, 3, {-3.0, 3.0, 0.0});
    o.filter.landmark_kinematics = robot_agent::LandmarkKinematics::kConstantTurnRate;
    TinyWorld world(o, seed);
    const auto filter = CreateFilter(common::AgentOptionsFor(o, "r1"), seed);
    for (int k = 0; k < 60; ++k) filter->Process(world.Step());
    const FilterEstimate e = filter->Estimate();
    ASSERT_EQ(e.landmarks.size(), 3u) << "seed " << seed;
    const MapLandmark* moving = Nearest(e, world.landmarks()[0].Translation());
    // Within 4 standard deviations of the map's own uncertainty, pose error included.
    const double sd = std::sqrt(moving->covariance.topLeftCorner<2, 2>().trace() + e.covariance.trace());
    EXPECT_LT((moving->mean.head<2>() - world.landmarks()[0].Translation()).norm(), 4.0 * sd);
    EXPECT_NEAR(moving->v_mps, kV, 0.05) << "seed " << seed;
    EXPECT_NEAR(moving->w_radps, kW, 0.03) << "seed " << seed;
    EXPECT_TRUE(moving->moving);
    EXPECT_EQ(moving->motion, LandmarkMotionKind::kConstantTurnRate);
    for (int i = 1; i < 3; ++i) {
      const MapLandmark* still = Nearest(e, world.landmarks()[i].Translation());
      EXPECT_LT(std::abs(still->v_mps), 0.05) << "seed " << seed;
      // Most of the weight holding it has settled on the static hypothesis (landmark_static_prior).
      EXPECT_EQ(still->motion, LandmarkMotionKind::kStatic) << "seed " << seed;
      EXPECT_FALSE(still->moving);
    }
  }
}

TEST(FastSlam, StaticHypothesisKeepsAnUnseenStaticLandmarkWhereItWas) {
  // A static landmark seen for 10 steps, then out of range for 40: with the static hypothesis
  // its position and covariance stay; with every landmark moving (prior 0) the speed's random
  // walk spreads it.
  double sd_with = 0.0, sd_without = 0.0;
  for (const double prior : {0.5, 0.0}) {
    common::ScenarioOptions o = OneRobotScenario(0.5, 0.0, 200);
    o.robots[0].initial_pose = {0.0, 0.0, 0.0};
    o.sensors.lidar.max_range_m = 6.0;
    AddLandmark(&o, 1, {2.0, 1.0, 0.0});
    AddLandmark(&o, 2, {25.0, 1.0, 0.0});  // keeps the robot company later
    o.filter.landmark_kinematics = robot_agent::LandmarkKinematics::kConstantTurnRate;
    o.filter.landmark_static_prior = prior;
    o.filter.max_landmark_position_sd_m = std::numeric_limits<double>::infinity();
    TinyWorld world(o, 3);
    const auto filter = CreateFilter(common::AgentOptionsFor(o, "r1"), 3);
    for (int k = 0; k < 50; ++k) filter->Process(world.Step());  // 25 m on: out of range since step 16
    const FilterEstimate e = filter->Estimate();
    const MapLandmark* first = Nearest(e, world.landmarks()[0].Translation());
    ASSERT_NE(first, nullptr);
    EXPECT_LT((first->mean.head<2>() - world.landmarks()[0].Translation()).norm(), 0.5) << "prior " << prior;
    (prior > 0.0 ? sd_with : sd_without) = std::sqrt(first->covariance.topLeftCorner<2, 2>().trace());
  }
  EXPECT_LT(sd_with, 0.2);
  EXPECT_GT(sd_without, 2.0 * sd_with);
}

// Two landmarks on straight paths that cross at the same time (at step 12): the track that
// follows each landmark before the crossing still follows it afterwards.
TEST(FastSlam, AssociationKeepsCrossingLandmarksApart) {
  for (int seed = 1; seed <= 5; ++seed) {
    common::ScenarioOptions o = OneRobotScenario(0.0, 0.0, 300);
    o.robots[0].initial_pose = {-3.0, -4.0, 0.5};
    o.noise.robot_process_var = Eigen::Vector3d(1e-4, 1e-4, 1e-5);
    o.sensors.lidar.max_range_m = 12.0;
    AddLandmark(&o, 1, {-3.0, 0.0, 0.0}, 0.5, 0.0);
    AddLandmark(&o, 2, {0.0, -3.0, common::kPi / 2}, 0.5, 0.0);
    AddLandmark(&o, 3, {-6.0, -6.0, 0.0});
    o.filter.landmark_kinematics = robot_agent::LandmarkKinematics::kConstantTurnRate;
    TinyWorld world(o, seed);
    const auto filter = CreateFilter(common::AgentOptionsFor(o, "r1"), seed);
    std::uint32_t track[2] = {0, 0};
    for (int k = 1; k <= 26; ++k) {
      filter->Process(world.Step());
      if (k == 8 || k == 26) {
        const FilterEstimate e = filter->Estimate();
        for (int i = 0; i < 2; ++i) {
          const MapLandmark* l = Nearest(e, world.landmarks()[i].Translation());
          ASSERT_NE(l, nullptr);
          EXPECT_LT((l->mean.head<2>() - world.landmarks()[i].Translation()).norm(), 0.4)
              << "seed " << seed << " step " << k;
          if (k == 8) track[i] = l->track_id;
          if (k == 26) {
            EXPECT_EQ(l->track_id, track[i]) << "seed " << seed;
          }
        }
        EXPECT_NE(track[0], track[1]);
      }
    }
  }
}

// Paper A's setting: which of two known (v, w) models each landmark follows is a per-particle
// hypothesis that the weights settle.
TEST(FastSlam, KnownCandidatesSettleOnTheRightModel) {
  for (int seed = 1; seed <= 5; ++seed) {
    common::ScenarioOptions o = OneRobotScenario(1.0, 0.2, 500);
    o.robots[0].initial_pose = {0.0, -5.0, 0.0};
    AddLandmark(&o, 1, {-1.5, -1.0, 1.22}, 0.4, 0.2);
    AddLandmark(&o, 2, {2.5, -1.5, 2.09}, 0.6, 0.2);
    o.filter.landmark_kinematics = robot_agent::LandmarkKinematics::kKnownCandidates;
    o.filter.known_kinematics = {{0.4, 0.2}, {0.6, 0.2}};
    TinyWorld world(o, seed);
    const auto filter = CreateFilter(common::AgentOptionsFor(o, "r1"), seed);
    for (int k = 0; k < 40; ++k) filter->Process(world.Step());
    const FilterEstimate e = filter->Estimate();
    ASSERT_EQ(e.landmarks.size(), 2u) << "seed " << seed;
    EXPECT_NEAR(Nearest(e, world.landmarks()[0].Translation())->v_mps, 0.4, 0.02);
    EXPECT_NEAR(Nearest(e, world.landmarks()[1].Translation())->v_mps, 0.6, 0.02);
  }
}

TEST(FastSlam, ReportedIdentitiesAreUsed) {
  common::ScenarioOptions o = StaticScenario(100);
  o.sensors.lidar.report_identity = true;
  TinyWorld world(o, 3);
  const auto filter = CreateFilter(common::AgentOptionsFor(o, "r1"), 3);
  for (int k = 0; k < 40; ++k) filter->Process(world.Step());
  const FilterEstimate e = filter->Estimate();
  ASSERT_EQ(e.landmarks.size(), 8u);
  std::set<int> ids;
  for (const auto& l : e.landmarks) {
    ids.insert(l.landmark_id);
    const common::Pose2& truth = world.landmarks()[l.landmark_id - 1];
    EXPECT_LT((l.mean.head<2>() - truth.Translation()).norm(), 0.5);
  }
  EXPECT_EQ(ids.size(), 8u);
}

// An identified reading beyond the outlier gate, which the filter leaves out, keeps its
// landmark's track as its label (a smoother fed by the labels decides by its own gate).
TEST(FastSlam, AReadingBeyondTheOutlierGateKeepsItsLabel) {
  common::ScenarioOptions o = StaticScenario(100);
  o.sensors.lidar.report_identity = true;
  o.filter.outlier_gate_probability = 0.999;
  TinyWorld world(o, 3);
  const auto filter = CreateFilter(common::AgentOptionsFor(o, "r1"), 3);
  for (int k = 0; k < 40; ++k) filter->Process(world.Step());
  common::SensorStep step = world.Step();
  ASSERT_FALSE(step.lidar.landmarks.empty());
  common::LandmarkDetection& outlier = step.lidar.landmarks.front();
  outlier.range_m += 3.0;
  filter->Process(step);
  const FilterEstimate e = filter->Estimate();
  ASSERT_EQ(e.detection_tracks.size(), step.lidar.landmarks.size());
  const auto it = std::find_if(e.landmarks.begin(), e.landmarks.end(),
                               [&](const MapLandmark& l) { return l.landmark_id == outlier.landmark_id; });
  ASSERT_NE(it, e.landmarks.end());
  EXPECT_EQ(e.detection_tracks.front(), it->track_id);
}

bool SameEstimate(const FilterEstimate& a, const FilterEstimate& b) {
  if (a.landmarks.size() != b.landmarks.size()) return false;
  for (std::size_t i = 0; i < a.landmarks.size(); ++i) {
    if (a.landmarks[i].track_id != b.landmarks[i].track_id || a.landmarks[i].mean != b.landmarks[i].mean ||
        a.landmarks[i].covariance != b.landmarks[i].covariance) {
      return false;
    }
  }
  return a.pose.Vector() == b.pose.Vector() && a.covariance == b.covariance &&
         a.effective_sample_size == b.effective_sample_size;
}

// Same seed, same numbers; and the order of the detections in a scan changes nothing.
TEST(FastSlam, SameSeedSameNumbersWhateverTheScanOrder) {
  common::ScenarioOptions o = StaticScenario(100);
  o.filter.landmark_kinematics = robot_agent::LandmarkKinematics::kConstantTurnRate;
  TinyWorld world(o, 5);
  const auto a = CreateFilter(common::AgentOptionsFor(o, "r1"), 5);
  const auto b = CreateFilter(common::AgentOptionsFor(o, "r1"), 5);
  const auto c = CreateFilter(common::AgentOptionsFor(o, "r1"), 6);
  bool differs_with_other_seed = false;
  for (int k = 0; k < 30; ++k) {
    common::SensorStep step = world.Step();
    a->Process(step);
    std::reverse(step.lidar.landmarks.begin(), step.lidar.landmarks.end());
    b->Process(step);
    c->Process(step);
    ASSERT_TRUE(SameEstimate(a->Estimate(), b->Estimate())) << "step " << k;
    differs_with_other_seed |= !SameEstimate(a->Estimate(), c->Estimate());
  }
  EXPECT_TRUE(differs_with_other_seed);
}

// After resampling, copies of a particle share its landmark blocks instead of copying them.
TEST(FastSlam, ResamplingSharesLandmarkStorage) {
  common::ScenarioOptions o = StaticScenario(200);
  o.filter.resample_every_step = true;
  TinyWorld world(o, 9);
  FastSlam<2> filter(common::AgentOptionsFor(o, "r1"), 9);
  for (int k = 0; k < 10; ++k) filter.Process(world.Step());
  std::set<const void*> unique;
  int total = 0;
  for (int p = 0; p < filter.NumParticles(); ++p) {
    for (const void* b : filter.LandmarkStorage(p)) {
      unique.insert(b);
      ++total;
    }
  }
  ASSERT_GT(total, 0);
  EXPECT_LT(static_cast<int>(unique.size()), total);
  // Weights are uniform right after resampling.
  for (int p = 0; p < filter.NumParticles(); ++p) {
    EXPECT_NEAR(filter.ParticleWeight(p), 1.0 / filter.NumParticles(), 1e-12);
  }
}

// Merging a peer's map fuses a block that particles share, and in which they match the same peer
// landmarks, once for all of them: they go on sharing the fused block. The peer here knows what
// this robot knows, so every particle matches its landmarks. A robot drives past 24 static landmarks, resampling every
// step, so that those behind it are held in blocks that descend from few ancestors.
TEST(FastSlam, MergingFusesASharedBlockOnceForAllItsParticles) {
  common::ScenarioOptions o = OneRobotScenario(1.0, 0.0, 100);
  o.robots[0].initial_pose = {0.0, 0.0, 0.0};
  o.sensors.lidar.max_range_m = 6.0;
  for (int i = 0; i < 24; ++i) AddLandmark(&o, i + 1, {1.0 * i, i % 2 ? 2.0 : -2.0, 0.0});
  o.filter.resample_every_step = true;
  TinyWorld world(o, 4);
  FastSlam<2> filter(common::AgentOptionsFor(o, "r1"), 4);
  for (int k = 0; k < 70; ++k) filter.Process(world.Step());
  const auto distinct_blocks = [&] {
    std::set<const void*> distinct;
    for (int p = 0; p < filter.NumParticles(); ++p) {
      for (const void* b : filter.LandmarkStorage(p)) distinct.insert(b);
    }
    return distinct.size();
  };
  std::size_t held = 0;  // blocks held, a block held by n particles counted n times
  for (int p = 0; p < filter.NumParticles(); ++p) held += filter.LandmarkStorage(p).size();
  const std::size_t before = distinct_blocks();
  ASSERT_LT(2 * before, held);
  const std::vector<MapLandmark> peer = filter.Estimate().landmarks;
  ASSERT_FALSE(peer.empty());
  EXPECT_EQ(filter.MergeLandmarks(peer, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 0.0), 0);
  // Here every particle that shares a block matches the same peer landmarks in it: one fused block
  // for each block there was (copies per particle would make all of those held distinct).
  EXPECT_EQ(distinct_blocks(), before);
}

// Constant turn rate: prediction leaves the landmarks taken as static alone, so their blocks
// stay shared between the copies resampling made. A robot drives past 24 static landmarks,
// resampling every step; once they are all behind it, out of view, the particles' first blocks
// (static landmarks only) descend from few ancestors: under a quarter of them are distinct
// (every one was distinct when prediction wrote every landmark each step).
TEST(FastSlam, PredictionLeavesTheBlocksOfStaticLandmarksShared) {
  common::ScenarioOptions o = OneRobotScenario(1.0, 0.0, 100);
  o.robots[0].initial_pose = {0.0, 0.0, 0.0};
  o.sensors.lidar.max_range_m = 6.0;
  for (int i = 0; i < 24; ++i) AddLandmark(&o, i + 1, {1.0 * i, i % 2 ? 2.0 : -2.0, 0.0});
  o.filter.landmark_kinematics = robot_agent::LandmarkKinematics::kConstantTurnRate;
  o.filter.resample_every_step = true;
  TinyWorld world(o, 4);
  FastSlam<5> filter(common::AgentOptionsFor(o, "r1"), 4);
  for (int k = 0; k < 70; ++k) filter.Process(world.Step());
  ASSERT_GE(filter.Estimate().landmarks.size(), 20u);
  std::set<const void*> first_blocks;
  for (int p = 0; p < filter.NumParticles(); ++p) first_blocks.insert(filter.LandmarkStorage(p).at(0));
  EXPECT_LT(4 * first_blocks.size(), static_cast<std::size_t>(filter.NumParticles()));
}

// What FastSLAM holds grows with its map, not with time: in a static world whose map is complete
// by step 200, EstimatorBytes at step 2000 is within 10% of that at step 200. It counts each
// distinct landmark block once (shared copies as the archive writes them).
TEST(FastSlam, EstimatorBytesStayFlatOnceTheMapIsComplete) {
  const common::ScenarioOptions o = StaticScenario(100);
  TinyWorld world(o, 5);
  FastSlam<2> filter(common::AgentOptionsFor(o, "r1"), 5);
  std::size_t at_200 = 0;
  for (int k = 1; k <= 2000; ++k) {
    filter.Process(world.Step());
    if (k == 200) {
      ASSERT_EQ(filter.Estimate().landmarks.size(), 8u);
      at_200 = filter.EstimatorBytes();
    }
  }
  EXPECT_EQ(filter.Estimate().landmarks.size(), 8u);
  const std::size_t at_2000 = filter.EstimatorBytes();
  EXPECT_GT(static_cast<double>(at_2000), 0.9 * static_cast<double>(at_200));
  EXPECT_LT(static_cast<double>(at_2000), 1.1 * static_cast<double>(at_200));
  std::set<const void*> distinct;
  for (int p = 0; p < filter.NumParticles(); ++p) {
    for (const void* b : filter.LandmarkStorage(p)) distinct.insert(b);
  }
  EXPECT_GE(at_2000, sizeof(FastSlam<2>) + distinct.size() * sizeof(LandmarkBlock<2>));
}

TEST(SlamFilter, CreatesEveryKnownFilterAndNothingElse) {
  common::ScenarioOptions o = StaticScenario(10);
  for (const char* type : {"fastslam", "ekf", "ekf_ela"}) {
    o.filter.type = type;
    EXPECT_NE(CreateFilter(common::AgentOptionsFor(o, "r1"), 1), nullptr) << type;
  }
  o.filter.type = "particle_smoother";
  EXPECT_EQ(CreateFilter(common::AgentOptionsFor(o, "r1"), 1), nullptr);
}

}  // namespace
}  // namespace mrslam::robot_agent::filters
