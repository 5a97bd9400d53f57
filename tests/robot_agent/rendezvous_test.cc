// The rendezvous maths: the transform from mutual detections, its Jacobians and consistency,
// chaining and split covariance intersection, and the alignment on common landmarks.
#include "robot_agent/cooperation/rendezvous.h"

#include <cmath>
#include <limits>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/gaussian.h"
#include "common/rng.h"
#include "tests/robot_agent/pose_sampling.h"
#include "tests/test_matchers.h"

namespace mrslam::robot_agent::cooperation {
namespace {

using mrslam::testing::IsNearlyPose;

// The true mutual detection between two robots given in one frame.
MutualDetection TrueMutual(const Pose2& robot_i, const Pose2& robot_j) {
  const common::RangeBearing ij = common::MeasureRangeBearing(robot_i, robot_j.Translation());
  const common::RangeBearing ji = common::MeasureRangeBearing(robot_j, robot_i.Translation());
  return {ij.range_m, ij.bearing_rad, ji.range_m, ji.bearing_rad, true};
}

struct RandomCase {
  Pose2 frame_i, frame_j;  // G_i, G_j in W
  Pose2 robot_i, robot_j;  // robots in W
  Pose2 Truth() const { return common::Compose(common::Inverse(frame_i), frame_j); }
  Pose2 PoseI() const { return common::Compose(common::Inverse(frame_i), robot_i); }
  Pose2 PoseJ() const { return common::Compose(common::Inverse(frame_j), robot_j); }
};

RandomCase MakeCase(common::Rng* rng) {
  RandomCase c;
  c.frame_i = {rng->Uniform(-10, 10), rng->Uniform(-10, 10), rng->Uniform(-3.1, 3.1)};
  c.frame_j = {rng->Uniform(-10, 10), rng->Uniform(-10, 10), rng->Uniform(-3.1, 3.1)};
  c.robot_i = {rng->Uniform(-10, 10), rng->Uniform(-10, 10), rng->Uniform(-3.1, 3.1)};
  const double r = rng->Uniform(0.5, 6.0), a = rng->Uniform(-3.1, 3.1);
  c.robot_j = {c.robot_i.x + r * std::cos(a), c.robot_i.y + r * std::sin(a), rng->Uniform(-3.1, 3.1)};
  return c;
}

// ---------------------------------------------------------------------------------------------
// Rendezvous maths.

TEST(Rendezvous, RelativePoseOfBothSidesAreInverses) {
  common::Rng rng(1, "relative");
  for (int trial = 0; trial < 1000; ++trial) {
    const RandomCase c = MakeCase(&rng);
    const MutualDetection z = TrueMutual(c.robot_i, c.robot_j);
    const MutualDetection swapped{z.range_ji_m, z.bearing_ji_rad, z.range_ij_m, z.bearing_ij_rad, true};
    const Pose2 ij = RelativePoseFromMutual(z, nullptr), ji = RelativePoseFromMutual(swapped, nullptr);
    EXPECT_THAT(common::Compose(ij, ji), IsNearlyPose(Pose2{}, 1e-9, 1e-9));
    EXPECT_THAT(ij, IsNearlyPose(common::Between(c.robot_i, c.robot_j), 1e-9, 1e-9));
  }
}

TEST(Rendezvous, TransformIsExactWithoutNoise) {
  common::Rng rng(2, "exact");
  const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() * 1e-4;
  for (int trial = 0; trial < 1000; ++trial) {
    const RandomCase c = MakeCase(&rng);
    const TransformEstimate t =
        TransformFromMutual(c.PoseI(), p, c.PoseJ(), p, TrueMutual(c.robot_i, c.robot_j), 1e-4, 1e-4);
    EXPECT_THAT(t.t, IsNearlyPose(c.Truth(), 1e-9, 1e-9));
    EXPECT_TRUE(common::IsSymmetricPositiveDefinite<3>(t.Covariance()));
  }
}

TEST(Rendezvous, JacobiansMatchNumericDifferences) {
  common::Rng rng(3, "jacobians");
  for (int trial = 0; trial < 100; ++trial) {
    const RandomCase c = MakeCase(&rng);
    MutualDetection z = TrueMutual(c.robot_i, c.robot_j);
    Eigen::Matrix<double, 3, 4> j;
    const Pose2 base = RelativePoseFromMutual(z, &j);
    const double h = 1e-6;
    double* fields[4] = {&z.range_ij_m, &z.bearing_ij_rad, &z.range_ji_m, &z.bearing_ji_rad};
    for (int k = 0; k < 4; ++k) {
      MutualDetection zp = z;
      double* fp[4] = {&zp.range_ij_m, &zp.bearing_ij_rad, &zp.range_ji_m, &zp.bearing_ji_rad};
      *fp[k] = *fields[k] + h;
      const Eigen::Vector3d d = PoseError(RelativePoseFromMutual(zp, nullptr), base) / h;
      EXPECT_LT((d - j.col(k)).norm(), 1e-4) << "column " << k;
    }
    const Pose2 a = c.PoseI();
    const Eigen::Matrix3d ji = InverseJacobian(a);
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d v = a.Vector();
      v(k) += h;
      const Eigen::Vector3d d = PoseError(common::Inverse(Pose2{v.x(), v.y(), v.z()}), common::Inverse(a)) / h;
      EXPECT_LT((d - ji.col(k)).norm(), 1e-4);
    }
  }
}

// Normalized estimation error squared over many seeded trials with noisy poses and readings:
// the mean must be 3 (chi-square, 3 dof) within its sampling spread.
TEST(Rendezvous, TransformIsConsistentWithNoise) {
  common::Rng rng(4, "nees");
  constexpr int kTrials = 4000;
  const double sd_r = 0.03, sd_b = 0.02;
  double nees_sum = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const RandomCase c = MakeCase(&rng);
    Eigen::Matrix3d pi = Eigen::Matrix3d::Zero(), pj = Eigen::Matrix3d::Zero();
    pi.diagonal() << std::pow(rng.Uniform(0.01, 0.05), 2), std::pow(rng.Uniform(0.01, 0.05), 2),
        std::pow(rng.Uniform(0.005, 0.02), 2);
    pj.diagonal() << std::pow(rng.Uniform(0.01, 0.05), 2), std::pow(rng.Uniform(0.01, 0.05), 2),
        std::pow(rng.Uniform(0.005, 0.02), 2);
    const Pose2 est_i = SamplePose(&rng, c.PoseI(), pi), est_j = SamplePose(&rng, c.PoseJ(), pj);
    MutualDetection z = TrueMutual(c.robot_i, c.robot_j);
    z.range_ij_m += rng.Normal(0, sd_r);
    z.range_ji_m += rng.Normal(0, sd_r);
    z.bearing_ij_rad += rng.Normal(0, sd_b);
    z.bearing_ji_rad += rng.Normal(0, sd_b);
    const TransformEstimate t = TransformFromMutual(est_i, pi, est_j, pj, z, sd_r * sd_r, sd_b * sd_b);
    nees_sum += Nees(t.t, c.Truth(), t.Covariance());
  }
  const double mean = nees_sum / kTrials;  // sd of the mean: sqrt(6 / 4000) = 0.039
  EXPECT_GT(mean, 3.0 - 0.2);
  EXPECT_LT(mean, 3.0 + 0.2);
}

