#include <cmath>
#include <limits>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "common/angles.h"
#include "common/rng.h"
#include "common/se2.h"
#include "tests/test_matchers.h"

// Property tests of the SE(2) and angle maths over many seeded random cases (Ceres'
// manifold_test.cc style): each identity must hold for every sample.
namespace mrslam::common {
namespace {

using mrslam::testing::IsNearlyPose;

constexpr int kTrials = 2000;
// Rounding of a few compositions of values of order 10: far above 1e-16 * 10, far below any
// real error.
constexpr double kTol = 1e-9;

Pose2 RandomPose(Rng& rng) { return {rng.Uniform(-10.0, 10.0), rng.Uniform(-10.0, 10.0), rng.Uniform(-kPi, kPi)}; }
Eigen::Vector2d RandomPoint(Rng& rng) { return {rng.Uniform(-10.0, 10.0), rng.Uniform(-10.0, 10.0)}; }

TEST(Se2PropertyTest, InverseUndoesCompose) {
  Rng rng(1, "se2/inverse");
  const Pose2 identity;
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 a = RandomPose(rng), b = RandomPose(rng);
    ASSERT_THAT(Compose(a, Inverse(a)), IsNearlyPose(identity, kTol, kTol));
    ASSERT_THAT(Compose(Inverse(a), a), IsNearlyPose(identity, kTol, kTol));
    ASSERT_THAT(Inverse(Inverse(a)), IsNearlyPose(a, kTol, kTol));
    ASSERT_THAT(Compose(a, identity), IsNearlyPose(a, kTol, kTol));
    ASSERT_THAT(Compose(identity, a), IsNearlyPose(a, kTol, kTol));
    // (a b)^-1 = b^-1 a^-1; Between(a, a b) = b.
    ASSERT_THAT(Inverse(Compose(a, b)), IsNearlyPose(Compose(Inverse(b), Inverse(a)), kTol, kTol));
    ASSERT_THAT(Between(a, Compose(a, b)), IsNearlyPose(b, kTol, kTol));
  }
}

TEST(Se2PropertyTest, ComposeIsAssociative) {
  Rng rng(1, "se2/associative");
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 a = RandomPose(rng), b = RandomPose(rng), c = RandomPose(rng);
    ASSERT_THAT(Compose(Compose(a, b), c), IsNearlyPose(Compose(a, Compose(b, c)), kTol, kTol));
  }
}

TEST(Se2PropertyTest, ResultsAreWrapped) {
  Rng rng(1, "se2/wrapped");
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 a = RandomPose(rng), b = RandomPose(rng);
    for (const Pose2& p :
         {Compose(a, b), Inverse(a), Between(a, b), UnicycleStep(a, rng.Uniform(-2, 2), rng.Uniform(-5, 5), 0.7)}) {
      ASSERT_GT(p.heading, -kPi);
      ASSERT_LE(p.heading, kPi);
    }
  }
}

TEST(Se2PropertyTest, WrapAngleLandsInHalfOpenRangeAndKeepsTheDirection) {
  Rng rng(1, "se2/wrap");
  std::vector<double> angles = {0.0,
                                kPi,
                                -kPi,
                                3.0 * kPi,
                                -3.0 * kPi,
                                2 * kPi,
                                -2 * kPi,
                                1e6,
                                -1e6,
                                std::nextafter(kPi, 4.0),
                                std::nextafter(-kPi, -4.0),
                                std::nextafter(-kPi, 0.0)};
  for (int i = 0; i < kTrials; ++i) angles.push_back(rng.Uniform(-100.0, 100.0));
  for (const double a : angles) {
    const double w = WrapAngle(a);
    ASSERT_GT(w, -kPi) << a;
    ASSERT_LE(w, kPi) << a;
    // Same direction: w - a is a multiple of 2 pi (to the rounding of |a|).
    const double tol = 1e-15 * std::max(1.0, std::abs(a)) * 16;
    ASSERT_NEAR(std::cos(w), std::cos(a), tol) << a;
    ASSERT_NEAR(std::sin(w), std::sin(a), tol) << a;
    ASSERT_EQ(WrapAngle(w), w) << a;  // idempotent
  }
  EXPECT_EQ(WrapAngle(-kPi), kPi);
  EXPECT_EQ(WrapAngle(kPi), kPi);
}

