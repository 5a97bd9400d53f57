// EKF-SLAM core: measurement and motion Jacobians against numeric differences, the Joseph-form
// update keeping the covariance symmetric positive definite (seeded property test), and the
// filter on a small simulated world (consistency, association, map merging).
#include "robot_agent/filters/ekf_slam.h"
#include "common/config/agent_options_projection.h"
#include "robot_agent/factory/filter_factory.h"

#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "common/gaussian.h"
#include "common/rng.h"
#include "robot_agent/filters/slam_filter.h"
#include "tests/robot_agent/tiny_world.h"

namespace mrslam::robot_agent::filters {
namespace {

using factory::CreateFilter;
using testing::AddLandmark;
using testing::OneRobotScenario;
using testing::TinyWorld;

TEST(EkfSlamTest, MeasurementJacobiansMatchNumericDifferences) {
  common::Rng rng(7, "jacobians");
  const double eps = 1e-6;
  for (int trial = 0; trial < 1000; ++trial) {
    const Eigen::Vector3d robot(rng.Uniform(-10, 10), rng.Uniform(-10, 10), rng.Uniform(-3.1, 3.1));
    Eigen::Vector2d m;
    do {
      m = Eigen::Vector2d(rng.Uniform(-10, 10), rng.Uniform(-10, 10));
    } while ((m - robot.head<2>()).norm() < 0.5);
    Eigen::Matrix<double, 2, 3> h_r;
    Eigen::Matrix2d h_m;
    EkfSlam::MeasureJacobians(robot, m, &h_r, &h_m);
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d a = robot, b = robot;
      a(c) += eps;
      b(c) -= eps;
      Eigen::Vector2d diff = EkfSlam::Measure(a, m) - EkfSlam::Measure(b, m);
      diff(1) = common::WrapAngle(diff(1));
      EXPECT_NEAR((diff / (2 * eps) - h_r.col(c)).norm(), 0.0, 1e-5) << "trial " << trial << " robot col " << c;
    }
    for (int c = 0; c < 2; ++c) {
      Eigen::Vector2d a = m, b = m;
      a(c) += eps;
      b(c) -= eps;
      Eigen::Vector2d diff = EkfSlam::Measure(robot, a) - EkfSlam::Measure(robot, b);
      diff(1) = common::WrapAngle(diff(1));
      EXPECT_NEAR((diff / (2 * eps) - h_m.col(c)).norm(), 0.0, 1e-5) << "trial " << trial << " map col " << c;
    }
  }
}

// The prediction's covariance is F P F^T + G Q_u G^T + Q with F, G the Jacobians of the unicycle
// step: checked with F and G from numeric differences of common::UnicycleStep.
TEST(EkfSlamTest, PredictionCovarianceMatchesNumericJacobians) {
  common::ScenarioOptions o = OneRobotScenario(0.7, 0.3, 1);
  o.run.dt_s = 1.0;
  o.sensors.odometry.v_noise_sd_mps = 0.05;
  o.sensors.odometry.w_noise_sd_radps = 0.02;
  o.robots[0].initial_pose = {1.0, -2.0, 0.4};
  EkfSlam ekf(common::AgentOptionsFor(o, "r1"), /*ela=*/false);
  common::SensorStep step;
  step.lidar.stamp.step = 1;
  step.odometry.segments.push_back({0.0, 1.0, 0.7, 0.3});
  ekf.Process(step);  // P0 = 0: P1 = G Q_u G^T + Q at the start pose
  const Eigen::Matrix3d p1 = ekf.Covariance().topLeftCorner<3, 3>();
  const common::Pose2 pose1 = common::Pose2::FromVector(ekf.State().head<3>());
  step.lidar.stamp.step = 2;
  ekf.Process(step);

  const double eps = 1e-6;
  auto f = [](const Eigen::Vector3d& x, double v, double w) {
    return common::UnicycleStep(common::Pose2::FromVector(x), v, w, 1.0).Vector();
  };
  Eigen::Matrix3d f_num;
  Eigen::Matrix<double, 3, 2> g_num;
  for (int c = 0; c < 3; ++c) {
    Eigen::Vector3d a = pose1.Vector(), b = pose1.Vector();
    a(c) += eps;
    b(c) -= eps;
    f_num.col(c) = (f(a, 0.7, 0.3) - f(b, 0.7, 0.3)) / (2 * eps);
  }
  g_num.col(0) = (f(pose1.Vector(), 0.7 + eps, 0.3) - f(pose1.Vector(), 0.7 - eps, 0.3)) / (2 * eps);
  g_num.col(1) = (f(pose1.Vector(), 0.7, 0.3 + eps) - f(pose1.Vector(), 0.7, 0.3 - eps)) / (2 * eps);
  const Eigen::Matrix2d q_u = Eigen::Vector2d(0.05 * 0.05, 0.02 * 0.02).asDiagonal();
  const Eigen::Matrix3d expected = f_num * p1 * f_num.transpose() + g_num * q_u * g_num.transpose() +
                                   Eigen::Matrix3d(o.noise.robot_process_var.asDiagonal());
  EXPECT_LT((ekf.Covariance().topLeftCorner<3, 3>() - expected).cwiseAbs().maxCoeff(), 1e-8);
}

// A random SPD covariance of the given size: A A^T + eps I.
Eigen::MatrixXd RandomSpd(common::Rng* rng, int n, double scale) {
  Eigen::MatrixXd a(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) a(i, j) = rng->Normal(0.0, scale);
  }
  return a * a.transpose() + 1e-6 * Eigen::MatrixXd::Identity(n, n);
}