TEST(Rendezvous, BothSidesComputeInverseTransforms) {
  common::Rng rng(5, "sides");
  for (int trial = 0; trial < 500; ++trial) {
    const RandomCase c = MakeCase(&rng);
    Eigen::Matrix3d pi = Eigen::Matrix3d::Identity() * 4e-4, pj = Eigen::Matrix3d::Identity() * 9e-4;
    pi(2, 2) = 1e-4;
    const Pose2 est_i = SamplePose(&rng, c.PoseI(), pi), est_j = SamplePose(&rng, c.PoseJ(), pj);
    MutualDetection z = TrueMutual(c.robot_i, c.robot_j);
    z.range_ij_m += rng.Normal(0, 0.03);
    z.bearing_ji_rad += rng.Normal(0, 0.03);
    const MutualDetection swapped{z.range_ji_m, z.bearing_ji_rad, z.range_ij_m, z.bearing_ij_rad, true};
    const TransformEstimate ij = TransformFromMutual(est_i, pi, est_j, pj, z, 1e-3, 1e-3);
    const TransformEstimate ji = TransformFromMutual(est_j, pj, est_i, pi, swapped, 1e-3, 1e-3);
    EXPECT_THAT(common::Compose(ij.t, ji.t), IsNearlyPose(Pose2{}, 1e-9, 1e-9));
    const TransformEstimate inv = InvertTransform(ij);
    EXPECT_LT((inv.Covariance() - ji.Covariance()).norm(), 1e-9 * (1.0 + ji.Covariance().norm()));
  }
}

