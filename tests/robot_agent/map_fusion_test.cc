#include "robot_agent/filters/map_fusion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>

#include "common/gaussian.h"
#include "common/rng.h"

namespace mrslam::robot_agent::filters {
namespace {

using common::Pose2;
using robot_agent::MapFusionRule;

// A random symmetric positive-definite n x n matrix with eigenvalues in [lo, hi].
Eigen::MatrixXd RandomSpd(common::Rng* rng, int n, double lo, double hi) {
  Eigen::MatrixXd a(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) a(i, j) = rng->Normal();
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(a);
  const Eigen::MatrixXd q = qr.householderQ();
  Eigen::VectorXd d(n);
  for (int i = 0; i < n; ++i) d(i) = rng->Uniform(lo, hi);
  return q * d.asDiagonal() * q.transpose();
}

Eigen::VectorXd Sample(common::Rng* rng, const Eigen::MatrixXd& cov) {
  const Eigen::LLT<Eigen::MatrixXd> llt(cov);
  Eigen::VectorXd n(cov.rows());
  for (int i = 0; i < n.size(); ++i) n(i) = rng->Normal();
  return llt.matrixL() * n;
}

// True when b - a is positive semidefinite (a "no larger than" b), to a tolerance.
bool NoLarger(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(b - a);
  return es.eigenvalues().minCoeff() > -1e-9 * std::max(1.0, b.norm());
}

TEST(TransformLandmark, ExactAndConsistent) {
  common::Rng rng(7, "transform_landmark");
  double nees_sum = 0.0;
  constexpr int kTrials = 3000;
  for (int trial = 0; trial < kTrials; ++trial) {
    const Pose2 t{rng.Uniform(-5, 5), rng.Uniform(-5, 5), rng.Uniform(-3, 3)};
    MapLandmark l;
    l.mean = {rng.Uniform(-5, 5), rng.Uniform(-5, 5), rng.Uniform(-3, 3)};
    l.covariance = RandomSpd(&rng, 3, 1e-4, 4e-3);
    const Eigen::Matrix3d t_cov = RandomSpd(&rng, 3, 1e-4, 2e-3);
    const MapLandmark out = TransformLandmark(l, t, t_cov);
    // Exact for the means.
    const Eigen::Vector2d p = common::TransformPoint(t, l.mean.head<2>());
    EXPECT_NEAR(out.mean.x(), p.x(), 1e-12);
    EXPECT_NEAR(out.mean.y(), p.y(), 1e-12);
    EXPECT_NEAR(common::WrapAngle(out.mean.z() - l.mean.z() - t.heading), 0.0, 1e-12);
    // Consistent: a perturbed transform and landmark fall within the propagated covariance.
    const Eigen::Vector3d dt = Sample(&rng, t_cov), dl = Sample(&rng, l.covariance);
    const Pose2 t_true = Pose2::FromVector(t.Vector() + dt);
    const Pose2 l_true = Pose2::FromVector(l.mean + dl);
    const Pose2 moved = common::Compose(t_true, l_true);
    Eigen::Vector3d e(moved.x - out.mean.x(), moved.y - out.mean.y(), common::WrapAngle(moved.heading - out.mean.z()));
    nees_sum += e.dot(out.covariance.ldlt().solve(e));
  }
  const double mean_nees = nees_sum / kTrials;
  // Mean of 3000 chi-square(3) draws: 3 +- 3.3 sd (sd = sqrt(6 / 3000) = 0.045).
  EXPECT_GT(mean_nees, 2.85);
  EXPECT_LT(mean_nees, 3.15);
}

TEST(FuseObservation, WeightedIsInformationFusion) {
  common::Rng rng(11, "weighted");
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Matrix3d pa = RandomSpd(&rng, 3, 0.01, 1.0), pb = RandomSpd(&rng, 3, 0.01, 1.0);
    const Eigen::Vector3d xa(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1));
    const Eigen::Vector3d xb(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1));
    Eigen::Vector3d x = xa;
    Eigen::Matrix3d p = pa;
    ASSERT_TRUE((FuseObservation<3, 3>(&x, &p, xb, pb, MapFusionRule::kWeighted)));
    const Eigen::Matrix3d info = pa.inverse() + pb.inverse();
    const Eigen::Matrix3d p_expected = info.inverse();
    const Eigen::Vector3d x_expected = p_expected * (pa.inverse() * xa + pb.inverse() * xb);
    EXPECT_LT((p - p_expected).norm(), 1e-9);
    EXPECT_LT((x - x_expected).norm(), 1e-9);
  }
}

