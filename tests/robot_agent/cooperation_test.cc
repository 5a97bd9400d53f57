#include "robot_agent/cooperation/cooperation.h"

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>
#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/config/agent_options_projection.h"
#include "common/gaussian.h"
#include "common/rng.h"
#include "robot_agent/cooperation/rendezvous.h"
#include "robot_agent/filters/fastslam.h"
#include "robot_agent/filters/filter_factory.h"
#include "robot_agent/filters/map_fusion.h"
#include "tests/robot_agent/tiny_world.h"
#include "tests/test_matchers.h"

namespace mrslam::robot_agent::cooperation {
namespace {

using mrslam::testing::IsNearlyPose;

using common::Pose2;

// ---------------------------------------------------------------------------------------------
// Helpers.

Eigen::Vector3d PoseError(const Pose2& estimate, const Pose2& truth) {
  return {estimate.x - truth.x, estimate.y - truth.y, common::WrapAngle(estimate.heading - truth.heading)};
}

double Nees(const Pose2& estimate, const Pose2& truth, const Eigen::Matrix3d& cov) {
  const Eigen::Vector3d e = PoseError(estimate, truth);
  return e.dot(cov.ldlt().solve(e));
}

Pose2 SamplePose(common::Rng* rng, const Pose2& mean, const Eigen::Matrix3d& cov) {
  const Eigen::LLT<Eigen::Matrix3d> llt(cov);
  const Eigen::Vector3d n(rng->Normal(), rng->Normal(), rng->Normal());
  return Pose2::FromVector(mean.Vector() + llt.matrixL() * n);
}

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

// ---------------------------------------------------------------------------------------------
// Cooperation among agents, in process, with a fake filter.

// A filter whose estimate the test sets; merges like FastSLAM's rule for one hypothesis.
class FakeFilter : public filters::SlamFilter {
 public:
  void Process(const common::SensorStep&) override {}
  filters::FilterEstimate Estimate() const override { return estimate; }
  int MergeLandmarks(const std::vector<filters::MapLandmark>& in, robot_agent::MapFusionRule rule,
                     double gate_probability, double /*too_close_m*/) override {
    ++merges;
    std::vector<filters::MatchCandidate> own, incoming;
    for (const auto& l : estimate.landmarks)
      own.push_back({l.mean.head<2>(), l.covariance.topLeftCorner<2, 2>(), l.landmark_id});
    for (const auto& l : in) incoming.push_back({l.mean.head<2>(), l.covariance.topLeftCorner<2, 2>(), l.landmark_id});
    const std::vector<int> match = filters::MatchLandmarks(own, incoming, common::ChiSquare2Quantile(gate_probability));
    int added = 0;
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (match[i] < 0) {
        estimate.landmarks.push_back(in[i]);
        estimate.landmarks.back().track_id = 1000 + added;
        ++added;
        continue;
      }
      filters::MapLandmark& l = estimate.landmarks[match[i]];
      Eigen::VectorXd x = l.mean.head<2>();
      Eigen::MatrixXd p = l.covariance.topLeftCorner<2, 2>();
      filters::FuseObservation(&x, &p, in[i].mean.head<2>(), in[i].covariance.topLeftCorner<2, 2>(), rule);
      l.mean.head<2>() = x;
      l.covariance.topLeftCorner<2, 2>() = p;
    }
    return added;
  }
  bool ObserveKnownRobot(const Eigen::Vector2d&, const Eigen::Matrix2d&, double, double, double) override {
    ++robot_observations;
    return true;
  }
  bool ApplyMovedNotice(const Eigen::Vector2d& position, const Eigen::Matrix2d& cov, double) override {
    notices.emplace_back(position, cov);
    return true;
  }

  filters::FilterEstimate estimate;
  int merges = 0;
  int robot_observations = 0;
  std::vector<std::pair<Eigen::Vector2d, Eigen::Matrix2d>> notices;
};

common::ScenarioOptions Scenario(int robots) {
  common::ScenarioOptions s;
  s.name = "cooperation_test";
  const Pose2 frames[3] = {{0.0, 0.0, 0.0}, {0.347, 2.209, -0.6194}, {-3.0, 1.0, 2.0}};
  for (int i = 0; i < robots; ++i) {
    common::RobotOptions r;
    r.id = "r" + std::to_string(i + 1);
    r.frame_in_world = frames[i];
    s.robots.push_back(r);
  }
  s.sensors.lidar.range_noise_sd_m = 0.03;
  s.sensors.lidar.bearing_noise_sd_rad = 0.03;
  s.rendezvous.enable_from_step = 14;
  s.rendezvous.window_steps = 1;
  s.rendezvous.min_interval_steps = 20;
  return s;
}

// N agents with fake filters in a small world; the test says when two robots see each other.
// Pose estimates are the truth in each robot's frame plus noise drawn from the covariance they
// report, so every number the agents exchange is consistent by construction.
class Sim {
 public:
  using Contact = std::function<bool(std::uint32_t step, int i, int j)>;
  Sim(common::ScenarioOptions scenario, Contact contact, std::uint64_t seed)
      : scenario_(std::move(scenario)), contact_(std::move(contact)), rng_(seed, "sim") {
    // Landmarks in W; robot i knows landmarks i and i + 1 (neighbours share one).
    for (int l = 0; l < static_cast<int>(scenario_.robots.size()) + 1; ++l) {
      landmarks_.push_back({3.0 * l - 2.0, 4.0 - l});
    }
    for (std::size_t i = 0; i < scenario_.robots.size(); ++i) {
      agents_.push_back(std::make_unique<Cooperation>(common::AgentOptionsFor(scenario_, scenario_.robots[i].id)));
      filters_.push_back(std::make_unique<FakeFilter>());
      for (std::size_t l = i; l <= i + 1; ++l) {
        filters::MapLandmark m;
        m.track_id = static_cast<std::uint32_t>(l + 1);
        const Eigen::Vector2d p = common::TransformPoint(common::Inverse(Frame(i)), landmarks_[l]);
        m.covariance = Eigen::Vector3d(1e-3, 1e-3, 1.0).asDiagonal();
        m.mean = {p.x() + rng_.Normal(0, std::sqrt(1e-3)), p.y() + rng_.Normal(0, std::sqrt(1e-3)), 0.0};
        filters_[i]->estimate.landmarks.push_back(m);
      }
    }
    inbox_.resize(scenario_.robots.size());
    pose_error_.resize(scenario_.robots.size());
  }