TEST(Se2PropertyTest, TransformPointAgreesWithCompose) {
  Rng rng(1, "se2/points");
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 a = RandomPose(rng), b = RandomPose(rng);
    const Eigen::Vector2d p = RandomPoint(rng);
    // T_ac p = T_ab (T_bc p); T_ab^-1 (T_ab p) = p; the origin of B lands on (x, y).
    ASSERT_LT((TransformPoint(Compose(a, b), p) - TransformPoint(a, TransformPoint(b, p))).norm(), kTol);
    ASSERT_LT((TransformPoint(Inverse(a), TransformPoint(a, p)) - p).norm(), kTol);
    ASSERT_LT((TransformPoint(a, Eigen::Vector2d::Zero()) - a.Translation()).norm(), kTol);
    // A pose is a point and a direction: Compose(a, (p, h)) has translation T_ab p.
    ASSERT_LT((Compose(a, {p.x(), p.y(), 0.3}).Translation() - TransformPoint(a, p)).norm(), kTol);
  }
}

// Central difference of Compose over (x, y, heading) of one argument; heading differences
// wrapped.
Eigen::Matrix3d NumericJacobian(const Pose2& a, const Pose2& b, bool left) {
  constexpr double kStep = 1e-6;
  Eigen::Matrix3d j;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(k) = kStep;
    const Pose2 plus =
        left ? Compose(Pose2::FromVector(a.Vector() + d), b) : Compose(a, Pose2::FromVector(b.Vector() + d));
    const Pose2 minus =
        left ? Compose(Pose2::FromVector(a.Vector() - d), b) : Compose(a, Pose2::FromVector(b.Vector() - d));
    j.col(k) << (plus.x - minus.x) / (2 * kStep), (plus.y - minus.y) / (2 * kStep),
        WrapAngle(plus.heading - minus.heading) / (2 * kStep);
  }
  return j;
}

TEST(Se2PropertyTest, ComposeJacobiansMatchNumericDifferences) {
  Rng rng(1, "se2/jacobians");
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 a = RandomPose(rng), b = RandomPose(rng);
    // Central differences: truncation O(h^2 |b|) ~ 1e-10, rounding O(eps |x| / h) ~ 1e-9.
    constexpr double kJacobianTol = 1e-6;
    ASSERT_LT((ComposeJacobianLeft(a, b) - NumericJacobian(a, b, true)).cwiseAbs().maxCoeff(), kJacobianTol)
        << "left\n"
        << ComposeJacobianLeft(a, b) << "\nvs\n"
        << NumericJacobian(a, b, true);
    ASSERT_LT((ComposeJacobianRight(a, b) - NumericJacobian(a, b, false)).cwiseAbs().maxCoeff(), kJacobianTol)
        << "right\n"
        << ComposeJacobianRight(a, b) << "\nvs\n"
        << NumericJacobian(a, b, false);
  }
}

