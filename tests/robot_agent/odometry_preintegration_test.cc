#include "robot_agent/smoother/odometry_preintegration.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "common/angles.h"
#include "common/se2.h"

namespace mrslam::robot_agent::smoother {
namespace {

Eigen::Vector3d Minus(const common::Pose2& a, const common::Pose2& b) {
  return {a.x - b.x, a.y - b.y, common::WrapAngle(a.heading - b.heading)};
}

// 40 steps of three segments each (0.1 s a step), turning both ways and through the heading's
// wrap: 4 m driven, about 7 rad turned.
std::vector<std::vector<Motion>> Steps() {
  std::vector<std::vector<Motion>> steps(40);
  for (int k = 0; k < 40; ++k) {
    for (int j = 0; j < 3; ++j) {
      const double w = 2.5 * std::sin(0.2 * k) + 0.3 * j;
      steps[k].push_back({1.0 + 0.2 * std::cos(0.3 * k), w, 0.1 / 3.0});
    }
  }
  return steps;
}

void ExpectEqual(const OdometryIncrementJacobians& got, const OdometryIncrementJacobians& want, double value_tol,
                 double jacobian_tol) {
  EXPECT_LT(Minus(got.delta, want.delta).norm(), value_tol);
  EXPECT_LT((got.d_correction - want.d_correction).cwiseAbs().maxCoeff(), jacobian_tol);
}

TEST(OdometryPreintegration, ItIsTheIncrementAndItsJacobianNearAndFar) {
  const auto steps = Steps();
  OdometryPreintegration p;
  for (const Eigen::Vector3d& c : {Eigen::Vector3d(1.05, 0.93, 0.02), Eigen::Vector3d(1.06, 0.9301, 0.0201),
                                   Eigen::Vector3d(1.0, 0.9299, 0.0199), Eigen::Vector3d(0.8, 1.2, -0.1)}) {
    ExpectEqual(p.At(steps, c), OdometryIncrementWithJacobian(steps, c), 1e-12, 1e-8);
  }
}

TEST(OdometryPreintegration, ACorrectionMovingLittleGoesOverTheSegmentsRarely) {
  const auto steps = Steps();
  OdometryPreintegration p;
  for (int i = 0; i < 100; ++i) p.At(steps, Eigen::Vector3d(1.05 + 1e-4 * i, 0.93 + 1e-6 * i, 0.02 - 1e-6 * i));
  EXPECT_LE(p.Expansions(), 2);  // the cells are ~3e-4 by 2.5e-4 here: a boundary crossed at most
}

TEST(OdometryPreintegration, ItsValueDoesNotDependOnTheCorrectionsEvaluatedBefore) {
  const auto steps = Steps();
  const Eigen::Vector3d c(1.02, 0.95, 0.011);
  OdometryPreintegration fresh, used;
  for (int i = 0; i < 20; ++i) used.At(steps, c + Eigen::Vector3d(0.0, 1e-5 * (i + 1), -1e-5 * (i + 1)));
  const OdometryIncrementJacobians a = fresh.At(steps, c), b = used.At(steps, c);
  EXPECT_EQ(a.delta.x, b.delta.x);
  EXPECT_EQ(a.delta.y, b.delta.y);
  EXPECT_EQ(a.delta.heading, b.delta.heading);
  EXPECT_EQ(a.d_correction, b.d_correction);
}

}  // namespace
}  // namespace mrslam::robot_agent::smoother