  Pose2 Frame(std::size_t i) const { return scenario_.robots[i].frame_in_world; }
  // Robot i in W at step k: circles near the origin, so every pair is within lidar range.
  Pose2 Truth(std::size_t i, std::uint32_t k) const {
    const double a = 0.15 * k + 2.0 * static_cast<double>(i);
    const Eigen::Vector2d center(1.2 * static_cast<double>(i), 0.5 * static_cast<double>(i));
    return {center.x() + 1.5 * std::cos(a), center.y() + 1.5 * std::sin(a), common::WrapAngle(a + common::kPi / 2)};
  }
  Pose2 TrueTransform(std::size_t i, std::size_t j) const {
    return common::Compose(common::Inverse(Frame(i)), Frame(j));
  }

  void Run(std::uint32_t steps) {
    for (std::uint32_t k = step_ + 1; k <= step_ + steps; ++k) StepOnce(k);
    step_ += steps;
  }

  Cooperation& agent(std::size_t i) { return *agents_[i]; }
  FakeFilter& filter(std::size_t i) { return *filters_[i]; }
  std::uint32_t step() const { return step_; }
  const std::vector<Eigen::Vector2d>& landmarks() const { return landmarks_; }
  // From now on robot i's pose estimates are off by this (in its body frame): a lost robot
  // whose covariance does not say so.
  void SetPoseError(std::size_t i, const Pose2& error) { pose_error_[i] = error; }
  int sent_maps = 0;

 private:
  void StepOnce(std::uint32_t k) {
    const std::size_t n = agents_.size();
    std::vector<PeerInbox> next(n);
    for (std::size_t i = 0; i < n; ++i) {
      agents_[i]->Receive(inbox_[i], filters_[i].get());
      const Eigen::Matrix3d cov = Eigen::Vector3d(4e-4, 4e-4, 1e-4).asDiagonal();
      filters::FilterEstimate& e = filters_[i]->estimate;
      e.step = k;
      e.time_s = 0.65 * k;
      e.covariance = cov;
      e.pose = common::Compose(SamplePose(&rng_, common::Compose(common::Inverse(Frame(i)), Truth(i, k)), cov),
                               pose_error_[i]);
      common::LidarScan scan;
      scan.stamp = {scenario_.robots[i].id, k, e.time_s};
      for (std::size_t j = 0; j < n; ++j) {
        if (j == i || !contact_(k, static_cast<int>(std::min(i, j)), static_cast<int>(std::max(i, j)))) continue;
        const common::RangeBearing z = common::MeasureRangeBearing(Truth(i, k), Truth(j, k).Translation());
        scan.robots.push_back({e.time_s, z.range_m + rng_.Normal(0, 0.03),
                               common::WrapAngle(z.bearing_rad + rng_.Normal(0, 0.03)), scenario_.robots[j].id});
      }
      common::SensorStep step;
      step.lidar = scan;
      const PeerOutbox out = agents_[i]->AfterStep(step, filters_[i]->Estimate());
      for (const auto& m : out.measurements) next[Index(m.header.recipient)].measurements.push_back(m);
      for (const auto& m : out.maps) {
        next[Index(m.header.recipient)].maps.push_back(m);
        ++sent_maps;
      }
    }
    inbox_ = std::move(next);
  }
  std::size_t Index(const std::string& id) const { return static_cast<std::size_t>(scenario_.RobotIndex(id)); }