TEST(Rendezvous, ChainedTransformIsExactAndConsistent) {
  common::Rng rng(6, "chain");
  constexpr int kTrials = 3000;
  double nees_sum = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const RandomCase c = MakeCase(&rng);
    const Pose2 frame_k{rng.Uniform(-10, 10), rng.Uniform(-10, 10), rng.Uniform(-3, 3)};
    const Pose2 t_ij = c.Truth(), t_jk = common::Compose(common::Inverse(c.frame_j), frame_k);
    TransformEstimate a, b;
    a.t = t_ij;
    a.dependent = Eigen::Matrix3d::Identity() * 1e-3;
    b.t = t_jk;
    b.independent = Eigen::Matrix3d::Identity() * 2e-3;
    const TransformEstimate exact = ChainTransforms(a, b);
    EXPECT_THAT(exact.t, IsNearlyPose(common::Compose(common::Inverse(c.frame_i), frame_k), 1e-9, 1e-9));
    TransformEstimate na = a, nb = b;
    na.t = SamplePose(&rng, t_ij, a.Covariance());
    nb.t = SamplePose(&rng, t_jk, b.Covariance());
    const TransformEstimate noisy = ChainTransforms(na, nb);
    nees_sum += Nees(noisy.t, exact.t, noisy.Covariance());
  }
  EXPECT_GT(nees_sum / kTrials, 2.8);
  EXPECT_LT(nees_sum / kTrials, 3.2);
}

// Split CI of estimates that share a pose error (the same drifting filters) and have
// independent measurement noise: consistent, and tighter than either input.
TEST(Rendezvous, SplitCiIsConsistentForSharedPoseErrors) {
  common::Rng rng(8, "sci");
  constexpr int kTrials = 3000, kRepeats = 8;
  double nees_sum = 0.0, naive_sum = 0.0;
  const Eigen::Matrix3d dep = Eigen::Vector3d(0.01, 0.01, 0.002).asDiagonal();
  const Eigen::Matrix3d ind = Eigen::Vector3d(0.004, 0.004, 0.001).asDiagonal();
  for (int trial = 0; trial < kTrials; ++trial) {
    const Pose2 truth{rng.Uniform(-5, 5), rng.Uniform(-5, 5), rng.Uniform(-3, 3)};
    const Pose2 shared = SamplePose(&rng, Pose2{}, dep);  // one error shared by all repeats
    TransformEstimate fused, naive;
    for (int k = 0; k < kRepeats; ++k) {
      TransformEstimate e;
      e.t = Pose2::FromVector(SamplePose(&rng, truth, ind).Vector() + shared.Vector());
      e.dependent = dep;
      e.independent = ind;
      if (k == 0) {
        fused = e;
        naive = e;
        continue;
      }
      const TransformEstimate before = fused;
      fused = FuseSplitCi(fused, e);
      EXPECT_LE(fused.Covariance().trace(), before.Covariance().trace() + 1e-12);
      // Naive information fusion that counts the shared error as independent.
      TransformEstimate a = naive, b = e;
      a.independent = naive.Covariance();
      a.dependent.setZero();
      b.independent = e.Covariance();
      b.dependent.setZero();
      naive = FuseSplitCi(a, b);
    }
    nees_sum += Nees(fused.t, truth, fused.Covariance());
    naive_sum += Nees(naive.t, truth, naive.Covariance());
  }
  EXPECT_LT(nees_sum / kTrials, 3.0 * 1.1);
  EXPECT_GT(naive_sum / kTrials, 3.0 * 1.5);  // the overconfidence SCI avoids
}

TEST(Rendezvous, ChiSquare3Quantile) {
  EXPECT_NEAR(ChiSquare3Quantile(0.95), 7.8147, 1e-3);
  EXPECT_NEAR(ChiSquare3Quantile(0.999), 16.266, 1e-2);
}

// ---------------------------------------------------------------------------------------------
// Alignment on common landmarks.

// One alignment problem: n landmarks (every other one moving, with a known heading) seen by two
// maps whose frames are a and b, T = T(G_a <- G_b) the truth. Each map's landmarks share one
// rigid error of that map (drawn from `shared`, standing for the robot's pose error that every
// landmark it mapped carries) plus independent noise of sd noise_sd (position, and heading). The
// prior is the truth perturbed by both maps' shared errors (the pose composition carries the
// same errors) and an independent error drawn from prior_independent; every covariance reported
// is the true one to first order.
struct AlignmentCase {
  Pose2 truth;
  TransformEstimate prior;
  std::vector<LandmarkPair> pairs;
};