// For independent inputs, information fusion gives a covariance no larger than either input
// (P <= A and P <= B in the positive-semidefinite order); covariance intersection, which gives up
// that gain to stay consistent under any correlation, gives a determinant no larger than either.
TEST(FuseObservation, FusedCovarianceNoLargerThanInputs) {
  common::Rng rng(12, "no_larger");
  for (const MapFusionRule rule : {MapFusionRule::kWeighted, MapFusionRule::kCovarianceIntersection}) {
    for (int trial = 0; trial < 300; ++trial) {
      const Eigen::Matrix3d pa = RandomSpd(&rng, 3, 0.01, 1.0), pb = RandomSpd(&rng, 3, 0.01, 1.0);
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      Eigen::Matrix3d p = pa;
      ASSERT_TRUE((FuseObservation<3, 3>(&x, &p, Eigen::Vector3d::Ones(), pb, rule)));
      if (rule == MapFusionRule::kWeighted) {
        EXPECT_TRUE(NoLarger(p, pa)) << "trial " << trial;
        EXPECT_TRUE(NoLarger(p, pb)) << "trial " << trial;
      } else {
        EXPECT_LE(p.determinant(), pa.determinant() * (1.0 + 1e-6)) << "trial " << trial;
        EXPECT_LE(p.determinant(), pb.determinant() * (1.0 + 1e-6)) << "trial " << trial;
      }
    }
  }
}

// Independent inputs of equal covariance: CI halves nothing but stays within both; the CI
// ellipse contains the information-fusion one (CI is never tighter than the optimal fusion).
TEST(FuseObservation, CovarianceIntersectionIsNeverTighterThanInformationFusion) {
  common::Rng rng(14, "ci_vs_info");
  for (int trial = 0; trial < 300; ++trial) {
    const Eigen::Matrix2d pa = RandomSpd(&rng, 2, 0.01, 1.0), pb = RandomSpd(&rng, 2, 0.01, 1.0);
    Eigen::Vector2d x1 = Eigen::Vector2d::Zero(), x2 = x1;
    Eigen::Matrix2d p_ci = pa, p_info = pa;
    ASSERT_TRUE(
        (FuseObservation<2, 2>(&x1, &p_ci, Eigen::Vector2d::Ones(), pb, MapFusionRule::kCovarianceIntersection)));
    ASSERT_TRUE((FuseObservation<2, 2>(&x2, &p_info, Eigen::Vector2d::Ones(), pb, MapFusionRule::kWeighted)));
    EXPECT_TRUE(NoLarger(p_info, p_ci)) << "trial " << trial;
  }
}

// Two estimates of one state whose errors are strongly correlated (a shared error): CI stays
// consistent (mean NEES at most the dimension), information fusion does not.
TEST(FuseObservation, CovarianceIntersectionConsistentForCorrelatedInputs) {
  common::Rng rng(13, "ci_correlated");
  constexpr int kTrials = 4000;
  const Eigen::MatrixXd shared = RandomSpd(&rng, 2, 0.5, 1.0);
  const Eigen::MatrixXd own_a = RandomSpd(&rng, 2, 0.05, 0.2), own_b = RandomSpd(&rng, 2, 0.05, 0.2);
  double nees_ci = 0.0, nees_weighted = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const Eigen::Vector2d common_error = Sample(&rng, shared);
    const Eigen::Vector2d xa = common_error + Sample(&rng, own_a);
    const Eigen::Vector2d xb = common_error + Sample(&rng, own_b);
    // Each input's own covariance is right: shared + own.
    for (const MapFusionRule rule : {MapFusionRule::kCovarianceIntersection, MapFusionRule::kWeighted}) {
      Eigen::Vector2d x = xa;
      Eigen::Matrix2d p = shared + own_a;
      ASSERT_TRUE((FuseObservation<2, 2>(&x, &p, xb, Eigen::Matrix2d(shared + own_b), rule)));
      const double nees = x.dot(p.ldlt().solve(x));  // the truth is 0
      (rule == MapFusionRule::kWeighted ? nees_weighted : nees_ci) += nees;
    }
  }
  EXPECT_LT(nees_ci / kTrials, 2.0 * 1.05);
  EXPECT_GT(nees_weighted / kTrials, 2.0 * 1.3);  // overconfident, as expected
}