  common::ScenarioOptions scenario_;
  Contact contact_;
  common::Rng rng_;
  std::vector<Eigen::Vector2d> landmarks_;
  std::vector<std::unique_ptr<Cooperation>> agents_;
  std::vector<std::unique_ptr<FakeFilter>> filters_;
  std::vector<PeerInbox> inbox_;
  std::vector<Pose2> pose_error_;
  std::uint32_t step_ = 0;
};

// The transform an agent holds to peer (a copy), if any.
std::optional<FrameTransform> Find(const std::vector<FrameTransform>& ts, const std::string& peer) {
  for (const auto& t : ts) {
    if (t.peer == peer) return t;
  }
  return std::nullopt;
}

TEST(Cooperation, TwoAgentsMeetAgreeAndMergeMaps) {
  // In sight of each other from step 5 to 30 (the detector acts from step 14).
  Sim sim(
      Scenario(2), [](std::uint32_t k, int, int) { return k >= 5 && k <= 30; }, 21);
  sim.Run(14);
  EXPECT_TRUE(sim.agent(0).rendezvous().empty());  // step 14's messages arrive at 15
  sim.Run(1);
  ASSERT_EQ(sim.agent(0).rendezvous().size(), 1u);
  ASSERT_EQ(sim.agent(1).rendezvous().size(), 1u);
  EXPECT_EQ(sim.agent(0).rendezvous()[0].peer, "r2");
  EXPECT_EQ(sim.agent(1).rendezvous()[0].peer, "r1");
  EXPECT_EQ(sim.agent(0).rendezvous()[0].step, 14u);
  EXPECT_EQ(sim.agent(1).rendezvous()[0].step, 14u);
  EXPECT_EQ(sim.agent(0).frames_known(), std::vector<std::string>{"r2"});
  EXPECT_EQ(sim.sent_maps, 2);  // one snapshot each way, in AfterStep of step 15
  EXPECT_EQ(sim.filter(0).merges, 0);
  sim.Run(1);
  EXPECT_EQ(sim.filter(0).merges, 1);
  EXPECT_EQ(sim.filter(1).merges, 1);
  // Each knew 2 landmarks, one shared: the merged maps hold 3, in the right place.
  for (std::size_t i = 0; i < 2; ++i) {
    ASSERT_EQ(sim.filter(i).estimate.landmarks.size(), 3u) << "robot " << i;
    for (const auto& l : sim.filter(i).estimate.landmarks) {
      double best = std::numeric_limits<double>::infinity();
      for (const auto& truth : sim.landmarks()) {
        const Eigen::Vector2d in_own = common::TransformPoint(common::Inverse(sim.Frame(i)), truth);
        best = std::min(best, (in_own - l.mean.head<2>()).norm());
      }
      EXPECT_LT(best, 0.3);
    }
  }
  sim.Run(30);
  // One continuous contact: one rendezvous, refined; later contact steps change nothing else.
  ASSERT_EQ(sim.agent(0).rendezvous().size(), 1u);
  EXPECT_EQ(sim.sent_maps, 2);
  const RendezvousEvent& e01 = sim.agent(0).rendezvous()[0];
  const RendezvousEvent& e10 = sim.agent(1).rendezvous()[0];
  EXPECT_THAT(common::Compose(e01.t_self_peer, e10.t_self_peer), IsNearlyPose(Pose2{}, 0.01, 0.01));
  EXPECT_LT(Nees(e01.t_self_peer, sim.TrueTransform(0, 1), e01.covariance), 16.3);  // chi2(3) 0.999
  const std::optional<FrameTransform> t01 = Find(sim.agent(0).known_transforms(), "r2");
  const std::optional<FrameTransform> t10 = Find(sim.agent(1).known_transforms(), "r1");
  ASSERT_TRUE(t01.has_value());
  ASSERT_TRUE(t10.has_value());
  EXPECT_THAT(common::Compose(t01->t_self_peer, t10->t_self_peer), IsNearlyPose(Pose2{}, 0.01, 0.01));
  EXPECT_LT(Nees(t01->t_self_peer, sim.TrueTransform(0, 1), t01->covariance), 16.3);
  EXPECT_EQ(sim.agent(0).rejected_messages(), 0);
  EXPECT_EQ(sim.agent(1).rejected_messages(), 0);
}

// A landmark of the own map goes into snapshots once it has been seen over
// cooperation.min_seen_span_steps (6) steps; one a peer passed on goes as it came.
TEST(Cooperation, OwnLandmarksAreSharedOnceSeenLongEnough) {
  // r1's first landmark is its own alone; r2 holds the second and third. Seen from step
  // `first` to step 12, by r1 itself or (origin 2) by r3, which r1 met earlier.
  const auto r2_landmarks_after_merge = [](std::uint32_t first, int origin) {
    Sim sim(
        Scenario(3), [](std::uint32_t k, int i, int j) { return i == 0 && j == 1 && k >= 5 && k <= 30; }, 21);
    filters::MapLandmark& l = sim.filter(0).estimate.landmarks[0];
    l.origin_robot = origin;
    l.origin_track = l.track_id;
    l.first_seen_step = first;
    l.last_seen_step = 12;
    sim.Run(16);
    EXPECT_EQ(sim.filter(1).merges, 1);
    return sim.filter(1).estimate.landmarks.size();
  };
  EXPECT_EQ(r2_landmarks_after_merge(7, 0), 2u);  // seen over 5 steps: withheld
  EXPECT_EQ(r2_landmarks_after_merge(6, 0), 3u);  // over 6: shared and added
  EXPECT_EQ(r2_landmarks_after_merge(7, 2), 3u);  // r3's: passed on
}

// The refined transform stays consistent over seeds and is more precise than one detection.
TEST(Cooperation, RefinedTransformIsConsistentOverSeeds) {
  double nees_sum = 0.0;
  constexpr int kSeeds = 200;
  for (int seed = 0; seed < kSeeds; ++seed) {
    Sim sim(
        Scenario(2), [](std::uint32_t k, int, int) { return k >= 14 && k <= 24; }, 100 + seed);
    sim.Run(26);
    const RendezvousEvent& e = sim.agent(0).rendezvous().at(0);
    nees_sum += Nees(e.t_self_peer, sim.TrueTransform(0, 1), e.covariance);
  }
  EXPECT_LT(nees_sum / kSeeds, 3.0 * 1.2);
}

TEST(Cooperation, RendezvousRepeatsOnlyAfterTheMinimumInterval) {
  // Contacts at 14-16, 25-26 (too soon: refines, no event), 40-41 (a second rendezvous).
  Sim sim(
      Scenario(2),
      [](std::uint32_t k, int, int) { return (k >= 14 && k <= 16) || (k >= 25 && k <= 26) || (k >= 40 && k <= 41); },
      5);
  sim.Run(50);
  ASSERT_EQ(sim.agent(0).rendezvous().size(), 2u);
  EXPECT_EQ(sim.agent(0).rendezvous()[1].step, 40u);
  EXPECT_EQ(sim.agent(1).rendezvous()[1].step, 40u);
  EXPECT_EQ(sim.sent_maps, 4);
  EXPECT_EQ(sim.filter(0).merges, 2);
}

// A snapshot is merged only while the sender's mutual detections agree with the transform held
// to its frame: here r2 is 1.5 m and 0.3 rad off in its own frame at the second rendezvous (its
// covariance does not say so), the detections fall outside the transform gate, and neither
// robot merges the other's map there; the frames stay known.
TEST(Cooperation, NoMergeWhileTheSendersDetectionsDisagreeWithTheTransform) {
  for (const bool lost : {false, true}) {
    Sim sim(
        Scenario(2), [](std::uint32_t k, int, int) { return (k >= 14 && k <= 16) || (k >= 40 && k <= 41); }, 5);
    sim.Run(30);
    EXPECT_EQ(sim.filter(0).merges, 1);
    if (lost) sim.SetPoseError(1, {1.5, 0.0, 0.3});
    sim.Run(20);
    ASSERT_EQ(sim.agent(0).rendezvous().size(), 2u);
    EXPECT_EQ(sim.sent_maps, 4);
    EXPECT_EQ(sim.filter(0).merges, lost ? 1 : 2) << "lost " << lost;
    EXPECT_EQ(sim.filter(1).merges, lost ? 1 : 2) << "lost " << lost;
    EXPECT_EQ(sim.agent(0).frames_known(), std::vector<std::string>{"r2"});
  }
}

TEST(Cooperation, NothingBeforeTheDetectorIsEnabled) {
  Sim sim(
      Scenario(2), [](std::uint32_t k, int, int) { return k < 14; }, 5);
  sim.Run(20);
  EXPECT_TRUE(sim.agent(0).rendezvous().empty());
  EXPECT_TRUE(sim.agent(0).frames_known().empty());
}

TEST(Cooperation, FramesChainThroughPeers) {
  // r1-r2 meet at 14; r2-r3 at 20; r1-r2 again at 40 (r2's snapshot carries T(G2 <- G3)).
  Sim sim(
      Scenario(3),
      [](std::uint32_t k, int i, int j) {
        if (i == 0 && j == 1) return (k >= 14 && k <= 15) || (k >= 40 && k <= 41);
        if (i == 1 && j == 2) return k >= 20 && k <= 21;
        return false;
      },
      9);
  sim.Run(30);
  EXPECT_EQ(sim.agent(0).frames_known(), std::vector<std::string>{"r2"});
  // r3 learnt r1's frame from r2's snapshot at their rendezvous, never meeting r1.
  EXPECT_EQ(sim.agent(2).frames_known(), (std::vector<std::string>{"r1", "r2"}));
  sim.Run(20);
  EXPECT_EQ(sim.agent(0).frames_known(), (std::vector<std::string>{"r2", "r3"}));
  const std::optional<FrameTransform> t13 = Find(sim.agent(0).known_transforms(), "r3");
  ASSERT_TRUE(t13.has_value());
  EXPECT_LT(Nees(t13->t_self_peer, sim.TrueTransform(0, 2), t13->covariance), 16.3);
  const std::optional<FrameTransform> t31 = Find(sim.agent(2).known_transforms(), "r1");
  ASSERT_TRUE(t31.has_value());
  EXPECT_LT(Nees(t31->t_self_peer, sim.TrueTransform(2, 0), t31->covariance), 16.3);
  // Maps spread: r1 holds r3's landmark (index 3) after the second meeting with r2.
  const Eigen::Vector2d l3 = common::TransformPoint(common::Inverse(sim.Frame(0)), sim.landmarks()[3]);
  bool found = false;
  for (const auto& l : sim.filter(0).estimate.landmarks) found = found || (l.mean.head<2>() - l3).norm() < 0.3;
  EXPECT_TRUE(found);
}

TEST(Cooperation, FramesSpreadDuringALongEncounter) {
  // r1 and r2 stay in contact from step 14 on (one encounter, one rendezvous); r2 meets r3 at
  // 30. Every 10 steps of the encounter r2 passes its transforms on, without its map.
  Sim sim(
      Scenario(3),
      [](std::uint32_t k, int i, int j) {
        if (i == 0 && j == 1) return k >= 14;
        if (i == 1 && j == 2) return k >= 30 && k <= 31;
        return false;
      },
      11);
  sim.Run(30);
  EXPECT_EQ(sim.agent(0).frames_known(), std::vector<std::string>{"r2"});
  sim.Run(15);
  ASSERT_EQ(sim.agent(0).rendezvous().size(), 1u);
  EXPECT_EQ(sim.agent(0).frames_known(), (std::vector<std::string>{"r2", "r3"}));
  const std::optional<FrameTransform> t13 = Find(sim.agent(0).known_transforms(), "r3");
  ASSERT_TRUE(t13.has_value());
  EXPECT_LT(Nees(t13->t_self_peer, sim.TrueTransform(0, 2), t13->covariance), 16.3);
  EXPECT_EQ(sim.filter(0).merges, 1);  // the rendezvous' snapshot only
}

TEST(Cooperation, CooperativeLocalizationUsesDetectionsAfterTheRefinement) {
  common::ScenarioOptions s = Scenario(2);
  s.cooperation.cooperative_localization = true;
  Sim sim(
      s, [](std::uint32_t k, int, int) { return k >= 14 && k <= 40; }, 3);
  sim.Run(45);
  // Steps 14..24 refine the transform; 25..40 correct the pose (applied at the next step).
  EXPECT_EQ(sim.filter(0).robot_observations, 16);
  EXPECT_EQ(sim.agent(0).cooperative_updates(), 16);
}

// ---------------------------------------------------------------------------------------------
// Hostile or broken peer input: rejected, counted, the map unchanged.

class HostileInput : public ::testing::Test {
 protected:
  HostileInput()
      : sim_(
            Scenario(3), [](std::uint32_t k, int i, int j) { return i == 0 && j == 1 && k >= 14 && k <= 15; }, 4) {
    sim_.Run(20);  // r1 knows r2's frame; r3 is a known robot whose frame r1 does not know
  }