AlignmentCase MakeAlignmentCase(common::Rng* rng, int n, const Eigen::Matrix3d& shared, double noise_sd,
                                const Eigen::Matrix3d& prior_independent) {
  AlignmentCase c;
  // A draw around mean (mean itself for a zero covariance).
  const auto perturb = [&](const Pose2& mean, const Eigen::Matrix3d& cov) {
    return cov.isZero() ? mean : SamplePose(rng, mean, cov);
  };
  c.truth = {rng->Uniform(-5, 5), rng->Uniform(-5, 5), rng->Uniform(-3.1, 3.1)};
  const Pose2 error_a = perturb(Pose2{}, shared), error_b = perturb(Pose2{}, shared);
  const Eigen::Matrix3d noise = Eigen::Vector3d::Constant(noise_sd * noise_sd).asDiagonal();
  // A landmark pose as a map with frame error `error` holds it, and the covariance of that.
  const auto mapped = [&](const Pose2& truth, const Pose2& error, Eigen::Vector3d* mean, Eigen::Matrix3d* cov) {
    const Pose2 noisy = perturb(common::Compose(error, truth), noise);
    *mean = noisy.Vector();
    const Eigen::Matrix3d j = common::ComposeJacobianLeft(Pose2{}, truth);
    *cov = j * shared * j.transpose() + noise;
  };
  for (int l = 0; l < n; ++l) {
    const Pose2 in_b{rng->Uniform(-6, 6), rng->Uniform(-6, 6), rng->Uniform(-3.1, 3.1)};
    LandmarkPair pair;
    mapped(common::Compose(c.truth, in_b), error_a, &pair.in_a, &pair.covariance_a);
    mapped(in_b, error_b, &pair.in_b, &pair.covariance_b);
    pair.use_heading = l % 2 == 1;
    c.pairs.push_back(pair);
  }
  // prior = error_a * T * error_b^-1 * independent error, covariance by first-order chaining.
  TransformEstimate a, t, b;
  a.dependent = shared;
  t.t = c.truth;
  b.dependent = shared;
  const TransformEstimate chained = ChainTransforms(ChainTransforms(a, t), InvertTransform(b));
  c.prior.t = common::Compose(common::Compose(common::Compose(error_a, c.truth), common::Inverse(error_b)),
                              perturb(Pose2{}, prior_independent));
  c.prior.dependent = chained.Covariance();
  c.prior.independent = prior_independent;
  return c;
}

TEST(Alignment, ExactWithoutNoise) {
  common::Rng rng(31, "align");
  for (int trial = 0; trial < 100; ++trial) {
    // Exact maps (covariances 1e-12), a prior off by decimetres: the landmarks decide.
    AlignmentCase c = MakeAlignmentCase(&rng, 2 + trial % 5, Eigen::Matrix3d::Zero(), 0.0, Eigen::Matrix3d::Zero());
    for (auto& p : c.pairs) {
      p.covariance_a = 1e-12 * Eigen::Matrix3d::Identity();
      p.covariance_b = 1e-12 * Eigen::Matrix3d::Identity();
    }
    c.prior.t = common::Compose(c.truth, Pose2{0.3, -0.2, 0.1});
    c.prior.dependent = Eigen::Vector3d(0.09, 0.09, 0.01).asDiagonal();
    c.prior.independent = Eigen::Vector3d(0.01, 0.01, 0.001).asDiagonal();
    const std::optional<TransformEstimate> aligned = AlignLandmarks(c.prior, c.pairs);
    ASSERT_TRUE(aligned.has_value());
    EXPECT_THAT(aligned->t, IsNearlyPose(c.truth, 1e-6, 1e-6)) << "trial " << trial;
    // One moving landmark with its heading fixes the transform on its own.
    const std::optional<TransformEstimate> one = AlignLandmarks(c.prior, {c.pairs[1]});
    ASSERT_TRUE(one.has_value());
    EXPECT_THAT(one->t, IsNearlyPose(c.truth, 1e-6, 1e-6)) << "trial " << trial;
  }
  TransformEstimate prior;
  prior.dependent = Eigen::Matrix3d::Identity();
  EXPECT_FALSE(AlignLandmarks(prior, {}).has_value());
}