// Covariance intersection written out plainly, as a reference: information form
//   P(omega)^-1 = omega P^-1 + (1 - omega) H^T r^-1 H,  P(omega)^-1 x' = omega P^-1 x + (1 - omega) H^T r^-1 z,
// omega by a golden-section search of log det P(omega) over [1e-4, 1 - 1e-4] run until the
// bracket stops shrinking, then the end points omega = 1 and (full observation) omega = 0.
struct Fused {
  Eigen::VectorXd x;
  Eigen::MatrixXd p;
};
Fused ReferenceCovarianceIntersection(const Eigen::VectorXd& x, const Eigen::MatrixXd& p, const Eigen::VectorXd& z,
                                      const Eigen::MatrixXd& r) {
  const int n = static_cast<int>(x.size()), m = static_cast<int>(z.size());
  const Eigen::MatrixXd h = Eigen::MatrixXd::Identity(m, n);
  const Eigen::MatrixXd a = p.inverse(), b = h.transpose() * r.inverse() * h;
  const auto log_det_p = [&](double w) { return -std::log((w * a + (1.0 - w) * b).determinant()); };
  constexpr double kInvPhi = 0.6180339887498949;
  double lo = 1e-4, hi = 1.0 - 1e-4;
  for (int i = 0; i < 200; ++i) {
    const double c = hi - kInvPhi * (hi - lo), d = lo + kInvPhi * (hi - lo);
    if (log_det_p(c) < log_det_p(d)) {
      hi = d;
    } else {
      lo = c;
    }
  }
  double omega = 0.5 * (lo + hi);
  if (std::log(p.determinant()) <= log_det_p(omega)) omega = 1.0;
  if (m == n && std::log(r.determinant()) < std::min(log_det_p(omega), std::log(p.determinant()))) omega = 0.0;
  if (omega == 0.0) return {z, r};
  const Eigen::MatrixXd info = omega * a + (1.0 - omega) * b;
  const Eigen::MatrixXd p_new = info.inverse();
  return {p_new * (omega * a * x + (1.0 - omega) * h.transpose() * r.inverse() * z), p_new};
}

// The closed-form weight against the reference on random inputs, the own and the incoming
// covariance each up to 30 times larger than the other (so that keeping the own estimate, taking
// the incoming one and every weight between occur). Tolerance: the golden-section search sees
// log det P only to round-off (1e-16 relative), and log det P is flat at its minimum (a change
// d omega moves it by g'' d omega^2 / 2), so the reference's omega is good to about 1e-8; the
// fused state moves with omega by dP/d omega = -P (P^-1 - H^T r^-1 H) P, a few times P here, so
// both agree to 1e-6 relative.
template <int N, int M>
void ExpectCovarianceIntersectionMatchesReference(std::uint64_t seed) {
  common::Rng rng(seed, "ci_reference");
  int keep = 0, take = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const double scale = std::exp(rng.Uniform(-std::log(30.0), std::log(30.0)));
    const Eigen::Matrix<double, N, N> p = RandomSpd(&rng, N, 0.05, 1.0);
    const Eigen::Matrix<double, M, M> r = RandomSpd(&rng, M, 0.05, 1.0) * scale;
    Eigen::Matrix<double, N, 1> x;
    Eigen::Matrix<double, M, 1> z;
    for (int i = 0; i < N; ++i) x(i) = rng.Uniform(-1, 1);
    for (int i = 0; i < M; ++i) z(i) = rng.Uniform(-1, 1);
    const Fused expected = ReferenceCovarianceIntersection(x, p, z, r);
    Eigen::Matrix<double, N, 1> x_fast = x;
    Eigen::Matrix<double, N, N> p_fast = p;
    ASSERT_TRUE((FuseObservation<N, M>(&x_fast, &p_fast, z, r, MapFusionRule::kCovarianceIntersection)));
    EXPECT_LT((x_fast - expected.x).norm(), 1e-6 * (1.0 + expected.x.norm())) << "trial " << trial;
    EXPECT_LT((p_fast - expected.p).norm(), 1e-6 * expected.p.norm()) << "trial " << trial;
    keep += p_fast == p ? 1 : 0;
    take += M == N && p_fast.template topLeftCorner<M, M>() == r ? 1 : 0;
  }
  EXPECT_GT(keep, 0);
  if (M == N) {
    EXPECT_GT(take, 0);
  }
}