  MapSnapshot GoodSnapshot() const {
    MapSnapshot m;
    m.header = {"r2", "r1", sim_.step(), 13.0, 1};
    filters::MapLandmark l;
    l.mean = {10.0, 10.0, 0.0};
    l.covariance = Eigen::Vector3d(0.01, 0.01, 1.0).asDiagonal();
    m.landmarks.push_back(l);
    return m;
  }
  RelativeMeasurement GoodMeasurement() const {
    RelativeMeasurement m;
    m.header = {"r2", "r1", sim_.step(), 13.0, 1};
    m.range_m = 2.0;
    m.bearing_rad = 0.5;
    m.sender_covariance = Eigen::Matrix3d::Identity() * 1e-3;
    return m;
  }
  // Applies the inbox; expects it rejected (one count per message) with the map unchanged.
  void ExpectRejected(const PeerInbox& inbox) {
    Cooperation& a = sim_.agent(0);
    const int before = a.rejected_messages();
    const auto landmarks = sim_.filter(0).estimate.landmarks;
    const int merges = sim_.filter(0).merges;
    const auto frames = a.frames_known();
    a.Receive(inbox, &sim_.filter(0));
    EXPECT_EQ(a.rejected_messages(),
              before + static_cast<int>(inbox.measurements.size() + inbox.maps.size() + inbox.moved.size()));
    EXPECT_EQ(sim_.filter(0).merges, merges);
    EXPECT_EQ(sim_.filter(0).estimate.landmarks.size(), landmarks.size());
    EXPECT_EQ(a.frames_known(), frames);
  }

