#include "robot_agent/smoother/graph_factors.h"

#include <vector>

#include <gtest/gtest.h>

#include "common/angles.h"
#include "common/se2.h"

namespace mrslam::robot_agent::smoother {
namespace {

using common::Pose2;

Eigen::Vector3d Minus(const Pose2& a, const Pose2& b) {
  return {a.x - b.x, a.y - b.y, common::WrapAngle(a.heading - b.heading)};
}

// Three steps of one or two segments each, turning through the wrap of the heading.
std::vector<std::vector<Motion>> Steps() {
  std::vector<std::vector<Motion>> steps(3);
  steps[0] = {{0.4, 1.2, 0.05}, {0.5, 1.4, 0.05}};
  steps[1] = {{0.3, -0.8, 0.1}};
  steps[2] = {{0.6, 2.0, 0.06}, {0.2, 0.5, 0.04}};
  return steps;
}

TEST(GraphFactors, TheIncrementsJacobianMatchesNumericDifferences) {
  const Eigen::Vector3d c(1.05, 0.93, 0.02);
  const auto steps = Steps();
  const OdometryIncrementJacobians analytic = OdometryIncrementWithJacobian(steps, c);
  EXPECT_LT(Minus(analytic.delta, OdometryIncrement(steps, c)).norm(), 1e-12);
  constexpr double kH = 1e-6;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(i) = kH;
    const Eigen::Vector3d numeric = Minus(OdometryIncrement(steps, c + d), OdometryIncrement(steps, c - d)) / (2 * kH);
    EXPECT_LT((analytic.d_correction.col(i) - numeric).norm(), 1e-7) << "column " << i;
  }
}

TEST(GraphFactors, TheOdometryFactorsJacobiansMatchNumericDifferences) {
  const Pose2 a{1.0, -2.0, 3.0}, b{1.3, -1.8, -3.1};
  const Eigen::Vector3d c(0.97, 1.02, -0.01);
  const auto steps = Steps();
  const Eigen::Matrix3d w = Eigen::Vector3d(10.0, 20.0, 30.0).asDiagonal();
  const OdometryFactor f = OdometryResidual(a, b, OdometryIncrementWithJacobian(steps, c), w, true);
  EXPECT_LT((f.residual - OdometryResidual(a, b, OdometryIncrementWithJacobian(steps, c), w, false).residual).norm(),
            1e-12);
  constexpr double kH = 1e-6;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(i) = kH;
    const auto at = [&](const Pose2& pa, const Pose2& pb, const Eigen::Vector3d& pc) {
      return OdometryResidual(pa, pb, OdometryIncrementWithJacobian(steps, pc), w, false).residual;
    };
    const Eigen::Vector3d da =
        (at(Pose2::FromVector(a.Vector() + d), b, c) - at(Pose2::FromVector(a.Vector() - d), b, c)) / (2 * kH);
    const Eigen::Vector3d db =
        (at(a, Pose2::FromVector(b.Vector() + d), c) - at(a, Pose2::FromVector(b.Vector() - d), c)) / (2 * kH);
    const Eigen::Vector3d dc = (at(a, b, c + d) - at(a, b, c - d)) / (2 * kH);
    EXPECT_LT((f.d_a.col(i) - da).norm(), 1e-5) << i;
    EXPECT_LT((f.d_b.col(i) - db).norm(), 1e-5) << i;
    EXPECT_LT((f.d_correction.col(i) - dc).norm(), 1e-5) << i;
  }
}

TEST(GraphFactors, TheHuberLossIsQuadraticWithinItsWidthAndLinearBeyond) {
  EXPECT_DOUBLE_EQ(HuberLoss(2.0, 3.0).scale, 1.0);
  EXPECT_DOUBLE_EQ(HuberLoss(2.0, 3.0).cost, 4.0);
  const Huber far = HuberLoss(12.0, 3.0);
  EXPECT_DOUBLE_EQ(far.scale, 0.5);
  EXPECT_DOUBLE_EQ(far.cost, 2.0 * 3.0 * 12.0 - 9.0);
}

}  // namespace
}  // namespace mrslam::robot_agent::smoother