TEST(FuseObservation, CovarianceIntersectionMatchesTheReference) {
  ExpectCovarianceIntersectionMatchesReference<2, 2>(21);
  ExpectCovarianceIntersectionMatchesReference<3, 2>(22);
  ExpectCovarianceIntersectionMatchesReference<3, 3>(23);
  ExpectCovarianceIntersectionMatchesReference<5, 2>(24);
  ExpectCovarianceIntersectionMatchesReference<5, 3>(25);
}

TEST(FuseObservation, AverageIsTheMidpointAndPartialObservationLeavesTheRest) {
  Eigen::Vector3d x(1.0, 2.0, 3.0);
  Eigen::Matrix3d p = Eigen::Matrix3d::Identity() * 0.5;
  const Eigen::Vector2d z(3.0, 0.0);
  const Eigen::Matrix2d r = Eigen::Matrix2d::Identity() * 0.1;
  ASSERT_TRUE((FuseObservation<3, 2>(&x, &p, z, r, MapFusionRule::kAverage)));
  EXPECT_DOUBLE_EQ(x(0), 2.0);
  EXPECT_DOUBLE_EQ(x(1), 1.0);
  EXPECT_DOUBLE_EQ(x(2), 3.0);
  EXPECT_NEAR(p(0, 0), 0.25 * (0.5 + 0.1), 1e-12);
  EXPECT_DOUBLE_EQ(p(2, 2), 0.5);
}

TEST(FuseObservation, WrapsTheAngleComponent) {
  Eigen::Vector3d x(0.0, 0.0, common::kPi - 0.05);
  Eigen::Matrix3d p = Eigen::Matrix3d::Identity() * 0.01;
  const Eigen::Vector3d z(0.0, 0.0, -common::kPi + 0.05);
  ASSERT_TRUE((FuseObservation<3, 3>(&x, &p, z, Eigen::Matrix3d(p), MapFusionRule::kWeighted, 2)));
  EXPECT_NEAR(std::abs(x(2)), common::kPi, 1e-9);
}

TEST(FuseObservation, RejectsUnusableInput) {
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  Eigen::Matrix2d p = Eigen::Matrix2d::Identity();
  const Eigen::Vector2d z(std::nan(""), 0.0);
  EXPECT_FALSE((FuseObservation<2, 2>(&x, &p, z, Eigen::Matrix2d(p), MapFusionRule::kCovarianceIntersection)));
  EXPECT_EQ(x, Eigen::Vector2d::Zero());
  // An incoming covariance that is not positive definite.
  const Eigen::Matrix2d indefinite = Eigen::Vector2d(1.0, -1.0).asDiagonal();
  for (const MapFusionRule rule : {MapFusionRule::kWeighted, MapFusionRule::kCovarianceIntersection}) {
    EXPECT_FALSE((FuseObservation<2, 2>(&x, &p, Eigen::Vector2d::Zero(), indefinite, rule)));
  }
  EXPECT_EQ(p, Eigen::Matrix2d::Identity());
}

TEST(MatchLandmarks, GatesByMahalanobisAndIdentity) {
  const double gate = common::ChiSquare2Quantile(0.999);
  const Eigen::Matrix2d c = Eigen::Matrix2d::Identity() * 0.01;
  const std::vector<MatchCandidate> own = {{{0.0, 0.0}, c, -1}, {{5.0, 0.0}, c, -1}, {{0.0, 5.0}, c, 7}};
  const std::vector<MatchCandidate> incoming = {
      {{5.1, 0.05}, c, -1},   // near own 1
      {{20.0, 0.0}, c, -1},   // nowhere
      {{0.05, 0.0}, c, -1},   // near own 0
      {{9.0, 9.0}, c, 7},     // identity 7: own 2 wherever it is
      {{0.02, 0.01}, c, -1},  // also near own 0, but own 0 is taken by a closer one? no: farther
  };
  const std::vector<int> m = MatchLandmarks(own, incoming, gate);
  EXPECT_EQ(m[0], 1);
  EXPECT_EQ(m[1], -1);
  EXPECT_EQ(m[3], 2);
  // Own 0 goes to the closest of incoming 2 and 4 (one to one).
  EXPECT_EQ(m[4], 0);
  EXPECT_EQ(m[2], -1);
}