  Sim sim_;
};

TEST_F(HostileInput, GoodSnapshotIsMerged) {
  ASSERT_EQ(sim_.agent(0).frames_known(), std::vector<std::string>{"r2"});
  const int merges = sim_.filter(0).merges;
  sim_.agent(0).Receive({{}, {GoodSnapshot()}, {}}, &sim_.filter(0));
  EXPECT_EQ(sim_.filter(0).merges, merges + 1);
  EXPECT_EQ(sim_.agent(0).rejected_messages(), 0);
}

TEST_F(HostileInput, MoversWithAnEstimatedMotionAreNotMerged) {
  // A moving landmark the peer tracks with a constant turn rate stays out of the own map; one
  // that follows known kinematics is merged.
  MapSnapshot estimated = GoodSnapshot();
  estimated.landmarks[0].moving = true;
  estimated.landmarks[0].motion = filters::LandmarkMotionKind::kConstantTurnRate;
  const int merges = sim_.filter(0).merges;
  sim_.agent(0).Receive({{}, {estimated}, {}}, &sim_.filter(0));
  EXPECT_EQ(sim_.filter(0).merges, merges);
  MapSnapshot known = GoodSnapshot();
  known.landmarks[0].moving = true;
  known.landmarks[0].motion = filters::LandmarkMotionKind::kUnicycle;
  sim_.agent(0).Receive({{}, {known}, {}}, &sim_.filter(0));
  EXPECT_EQ(sim_.filter(0).merges, merges + 1);
  EXPECT_EQ(sim_.agent(0).rejected_messages(), 0);
}

TEST_F(HostileInput, NanAndInfinity) {
  MapSnapshot a = GoodSnapshot();
  a.landmarks[0].mean.x() = std::nan("");
  MapSnapshot b = GoodSnapshot();
  b.landmarks[0].covariance(1, 1) = std::numeric_limits<double>::infinity();
  MapSnapshot c = GoodSnapshot();
  c.landmarks[0].v_mps = std::nan("");
  RelativeMeasurement m = GoodMeasurement();
  m.range_m = std::nan("");
  RelativeMeasurement n = GoodMeasurement();
  n.sender_pose.heading = std::numeric_limits<double>::infinity();
  ExpectRejected({{m, n}, {a, b, c}, {}});
}

TEST_F(HostileInput, CovarianceNotSymmetricPositiveDefinite) {
  MapSnapshot a = GoodSnapshot();
  a.landmarks[0].covariance(0, 0) = -0.01;
  MapSnapshot b = GoodSnapshot();
  b.landmarks[0].covariance(0, 1) = 0.005;  // not symmetric
  MapSnapshot c = GoodSnapshot();
  c.known_transforms.push_back({"r3", 1, {1.0, 2.0, 0.3}, Eigen::Matrix3d::Zero()});
  RelativeMeasurement m = GoodMeasurement();
  m.sender_covariance(2, 2) = 0.0;
  ExpectRejected({{m}, {a, b, c}, {}});
}

TEST_F(HostileInput, UnknownRobots) {
  MapSnapshot a = GoodSnapshot();
  a.header.sender = "r9";
  MapSnapshot b = GoodSnapshot();
  b.known_transforms.push_back({"r9", 1, {1.0, 2.0, 0.3}, Eigen::Matrix3d::Identity()});
  MapSnapshot c = GoodSnapshot();
  c.header.recipient = "r3";
  RelativeMeasurement m = GoodMeasurement();
  m.header.sender = "r1";  // itself
  LandmarkMovedNotice n;
  n.header = {"r7", "r1", sim_.step(), 0.0, 1};
  ExpectRejected({{m}, {a, b, c}, {n}});
}

// Landmarks carry their provenance (the robot that first mapped them): one naming a robot the
// scenario does not have is hostile input; r1's own landmarks coming back from r2 (after r2
// merged them) are not merged again, neither as duplicates nor as confirmation.
TEST_F(HostileInput, ProvenanceOfAnUnknownRobot) {
  MapSnapshot a = GoodSnapshot();
  a.landmarks[0].origin_robot = 3;  // robots 0..2
  MapSnapshot b = GoodSnapshot();
  b.landmarks[0].origin_robot = -2;
  ExpectRejected({{}, {a, b}, {}});
}

TEST_F(HostileInput, OwnLandmarksComingBackAreNotMergedAgain) {
  MapSnapshot echo = GoodSnapshot();
  echo.landmarks[0].origin_robot = 0;  // r1's
  echo.landmarks[0].origin_track = 5;
  const int merges = sim_.filter(0).merges;
  const std::size_t mapped = sim_.filter(0).estimate.landmarks.size();
  sim_.agent(0).Receive({{}, {echo}, {}}, &sim_.filter(0));
  EXPECT_EQ(sim_.filter(0).merges, merges);
  EXPECT_EQ(sim_.filter(0).estimate.landmarks.size(), mapped);
  EXPECT_EQ(sim_.agent(0).rejected_messages(), 0);  // not hostile: simply nothing new

  MapSnapshot mixed = GoodSnapshot();
  mixed.header.step = echo.header.step;
  mixed.landmarks.push_back(echo.landmarks[0]);
  mixed.landmarks[0].origin_robot = 2;  // r3's, merged by r2 earlier
  mixed.landmarks[1].mean.x() = -10.0;  // r1's, elsewhere
  sim_.agent(0).Receive({{}, {mixed}, {}}, &sim_.filter(0));
  EXPECT_EQ(sim_.filter(0).merges, merges + 1);
  ASSERT_EQ(sim_.filter(0).estimate.landmarks.size(), mapped + 1);  // r3's only
  EXPECT_EQ(sim_.filter(0).estimate.landmarks.back().origin_robot, 2);
}

TEST_F(HostileInput, AbsurdSize) {
  MapSnapshot a = GoodSnapshot();
  a.landmarks.assign(257, a.landmarks[0]);
  ExpectRejected({{}, {a}, {}});
}

TEST_F(HostileInput, BrokenHistories) {
  // A history of every step up to the snapshot's, with one labelled reading per step.
  const auto with_history = [this]() {
    MapSnapshot m = GoodSnapshot();
    for (std::uint32_t k = 1; k <= m.header.step; ++k) {
      common::SensorStep s;
      s.lidar.stamp = {"r2", k, 0.65 * k};
      s.lidar.landmarks.push_back({0.65 * k, 3.0, 0.2, 1});
      s.odometry.segments.push_back({0.65 * (k - 1), 0.65, 1.0, 0.2});
      m.history.push_back(s);
    }
    return m;
  };
  // The well-formed one is taken (its joint estimate may or may not be used: no shared landmark).
  sim_.agent(0).Receive({{}, {with_history()}, {}}, &sim_.filter(0));
  ASSERT_EQ(sim_.agent(0).rejected_messages(), 0);
  MapSnapshot nan = with_history();
  nan.history[3].lidar.landmarks[0].range_m = std::nan("");
  MapSnapshot odometry = with_history();
  odometry.history[2].odometry.segments[0].v_mps = std::numeric_limits<double>::infinity();
  MapSnapshot gap = with_history();
  gap.history.erase(gap.history.begin() + 5);
  MapSnapshot unlabelled = with_history();
  unlabelled.history[0].lidar.landmarks[0].landmark_id = -1;
  MapSnapshot first_pose = with_history();
  first_pose.first_pose.x = std::nan("");
  MapSnapshot extra = with_history();  // more steps than the snapshot's
  extra.history.push_back(extra.history.back());
  MapSnapshot crowded = with_history();  // more readings in one step than any scan holds
  crowded.history[1].lidar.landmarks.assign(257, crowded.history[1].lidar.landmarks[0]);
  ExpectRejected({{}, {nan, odometry, gap, unlabelled, first_pose, extra, crowded}, {}});
}

TEST_F(HostileInput, StaleAndFutureSteps) {
  sim_.agent(0).Receive({{}, {GoodSnapshot()}, {}}, &sim_.filter(0));
  MapSnapshot a = GoodSnapshot();
  a.header.step = sim_.step() - 5;  // older than the one just applied
  MapSnapshot b = GoodSnapshot();
  b.header.step = sim_.step() + 100;
  RelativeMeasurement m = GoodMeasurement();
  m.header.step = 14;  // r2's measurements up to step 15 were applied
  ExpectRejected({{m}, {a, b}, {}});
}

TEST_F(HostileInput, SnapshotFromAPeerWhoseFrameIsUnknown) {
  MapSnapshot a = GoodSnapshot();
  a.header.sender = "r3";
  ExpectRejected({{}, {a}, {}});
}

TEST_F(HostileInput, MovedNoticesAreValidatedAndCounted) {
  LandmarkMovedNotice good;
  good.header = {"r2", "r1", sim_.step(), 0.0, 1};
  good.position_in_sender = {1.0, 2.0};
  sim_.agent(0).Receive({{}, {}, {good}}, &sim_.filter(0));
  EXPECT_EQ(sim_.agent(0).moved_notices(), 1);
  LandmarkMovedNotice bad = good;
  bad.position_in_sender.x() = std::nan("");
  ExpectRejected({{}, {}, {bad}});
  EXPECT_EQ(sim_.agent(0).moved_notices(), 1);
  LandmarkMovedNotice unknown_frame = good;
  unknown_frame.header.sender = "r3";
  ExpectRejected({{}, {}, {unknown_frame}});
}

TEST_F(HostileInput, MovedNoticeReachesTheFilterInTheOwnFrame) {
  const std::optional<FrameTransform> t12 = Find(sim_.agent(0).known_transforms(), "r2");
  ASSERT_TRUE(t12.has_value());
  LandmarkMovedNotice n;
  n.header = {"r2", "r1", sim_.step(), 0.0, 1};
  n.position_in_sender = {1.0, 2.0};
  sim_.filter(0).notices.clear();
  sim_.agent(0).Receive({{}, {}, {n}}, &sim_.filter(0));
  ASSERT_EQ(sim_.filter(0).notices.size(), 1U);
  const Eigen::Vector2d expected = common::TransformPoint(t12->t_self_peer, n.position_in_sender);
  EXPECT_NEAR((sim_.filter(0).notices[0].first - expected).norm(), 0.0, 1e-12);
  // The transform's uncertainty reaches the notice: a positive definite position covariance.
  EXPECT_TRUE(common::IsSymmetricPositiveDefinite<2>(sim_.filter(0).notices[0].second));
}

TEST_F(HostileInput, MovedNoticesGoOnlyToPeersWhoseFrameIsKnown) {
  filters::MovedLandmark m;
  m.track_id = 4;
  m.position = {3.0, -1.0};
  const auto notices = sim_.agent(0).MovedNotices({m}, sim_.step(), 13.0);
  ASSERT_EQ(notices.size(), 1U);  // r2 (met); not r3 (frame unknown)
  EXPECT_EQ(notices[0].header.recipient, "r2");
  EXPECT_EQ(notices[0].header.sender, "r1");
  EXPECT_EQ(notices[0].track_id, 4U);
  EXPECT_EQ(notices[0].position_in_sender, m.position);
}

// ---------------------------------------------------------------------------------------------
// With the FastSLAM filter.

// r1 (a FastSLAM agent) has mapped two static landmarks; r2 is a second robot of the scenario.
class WithFastSlam : public ::testing::TestWithParam<robot_agent::LandmarkKinematics> {
 protected:
  void SetUp() override {
    options_ = testing::OneRobotScenario(0.2, 0.0, 100);
    options_.filter.landmark_kinematics = GetParam();
    options_.filter.known_kinematics = {{0.0, 0.0}, {0.4, 0.2}};
    testing::AddLandmark(&options_, 1, {2.0, 0.5, 0.0});
    testing::AddLandmark(&options_, 2, {0.5, 2.0, 0.0});
    common::RobotOptions r2;
    r2.id = "r2";
    r2.frame_in_world = {1.0, 1.0, 0.5};
    options_.robots.push_back(r2);
    options_.rendezvous.enable_from_step = 0;
    filter_ = filters::CreateFilter(common::AgentOptionsFor(options_, "r1"), 3);
    testing::TinyWorld world(options_, 3);
    for (int k = 0; k < 8; ++k) filter_->Process(world.Step());
    ASSERT_EQ(filter_->Estimate().landmarks.size(), 2u);
  }