TEST(EkfSlamTest, JosephUpdateKeepsCovarianceSymmetricPositiveDefinite) {
  common::Rng rng(11, "joseph");
  const Eigen::Matrix2d r = Eigen::Vector2d(0.05 * 0.05, 0.02 * 0.02).asDiagonal();
  for (int trial = 0; trial < 300; ++trial) {
    const int landmarks = rng.UniformInt(1, 8);
    const int n = 3 + 2 * landmarks;
    Eigen::VectorXd x(n);
    x.head<3>() << rng.Uniform(-5, 5), rng.Uniform(-5, 5), rng.Uniform(-3, 3);
    for (int l = 0; l < landmarks; ++l) {
      const double range = rng.Uniform(0.5, 6.0), bearing = rng.Uniform(-3.1, 3.1);
      x.segment<2>(3 + 2 * l) = x.head<2>() + range * Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
    }
    // Scales from tiny to large, including ill-conditioned mixtures.
    Eigen::MatrixXd p = RandomSpd(&rng, n, std::pow(10.0, rng.Uniform(-4, 0)));
    for (int u = 0; u < 20; ++u) {
      const int slot = rng.UniformInt(0, landmarks - 1);
      Eigen::Vector2d z = EkfSlam::Measure(x.head<3>(), x.segment<2>(3 + 2 * slot));
      z += Eigen::Vector2d(rng.Normal(0.0, 0.05), rng.Normal(0.0, 0.02));
      const double trace_before = p.trace();
      ASSERT_TRUE(EkfSlam::JosephUpdate(&x, &p, slot, z, r));
      ASSERT_TRUE(common::IsSymmetricPositiveDefinite<Eigen::Dynamic>(p, 1e-12))
          << "trial " << trial << " update " << u << "\n"
          << p;
      EXPECT_LE(p.trace(), trace_before * (1.0 + 1e-9));
      ASSERT_TRUE(x.allFinite());
      // The landmark-only update: the rest of the state and its covariance stay as they were.
      const int other = rng.UniformInt(0, landmarks - 1), j = 3 + 2 * other;
      const Eigen::VectorXd x_before = x;
      const Eigen::MatrixXd p_before = p;
      z = EkfSlam::Measure(x.head<3>(), x.segment<2>(j)) +
          Eigen::Vector2d(rng.Normal(0.0, 0.05), rng.Normal(0.0, 0.02));
      ASSERT_TRUE(EkfSlam::JosephUpdate(&x, &p, other, z, r, /*landmark_only=*/true));
      ASSERT_TRUE(common::IsSymmetricPositiveDefinite<Eigen::Dynamic>(p, 1e-12));
      const double landmark_trace_before = p_before.block(j, j, 2, 2).trace();
      EXPECT_LE(p.block(j, j, 2, 2).trace(), landmark_trace_before * (1.0 + 1e-9));
      for (int row = 0; row < n; ++row) {
        if (row == j || row == j + 1) continue;
        EXPECT_EQ(x(row), x_before(row));
        for (int col = 0; col < n; ++col) {
          if (col == j || col == j + 1) continue;
          EXPECT_NEAR(p(row, col), p_before(row, col), 1e-12 * (1.0 + p_before.norm()));
        }
      }
    }
  }
}