TEST(Se2PropertyTest, RangeBearingRoundTrip) {
  Rng rng(1, "se2/range_bearing");
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 pose = RandomPose(rng);
    const Eigen::Vector2d p = RandomPoint(rng);
    if ((p - pose.Translation()).norm() < 1e-3) continue;  // bearing undefined at the pose
    const RangeBearing z = MeasureRangeBearing(pose, p);
    ASSERT_GE(z.range_m, 0.0);
    ASSERT_GT(z.bearing_rad, -kPi);
    ASSERT_LE(z.bearing_rad, kPi);
    ASSERT_LT((PointFromRangeBearing(pose, z) - p).norm(), kTol);
    // And the other way: a reading maps to a point that gives the reading back.
    const RangeBearing r{rng.Uniform(0.01, 10.0), rng.Uniform(-kPi, kPi)};
    const RangeBearing back = MeasureRangeBearing(pose, PointFromRangeBearing(pose, r));
    ASSERT_NEAR(back.range_m, r.range_m, kTol);
    ASSERT_NEAR(WrapAngle(back.bearing_rad - r.bearing_rad), 0.0, kTol);
    // The bearing is relative to the heading: the point in the body frame is r (cos b, sin b).
    const Eigen::Vector2d body = TransformPoint(Inverse(pose), p);
    ASSERT_NEAR(z.bearing_rad, std::atan2(body.y(), body.x()), kTol);
  }
}

TEST(Se2PropertyTest, UnicycleStepIsABodyFrameMotion) {
  Rng rng(1, "se2/unicycle");
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 p = RandomPose(rng);
    const double v = rng.Uniform(-2.0, 2.0), w = rng.Uniform(-3.0, 3.0), dt = rng.Uniform(0.01, 1.0);
    // x += v dt cos(phi + w dt), ... is the body-frame motion (v dt cos(w dt), v dt sin(w dt), w dt).
    const Pose2 body{v * dt * std::cos(w * dt), v * dt * std::sin(w * dt), w * dt};
    ASSERT_THAT(UnicycleStep(p, v, w, dt), IsNearlyPose(Compose(p, body), kTol, kTol));
  }
}

TEST(Se2PropertyTest, UnicycleStepWithJacobiansMatchesTheStepAndNumericDifferences) {
  Rng rng(1, "se2/unicycle_jacobians");
  constexpr double kStep = 1e-6, kJacobianTol = 1e-6;  // central differences, as above
  for (int i = 0; i < kTrials; ++i) {
    const Pose2 p = RandomPose(rng);
    const double v = rng.Uniform(-2.0, 2.0), w = rng.Uniform(-3.0, 3.0), dt = rng.Uniform(0.01, 1.0);
    const LinearizedUnicycleStep j = UnicycleStepWithJacobians(p, v, w, dt);
    const Pose2 next = UnicycleStep(p, v, w, dt);  // the same expressions: equal to the bit
    ASSERT_EQ(j.next.x, next.x);
    ASSERT_EQ(j.next.y, next.y);
    ASSERT_EQ(j.next.heading, next.heading);
    // Difference of two steps as (dx, dy, wrapped dphi) over 2 kStep.
    auto slope = [](const Pose2& plus, const Pose2& minus) -> Eigen::Vector3d {
      return Eigen::Vector3d(plus.x - minus.x, plus.y - minus.y, WrapAngle(plus.heading - minus.heading)) / (2 * kStep);
    };
    Eigen::Matrix3d f;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      d(k) = kStep;
      f.col(k) = slope(UnicycleStep(Pose2{p.x + d.x(), p.y + d.y(), p.heading + d.z()}, v, w, dt),
                       UnicycleStep(Pose2{p.x - d.x(), p.y - d.y(), p.heading - d.z()}, v, w, dt));
    }
    Eigen::Matrix<double, 3, 2> g;
    g.col(0) = slope(UnicycleStep(p, v + kStep, w, dt), UnicycleStep(p, v - kStep, w, dt));
    g.col(1) = slope(UnicycleStep(p, v, w + kStep, dt), UnicycleStep(p, v, w - kStep, dt));
    ASSERT_LT((j.f - f).cwiseAbs().maxCoeff(), kJacobianTol) << j.f << "\nvs\n" << f;
    ASSERT_LT((j.g - g).cwiseAbs().maxCoeff(), kJacobianTol) << j.g << "\nvs\n" << g;
  }
}

}  // namespace
}  // namespace mrslam::common