  // Lets r1's agent learn r2's frame from one mutual detection at step 8 (the filter's step).
  void Meet(Cooperation* agent) {
    const filters::FilterEstimate e = filter_->Estimate();
    common::LidarScan scan;
    scan.stamp = {"r1", e.step, e.time_s};
    scan.robots.push_back({e.time_s, 2.0, 0.3, "r2"});
    common::SensorStep step;
    step.lidar = scan;
    agent->AfterStep(step, e);
    RelativeMeasurement m;
    m.header = {"r2", "r1", e.step, e.time_s, 1};
    m.range_m = 2.0;
    m.bearing_rad = -0.4;
    m.sender_pose = {0.5, 0.5, 0.1};
    m.sender_covariance = Eigen::Matrix3d::Identity() * 1e-3;
    agent->Receive({{m}, {}, {}}, filter_.get());
    ASSERT_EQ(agent->frames_known(), std::vector<std::string>{"r2"});
  }

  common::ScenarioOptions options_;
  std::unique_ptr<filters::SlamFilter> filter_;
};

// Particles of a FastSLAM filter (of any state dimension) holding more than n landmarks, and
// the number of particles.
template <int D>
const filters::FastSlam<D>* AsFastSlam(const filters::SlamFilter& f) {
  return dynamic_cast<const filters::FastSlam<D>*>(&f);
}
int ParticlesHoldingMoreThan(const filters::SlamFilter& f, int n) {
  int out = 0;
  const auto count = [&](const auto* fast) {
    for (int p = 0; fast != nullptr && p < fast->NumParticles(); ++p) out += fast->ParticleLandmarkCount(p) > n ? 1 : 0;
  };
  count(AsFastSlam<2>(f));
  count(AsFastSlam<3>(f));
  count(AsFastSlam<5>(f));
  return out;
}
int NumParticlesOf(const filters::SlamFilter& f) { return f.Estimate().particles; }

void ExpectSameEstimate(const filters::FilterEstimate& a, const filters::FilterEstimate& b) {
  EXPECT_EQ(a.pose.Vector(), b.pose.Vector());
  ASSERT_EQ(a.landmarks.size(), b.landmarks.size());
  for (std::size_t i = 0; i < a.landmarks.size(); ++i) {
    EXPECT_EQ(a.landmarks[i].track_id, b.landmarks[i].track_id);
    EXPECT_EQ(a.landmarks[i].mean, b.landmarks[i].mean);
    EXPECT_EQ(a.landmarks[i].covariance, b.landmarks[i].covariance);
  }
}

TEST_P(WithFastSlam, MergeFusesMatchedAndAddsNewLandmarks) {
  const filters::FilterEstimate before = filter_->Estimate();
  std::vector<filters::MapLandmark> in(2);
  // The first landmark as a peer with the same knowledge would hold it.
  in[0].mean = before.landmarks[0].mean;
  in[0].covariance = before.landmarks[0].covariance;
  in[1].mean = {-3.0, -2.0, 0.0};  // a landmark this robot never saw
  in[1].covariance = Eigen::Vector3d(0.01, 0.01, 3.0).asDiagonal();
  const int added = filter_->MergeLandmarks(in, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 0.0);
  if (GetParam() == robot_agent::LandmarkKinematics::kConstantTurnRate) {
    // Each particle gates with its own landmark covariance, which is tight where the particle
    // takes the landmark as static: a particle far out in the mixture may take the first as new.
    EXPECT_GE(added, 1);
    EXPECT_LE(ParticlesHoldingMoreThan(*filter_, 3), NumParticlesOf(*filter_) / 20);
  } else {
    EXPECT_EQ(added, 1);
  }
  const filters::FilterEstimate after = filter_->Estimate();
  ASSERT_EQ(after.landmarks.size(), 3u);
  int near_new = 0;
  for (const auto& l : after.landmarks) {
    if ((l.mean.head<2>() - Eigen::Vector2d(-3.0, -2.0)).norm() < 1e-9) ++near_new;
    EXPECT_FALSE(l.tentative);
  }
  EXPECT_EQ(near_new, 1);
  // The matched landmark's covariance does not grow (CI: no larger determinant than either).
  for (const auto& b : before.landmarks) {
    for (const auto& a : after.landmarks) {
      if (a.track_id != b.track_id) continue;
      const double det_after = a.covariance.topLeftCorner<2, 2>().determinant();
      const double det_before = b.covariance.topLeftCorner<2, 2>().determinant();
      EXPECT_LE(det_after, det_before * (1.0 + 1e-9));
    }
  }
  // SLAM goes on with the merged map.
  testing::TinyWorld world(options_, 4);
  for (int k = 0; k < 3; ++k) filter_->Process(world.Step());
  EXPECT_GE(filter_->Estimate().landmarks.size(), 2u);
}

// filter.max_landmark_position_sd_m (default 2 m): a peer landmark already less certain than the
// bound is not merged; a merged one within it stays while its covariance does; one whose
// covariance grows past the bound unseen (a landmark with a motion model, out of view) leaves
// the map, as an own landmark would.
TEST_P(WithFastSlam, LandmarksBeyondThePositionSdBoundLeaveTheMap) {
  ASSERT_EQ(options_.filter.max_landmark_position_sd_m, 2.0);
  const auto count_near = [](const filters::FilterEstimate& e, const Eigen::Vector2d& at) {
    int n = 0;
    for (const auto& l : e.landmarks) n += (l.mean.head<2>() - at).norm() < 1.0 ? 1 : 0;
    return n;
  };
  const Eigen::Vector2d far(-20.0, -20.0), farther(-30.0, 20.0);  // out of view, unmatched
  const Eigen::Vector2d still(20.0, -20.0);                       // the same, static for the peer
  // The first two with the filter's motion model, as a peer of the same scenario reports them.
  const filters::LandmarkMotionKind kind = GetParam() == robot_agent::LandmarkKinematics::kStatic
                                               ? filters::LandmarkMotionKind::kStatic
                                           : GetParam() == robot_agent::LandmarkKinematics::kKnownCandidates
                                               ? filters::LandmarkMotionKind::kUnicycle
                                               : filters::LandmarkMotionKind::kConstantTurnRate;
  std::vector<filters::MapLandmark> in(3);
  in[0].mean = {far.x(), far.y(), 0.0};
  in[0].covariance = Eigen::Vector3d(1.9, 1.9, 3.0).asDiagonal();  // sd sqrt(3.8) < 2 m
  in[0].motion = kind;
  in[1].mean = {farther.x(), farther.y(), 0.0};
  in[1].covariance = Eigen::Vector3d(2.1, 2.1, 3.0).asDiagonal();  // sd sqrt(4.2) > 2 m
  in[1].motion = kind;
  in[2].mean = {still.x(), still.y(), 0.0};
  in[2].covariance = Eigen::Vector3d(1.9, 1.9, 0.01).asDiagonal();
  in[2].v_mps = 0.3;  // a static report whose mixture still carries a heading and a speed
  in[2].motion = filters::LandmarkMotionKind::kStatic;
  EXPECT_EQ(filter_->MergeLandmarks(in, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 0.0), 2);
  EXPECT_EQ(count_near(filter_->Estimate(), far), 1);
  EXPECT_EQ(count_near(filter_->Estimate(), farther), 0);
  EXPECT_EQ(count_near(filter_->Estimate(), still), 1);
  testing::TinyWorld world(options_, 5);
  for (int k = 0; k < 10; ++k) filter_->Process(world.Step());
  const filters::FilterEstimate after = filter_->Estimate();
  // Static landmarks keep their covariance when unseen; a motion model spreads it every step. A
  // constant-turn-rate filter keeps a landmark the peer takes as static static; known
  // candidates have no static model.
  EXPECT_EQ(count_near(after, far), GetParam() == robot_agent::LandmarkKinematics::kStatic ? 1 : 0);
  EXPECT_EQ(count_near(after, still), GetParam() == robot_agent::LandmarkKinematics::kKnownCandidates ? 0 : 1);
  for (const auto& l : after.landmarks) {
    const double position_variance = l.covariance(0, 0) + l.covariance(1, 1);
    EXPECT_LE(position_variance, 4.0 + 1e-9);
  }
}

// cooperation.merge_min_separation_m: a static peer landmark outside the gate of the static own
// one it lies next to is left out, not added as a second copy; farther off, it is added. Next to
// a moving landmark (known candidates here) it is added: moving landmarks pass close by others.
TEST_P(WithFastSlam, MergeLeavesOutPeerLandmarksTooCloseToOwnOnes) {
  if (GetParam() == robot_agent::LandmarkKinematics::kConstantTurnRate) {
    GTEST_SKIP() << "whether the own landmark is static differs from particle to particle";
  }
  const filters::FilterEstimate before = filter_->Estimate();
  ASSERT_FALSE(before.landmarks.empty());
  std::vector<filters::MapLandmark> in(1);
  in[0].mean = before.landmarks[0].mean + Eigen::Vector3d(1.0, 0.0, 0.0);
  in[0].covariance = Eigen::Vector3d(1e-4, 1e-4, 3.0).asDiagonal();  // 1 m off, far beyond the gate
  in[0].motion = filters::LandmarkMotionKind::kStatic;
  const int added = filter_->MergeLandmarks(in, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 1.5);
  if (GetParam() == robot_agent::LandmarkKinematics::kKnownCandidates) {
    EXPECT_EQ(added, 1);
    return;
  }
  EXPECT_EQ(added, 0);
  ExpectSameEstimate(filter_->Estimate(), before);
  EXPECT_EQ(filter_->MergeLandmarks(in, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 0.5), 1);
  EXPECT_EQ(filter_->Estimate().landmarks.size(), before.landmarks.size() + 1);
}

TEST_P(WithFastSlam, MergeKeepsCopyOnWriteSharing) {
  auto* fast = dynamic_cast<filters::FastSlam<2>*>(filter_.get());
  if (fast == nullptr) GTEST_SKIP() << "checked on the static instantiation";
  std::vector<filters::MapLandmark> in(1);
  in[0].mean = {-3.0, -2.0, 0.0};
  in[0].covariance = Eigen::Vector3d(0.01, 0.01, 3.0).asDiagonal();
  filter_->MergeLandmarks(in, robot_agent::MapFusionRule::kWeighted, 0.999, 0.0);
  // Blocks are never shared by two particles after one of them wrote (each particle's storage
  // addresses are its own where it wrote); every particle holds the added landmark.
  for (int p = 0; p < fast->NumParticles(); ++p) EXPECT_EQ(fast->ParticleLandmarkCount(p), 3);
}

TEST_P(WithFastSlam, RejectedSnapshotsLeaveTheEstimateUnchanged) {
  Cooperation agent(common::AgentOptionsFor(options_, "r1"));
  Meet(&agent);
  const filters::FilterEstimate before = filter_->Estimate();
  MapSnapshot good;
  good.header = {"r2", "r1", before.step, before.time_s, 2};
  filters::MapLandmark l;
  l.mean = {-3.0, -3.0, 0.0};  // far from the own landmarks: added
  l.covariance = Eigen::Vector3d(0.01, 0.01, 3.0).asDiagonal();
  good.landmarks.push_back(l);
  MapSnapshot nan = good;
  nan.landmarks[0].mean.y() = std::nan("");
  MapSnapshot not_pd = good;
  not_pd.landmarks[0].covariance(1, 1) = -1.0;
  MapSnapshot too_big = good;
  too_big.landmarks.assign(300, l);
  MapSnapshot unknown = good;
  unknown.header.sender = "r5";
  agent.Receive({{}, {nan, not_pd, too_big, unknown}, {}}, filter_.get());
  EXPECT_EQ(agent.rejected_messages(), 4);
  ExpectSameEstimate(filter_->Estimate(), before);
  agent.Receive({{}, {good}, {}}, filter_.get());
  EXPECT_EQ(agent.rejected_messages(), 4);
  EXPECT_EQ(filter_->Estimate().landmarks.size(), before.landmarks.size() + 1);
}

TEST_P(WithFastSlam, ObservingAKnownRobotReweightsParticles) {
  auto* fast = dynamic_cast<filters::FastSlam<2>*>(filter_.get());
  if (fast == nullptr) GTEST_SKIP() << "checked on the static instantiation";
  // A robot 2 m ahead of the mean pose: particles that agree gain weight.
  const filters::FilterEstimate e = filter_->Estimate();
  const Eigen::Vector2d there = common::PointFromRangeBearing(e.pose, {2.0, 0.0});
  const double gate = common::ChiSquare2Quantile(0.9999);
  ASSERT_TRUE(filter_->ObserveKnownRobot(there, Eigen::Matrix2d::Identity() * 1e-4, 2.0, 0.0, gate));
  double sum = 0.0;
  std::vector<double> weights;
  for (int p = 0; p < fast->NumParticles(); ++p) {
    weights.push_back(fast->ParticleWeight(p));
    sum += weights.back();
  }
  EXPECT_NEAR(sum, 1.0, 1e-9);
  // A detection 3 m off where the robot is said to be is an outlier: not used,
  // the weights stay as they are.
  EXPECT_FALSE(filter_->ObserveKnownRobot(there, Eigen::Matrix2d::Identity() * 1e-4, 5.0, 0.0, gate));
  for (int p = 0; p < fast->NumParticles(); ++p) EXPECT_EQ(fast->ParticleWeight(p), weights[p]);
}

INSTANTIATE_TEST_SUITE_P(Kinematics, WithFastSlam,
                         ::testing::Values(robot_agent::LandmarkKinematics::kStatic,
                                           robot_agent::LandmarkKinematics::kKnownCandidates,
                                           robot_agent::LandmarkKinematics::kConstantTurnRate));

// ---------------------------------------------------------------------------------------------
// The scenario section.

TEST(CooperationOptions, ParsesDefaultsAndRejectsUnknownKeys) {
  const char* base = "name: t\nrun: {steps: 10, dt_s: 0.1}\nrobots: [{id: r1, pose: [0, 0, 0]}]\n";
  common::ScenarioOptions o = common::CreateScenarioOptions(YAML::Load(base));
  EXPECT_EQ(o.cooperation.map_fusion, robot_agent::MapFusionRule::kCovarianceIntersection);
  EXPECT_TRUE(o.cooperation.merge_maps);
  EXPECT_EQ(o.cooperation.max_snapshot_landmarks, 256);
  EXPECT_EQ(o.cooperation.min_seen_span_steps, 6);
  EXPECT_EQ(o.cooperation.merge_min_separation_m, 1.5);
  o = common::CreateScenarioOptions(YAML::Load(std::string(base) +
                                               "cooperation: {map_fusion: average, merge_maps: false, "
                                               "max_snapshot_landmarks: 10, cooperative_localization: true, "
                                               "min_seen_span_steps: 0, merge_min_separation_m: 0}\n"));
  EXPECT_EQ(o.cooperation.map_fusion, robot_agent::MapFusionRule::kAverage);
  EXPECT_FALSE(o.cooperation.merge_maps);
  EXPECT_EQ(o.cooperation.max_snapshot_landmarks, 10);
  EXPECT_TRUE(o.cooperation.cooperative_localization);
  EXPECT_EQ(o.cooperation.min_seen_span_steps, 0);
  EXPECT_EQ(o.cooperation.merge_min_separation_m, 0.0);
  EXPECT_THROW(common::CreateScenarioOptions(YAML::Load(std::string(base) + "cooperation: {fusion: x}\n")),
               common::ScenarioError);
  EXPECT_THROW(common::CreateScenarioOptions(YAML::Load(std::string(base) + "cooperation: {map_fusion: x}\n")),
               common::ScenarioError);
  o = common::CreateScenarioOptions(YAML::Load(std::string(base) + "cooperation: {max_snapshot_landmarks: 0}\n"));
  std::string error;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("cooperation.max_snapshot_landmarks"), std::string::npos);
  o = common::CreateScenarioOptions(YAML::Load(std::string(base) + "cooperation: {min_seen_span_steps: -1}\n"));
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("cooperation.min_seen_span_steps"), std::string::npos);
  o = common::CreateScenarioOptions(YAML::Load(std::string(base) + "cooperation: {merge_min_separation_m: -1}\n"));
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("cooperation.merge_min_separation_m"), std::string::npos);
  o = common::CreateScenarioOptions(YAML::Load(std::string(base) + "filter: {max_landmark_position_sd_m: .inf}\n"));
  EXPECT_TRUE(std::isinf(o.filter.max_landmark_position_sd_m));
  EXPECT_TRUE(o.IsValid(&error));
  o = common::CreateScenarioOptions(YAML::Load(std::string(base) + "filter: {max_landmark_position_sd_m: 0}\n"));
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("filter.max_landmark_position_sd_m"), std::string::npos);
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