// A robot on a circle among static landmarks: every landmark mapped once, pose error
// consistent with the covariance, covariance SPD throughout.
TEST(EkfSlamTest, MapsStaticLandmarksOnceAndStaysConsistent) {
  common::ScenarioOptions o = OneRobotScenario(0.5, 0.1, 1);
  o.run.steps = 120;
  int id = 1;
  for (int i = -2; i <= 2; ++i) {
    for (int j = -1; j <= 3; ++j) AddLandmark(&o, id++, {3.0 * i, 3.0 * j - 1.0, 0.0});
  }
  double nees_sum = 0.0;
  const int seeds = 5;
  for (int seed = 1; seed <= seeds; ++seed) {
    o.filter.type = "ekf";
    std::unique_ptr<SlamFilter> filter = CreateFilter(common::AgentOptionsFor(o, "r1"), seed);
    ASSERT_NE(filter, nullptr);
    auto* ekf = dynamic_cast<EkfSlam*>(filter.get());
    ASSERT_NE(ekf, nullptr);
    TinyWorld world(o, seed);
    for (int k = 0; k < o.run.steps; ++k) {
      ekf->Process(world.Step());
      ASSERT_TRUE(common::IsSymmetricPositiveDefinite<Eigen::Dynamic>(ekf->Covariance(), 1e-9)) << "step " << k;
    }
    const FilterEstimate e = ekf->Estimate();
    EXPECT_EQ(static_cast<int>(e.landmarks.size()), static_cast<int>(o.landmarks.size())) << "seed " << seed;
    Eigen::Vector3d err = e.pose.Vector() - world.robot().Vector();
    err(2) = common::WrapAngle(err(2));
    nees_sum += err.dot(e.covariance.ldlt().solve(err));
    for (const auto& l : e.landmarks) {
      double best = 1e9;
      for (const auto& t : world.landmarks()) best = std::min(best, (t.Translation() - l.mean.head<2>()).norm());
      EXPECT_LT(best, 0.5);
    }
  }
  // Mean NEES of a 3-dof consistent estimate is 3; allow the spread of 5 samples.
  EXPECT_LT(nees_sum / seeds, 12.0);
}

TEST(EkfSlamTest, MergeFusesKnownLandmarksAndAddsNewOnes) {
  common::ScenarioOptions o = OneRobotScenario(0.3, 0.1, 1);
  AddLandmark(&o, 1, {2.0, 1.0, 0.0});
  AddLandmark(&o, 2, {-1.0, 3.0, 0.0});
  for (const auto rule : {robot_agent::MapFusionRule::kWeighted, robot_agent::MapFusionRule::kCovarianceIntersection,
                          robot_agent::MapFusionRule::kAverage}) {
    EkfSlam ekf(common::AgentOptionsFor(o, "r1"), /*ela=*/false);
    TinyWorld world(o, 3);
    for (int k = 0; k < 10; ++k) ekf.Process(world.Step());
    ASSERT_EQ(ekf.NumMapped(), 2);
    std::vector<MapLandmark> incoming = ekf.Estimate().landmarks;
    MapLandmark far;
    far.mean = Eigen::Vector3d(20.0, 20.0, 0.0);
    far.covariance = 0.01 * Eigen::Matrix3d::Identity();
    incoming.push_back(far);
    const double before = ekf.Covariance().block(3, 3, 2, 2).trace();
    EXPECT_EQ(ekf.MergeLandmarks(incoming, rule, 0.999, 0.0), 1);
    EXPECT_EQ(ekf.NumMapped(), 3);
    const double after = ekf.Covariance().block(3, 3, 2, 2).trace();
    EXPECT_LE(after, before * (1.0 + 1e-9));
    EXPECT_TRUE(common::IsSymmetricPositiveDefinite<Eigen::Dynamic>(ekf.Covariance(), 1e-9));
  }
}

// A peer landmark outside the gate but within merge_min_separation_m of a mapped one is left
// out; the state is unchanged.
TEST(EkfSlamTest, MergeLeavesOutLandmarksTooCloseToMappedOnes) {
  common::ScenarioOptions o = OneRobotScenario(0.3, 0.1, 1);
  AddLandmark(&o, 1, {2.0, 1.0, 0.0});
  EkfSlam ekf(common::AgentOptionsFor(o, "r1"), /*ela=*/false);
  TinyWorld world(o, 3);
  for (int k = 0; k < 10; ++k) ekf.Process(world.Step());
  ASSERT_EQ(ekf.NumMapped(), 1);
  MapLandmark near;  // no identity, no provenance: matched by the gate alone
  near.mean = ekf.Estimate().landmarks[0].mean + Eigen::Vector3d(1.0, 0.0, 0.0);
  near.covariance = 1e-4 * Eigen::Matrix3d::Identity();
  const Eigen::MatrixXd p_before = ekf.Covariance();
  EXPECT_EQ(ekf.MergeLandmarks({near}, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 1.5), 0);
  EXPECT_EQ(ekf.NumMapped(), 1);
  EXPECT_EQ(ekf.Covariance(), p_before);
  EXPECT_EQ(ekf.MergeLandmarks({near}, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 0.5), 1);
  EXPECT_EQ(ekf.NumMapped(), 2);
}

}  // namespace
}  // namespace mrslam::robot_agent::filters