// Landmarks of the same provenance (robot, track) are one landmark wherever the estimates put
// them; different provenances fall back on the gate (two robots may map one landmark).
TEST(MatchLandmarks, SameProvenanceMatchesLikeAnIdentity) {
  const Eigen::Matrix2d c = Eigen::Matrix2d::Identity() * 0.01;
  const std::int64_t a = OriginKey(1, 7), b = OriginKey(2, 7);
  EXPECT_NE(a, b);
  EXPECT_EQ(OriginKey(-1, 7), -1);
  const std::vector<MatchCandidate> own = {{{0.0, 0.0}, c, -1, a}, {{5.0, 0.0}, c, -1, b}};
  const std::vector<MatchCandidate> incoming = {
      {{4.0, 0.0}, c, -1, a},   // far from own 0, but the same landmark
      {{5.05, 0.0}, c, -1, -1}  // no provenance: by the gate
  };
  const std::vector<int> m = MatchLandmarks(own, incoming, 13.8);
  EXPECT_EQ(m[0], 0);
  EXPECT_EQ(m[1], 1);
  const std::vector<int> other = MatchLandmarks(own, {{{4.0, 0.0}, c, -1, OriginKey(3, 7)}}, 13.8);
  EXPECT_EQ(other[0], -1);
}

// An incoming static landmark outside the gate of every own one (tight covariances) but closer
// than too_close_m to a static one is marked kTooClose: the merge leaves it out instead of adding
// a copy. Moving landmarks pass close by others: nearness does not mark them.
TEST(MatchLandmarks, UnmatchedButTooCloseIsMarked) {
  const double gate = common::ChiSquare2Quantile(0.999);
  const Eigen::Matrix2d c = Eigen::Matrix2d::Identity() * 0.01;
  const std::vector<MatchCandidate> own = {
      {{0.0, 0.0}, c, -1, -1, true}, {{10.0, 0.0}, c, 4, -1, true}, {{20.0, 0.0}, c, -1, -1, false}};
  const std::vector<MatchCandidate> incoming = {
      {{1.0, 0.0}, c, -1, -1, true},    // 1 m off: beyond the gate (d2 = 50), within 1.5 m
      {{0.0, 1.6}, c, -1, -1, true},    // 1.6 m off: a landmark of its own
      {{0.05, 0.0}, c, -1, -1, true},   // within the gate: matched
      {{11.0, 0.0}, c, 5, -1, true},    // 1 m from own 1, but another reported identity
      {{21.0, 0.0}, c, -1, -1, true},   // 1 m from a moving own landmark
      {{0.0, -1.0}, c, -1, -1, false},  // moving, 1 m from own 0
  };
  const std::vector<int> m = MatchLandmarks(own, incoming, gate, 1.5);
  EXPECT_EQ(m[0], kTooClose);
  EXPECT_EQ(m[1], -1);
  EXPECT_EQ(m[2], 0);
  EXPECT_EQ(m[3], -1);
  EXPECT_EQ(m[4], -1);
  EXPECT_EQ(m[5], -1);
  // Without the separation, the first is unmatched like any other.
  EXPECT_EQ(MatchLandmarks(own, incoming, gate)[0], -1);
}

TEST(MatchLandmarks, DifferentIdentitiesNeverMatch) {
  const Eigen::Matrix2d c = Eigen::Matrix2d::Identity() * 0.01;
  const std::vector<int> m = MatchLandmarks({{{0.0, 0.0}, c, 1}}, {{{0.0, 0.0}, c, 2}}, 100.0);
  EXPECT_EQ(m[0], -1);
}