// Independent landmark noise: the alignment is consistent and close to the best any estimator
// can do with these landmarks (the Cramer-Rao bound of the landmarks alone, from the information
// sum J^T S^-1 J at the truth). It may not reach the bound: the landmarks are weighted as if
// their errors could be correlated (1 / N each), so the prior keeps a say; 1.5 times the bound
// is far below the prior's own error (0.42 m, 0.1 rad).
TEST(Alignment, RecoversTheTransformFromNoisyLandmarks) {
  common::Rng rng(32, "align");
  constexpr int kTrials = 1000, kLandmarks = 8;
  const Eigen::Matrix3d prior_cov = Eigen::Vector3d(0.09, 0.09, 0.01).asDiagonal();
  double nees_sum = 0.0, translation_sq = 0.0, heading_sq = 0.0, bound_translation = 0.0, bound_heading = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    AlignmentCase c = MakeAlignmentCase(&rng, kLandmarks, Eigen::Matrix3d::Zero(), 0.05, prior_cov);
    const std::optional<TransformEstimate> aligned = AlignLandmarks(c.prior, c.pairs);
    ASSERT_TRUE(aligned.has_value());
    const Eigen::Vector3d e = PoseError(aligned->t, c.truth);
    translation_sq += e.head<2>().squaredNorm();
    heading_sq += e.z() * e.z();
    nees_sum += Nees(aligned->t, c.truth, aligned->Covariance());
    Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
    for (const auto& p : c.pairs) {
      const Pose2 l_b{p.in_b.x(), p.in_b.y(), p.in_b.z()};
      const Eigen::Matrix3d j = common::ComposeJacobianLeft(c.truth, l_b);
      const Eigen::Matrix3d jr = common::ComposeJacobianRight(c.truth, l_b);
      const Eigen::Matrix3d s = p.covariance_a + jr * p.covariance_b * jr.transpose();
      Eigen::Matrix3d w = Eigen::Matrix3d::Zero();
      if (p.use_heading) {
        w = s.inverse();
      } else {
        w.topLeftCorner<2, 2>() = s.topLeftCorner<2, 2>().inverse();
      }
      info += j.transpose() * w * j;
    }
    const Eigen::Matrix3d crb = info.inverse();
    bound_translation += crb(0, 0) + crb(1, 1);
    bound_heading += crb(2, 2);
  }
  EXPECT_LT(nees_sum / kTrials, 3.0);
  EXPECT_LT(std::sqrt(translation_sq / kTrials), 1.5 * std::sqrt(bound_translation / kTrials));
  EXPECT_LT(std::sqrt(heading_sq / kTrials), 1.5 * std::sqrt(bound_heading / kTrials));
}

// Each map's landmarks share that map's error, and the prior shares both: the landmarks are
// not independent of each other nor of the prior. Counting them as independent would be
// overconfident; the alignment stays consistent.
TEST(Alignment, ConsistentWhenLandmarksShareTheMapsErrors) {
  common::Rng rng(33, "align");
  constexpr int kTrials = 2000;
  const Eigen::Matrix3d shared = Eigen::Vector3d(0.04, 0.04, 0.0025).asDiagonal();
  const Eigen::Matrix3d independent = Eigen::Vector3d(0.01, 0.01, 0.001).asDiagonal();
  double nees_sum = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const AlignmentCase c = MakeAlignmentCase(&rng, 1 + trial % 10, shared, 0.05, independent);
    const std::optional<TransformEstimate> aligned = AlignLandmarks(c.prior, c.pairs);
    ASSERT_TRUE(aligned.has_value());
    EXPECT_LE(aligned->Covariance().determinant(), c.prior.Covariance().determinant() * (1.0 + 1e-6));
    nees_sum += Nees(aligned->t, c.truth, aligned->Covariance());
  }
  EXPECT_LT(nees_sum / kTrials, 3.0 * 1.1);
}

// The other side aligns the same landmarks the other way round from the inverse prior: it gets
// the inverse transform (up to the linearization of the prior's inverse).
TEST(Alignment, BothSidesGetInverseTransforms) {
  common::Rng rng(34, "align");
  const Eigen::Matrix3d shared = Eigen::Vector3d(0.04, 0.04, 0.0025).asDiagonal();
  const Eigen::Matrix3d independent = Eigen::Vector3d(0.01, 0.01, 0.001).asDiagonal();
  for (int trial = 0; trial < 200; ++trial) {
    const AlignmentCase c = MakeAlignmentCase(&rng, 1 + trial % 6, shared, 0.05, independent);
    std::vector<LandmarkPair> swapped;
    for (const auto& p : c.pairs) swapped.push_back({p.in_b, p.covariance_b, p.in_a, p.covariance_a, p.use_heading});
    const std::optional<TransformEstimate> ab = AlignLandmarks(c.prior, c.pairs);
    const std::optional<TransformEstimate> ba = AlignLandmarks(InvertTransform(c.prior), swapped);
    ASSERT_TRUE(ab.has_value() && ba.has_value());
    EXPECT_THAT(common::Compose(ab->t, ba->t), IsNearlyPose(Pose2{}, 0.01, 0.01)) << "trial " << trial;
  }
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