// MatchLandmarks as every pair is tried: the plain form its index must equal.
std::vector<int> MatchEveryPair(const std::vector<MatchCandidate>& own, const std::vector<MatchCandidate>& incoming,
                                double gate_d2, double too_close_m) {
  std::vector<std::tuple<double, int, int>> pairs;
  std::vector<char> near(incoming.size(), 0);
  for (int i = 0; i < static_cast<int>(incoming.size()); ++i) {
    for (int j = 0; j < static_cast<int>(own.size()); ++j) {
      const MatchCandidate &in = incoming[i], &o = own[j];
      if (in.landmark_id >= 0 && o.landmark_id >= 0) {
        if (in.landmark_id == o.landmark_id) pairs.emplace_back(-1.0, i, j);
        continue;
      }
      if (in.origin >= 0 && in.origin == o.origin) {
        pairs.emplace_back(-1.0, i, j);
        continue;
      }
      const Eigen::Vector2d d = in.position - o.position;
      if (in.stationary && o.stationary && d.norm() < too_close_m) near[i] = 1;
      const Eigen::Matrix2d s = in.covariance + o.covariance;
      const double det = s(0, 0) * s(1, 1) - s(0, 1) * s(1, 0);
      if (!(det > 0.0)) continue;
      const double d2 = (s(1, 1) * d.x() * d.x() - 2.0 * s(0, 1) * d.x() * d.y() + s(0, 0) * d.y() * d.y()) / det;
      if (d2 <= gate_d2) pairs.emplace_back(d2, i, j);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<int> match(incoming.size(), -1);
  std::vector<char> used(own.size(), 0);
  for (const auto& [d2, i, j] : pairs) {
    if (match[i] >= 0 || used[j]) continue;
    match[i] = j;
    used[j] = 1;
  }
  for (std::size_t i = 0; i < incoming.size(); ++i) {
    if (match[i] < 0 && near[i] && incoming[i].landmark_id < 0) match[i] = kTooClose;
  }
  return match;
}

// A random candidate on a 40 m field: covariances from round to long and thin, some with an
// identity, a provenance or moving; `odd` also gives non-finite positions and covariances and
// negative traces.
MatchCandidate RandomCandidate(common::Rng* rng, bool odd) {
  MatchCandidate c;
  c.position = {rng->Uniform(-20.0, 20.0), rng->Uniform(-20.0, 20.0)};
  const double a = rng->Uniform(0.0, 3.14159), l1 = std::pow(10.0, rng->Uniform(-3.0, 0.5));
  const double l2 = l1 * std::pow(10.0, rng->Uniform(-3.0, 0.0));
  const Eigen::Matrix2d r = Eigen::Rotation2Dd(a).toRotationMatrix();
  c.covariance = r * Eigen::Vector2d(l1, l2).asDiagonal() * r.transpose();
  if (rng->Uniform() < 0.1) c.landmark_id = rng->UniformInt(0, 5);
  if (rng->Uniform() < 0.1)
    c.origin = OriginKey(rng->UniformInt(0, 2), static_cast<std::uint32_t>(rng->UniformInt(0, 5)));
  c.stationary = rng->Uniform() < 0.8;
  if (odd) {
    const double u = rng->Uniform();
    if (u < 0.05) c.position.x() = std::numeric_limits<double>::quiet_NaN();
    if (u >= 0.05 && u < 0.1) c.covariance(0, 0) = std::numeric_limits<double>::infinity();
    if (u >= 0.1 && u < 0.15) c.covariance = -c.covariance;
  }
  return c;
}

// The index leaves out only pairs the plain form could not make: the same matches, marks and
// order over random maps, including odd entries (which make it try every pair).
TEST(MatchLandmarks, EqualsTryingEveryPair) {
  common::Rng rng(7);
  int matched = 0, too_close = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const bool odd = trial % 4 == 3;
    std::vector<MatchCandidate> own(rng.UniformInt(0, 60)), incoming(rng.UniformInt(0, 60));
    for (auto& c : own) c = RandomCandidate(&rng, odd);
    for (auto& c : incoming) c = RandomCandidate(&rng, odd);
    // Some incoming landmarks near own ones, as a peer's map of the same place gives.
    for (std::size_t i = 0; i < incoming.size() && i < own.size(); i += 2) {
      incoming[i].position = own[i].position + Eigen::Vector2d(rng.Normal(0.0, 0.3), rng.Normal(0.0, 0.3));
    }
    const double gate = common::ChiSquare2Quantile(trial % 2 == 0 ? 0.99 : 0.9999), too_close_m = trial % 3 * 0.5;
    const std::vector<int> got = MatchLandmarks(own, incoming, gate, too_close_m);
    ASSERT_EQ(got, MatchEveryPair(own, incoming, gate, too_close_m)) << "trial " << trial;
    matched += static_cast<int>(std::count_if(got.begin(), got.end(), [](int m) { return m >= 0; }));
    too_close += static_cast<int>(std::count(got.begin(), got.end(), kTooClose));
  }
  EXPECT_GT(matched, 1000);  // the case is exercised: many matches and marks
  EXPECT_GT(too_close, 100);
}

}  // namespace
}  // namespace mrslam::robot_agent::filters
