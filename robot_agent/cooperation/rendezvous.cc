#include "robot_agent/cooperation/rendezvous.h"

#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/angles.h"

namespace mrslam::robot_agent::cooperation {
namespace {

using common::Pose2;

// A Pose2 from a vector without wrapping (for fused means, then wrapped once).
Pose2 Wrapped(const Eigen::Vector3d& v) { return Pose2::FromVector(v); }

// The difference b - a over (x, y, heading) with the heading difference wrapped.
Eigen::Vector3d Difference(const Pose2& b, const Pose2& a) {
  return {b.x - a.x, b.y - a.y, common::WrapAngle(b.heading - a.heading)};
}

Eigen::Matrix3d Symmetrize(const Eigen::Matrix3d& m) { return 0.5 * (m + m.transpose()); }

// Minimizes f over [lo, hi] by golden-section search (f unimodal: det of the CI covariance is
// convex in omega for the log-det criterion).
template <typename F>
double GoldenSection(F f, double lo, double hi, int iterations) {
  constexpr double kInvPhi = 0.6180339887498949;
  double a = lo, b = hi;
  double c = b - kInvPhi * (b - a), d = a + kInvPhi * (b - a);
  double fc = f(c), fd = f(d);
  for (int i = 0; i < iterations; ++i) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - kInvPhi * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + kInvPhi * (b - a);
      fd = f(d);
    }
  }
  return 0.5 * (a + b);
}

// The split covariance intersection weight omega in (0, 1) that minimizes det P(omega);
// solve(omega) returns a result with `ok` and the fused covariance `p`.
template <typename Solve>
double MinDeterminantWeight(const Solve& solve) {
  constexpr double kEps = 1e-6;
  return GoldenSection(
      [&](double w) {
        const auto r = solve(w);
        return r.ok ? r.p.determinant() : std::numeric_limits<double>::infinity();
      },
      kEps, 1.0 - kEps, 60);
}

}  // namespace

Pose2 RelativePoseFromMutual(const MutualDetection& z, Eigen::Matrix<double, 3, 4>* jacobian) {
  const double rho = z.has_range_ji ? 0.5 * (z.range_ij_m + z.range_ji_m) : z.range_ij_m;
  const double c = std::cos(z.bearing_ij_rad), s = std::sin(z.bearing_ij_rad);
  if (jacobian != nullptr) {
    const double half = z.has_range_ji ? 0.5 : 1.0;
    jacobian->setZero();
    (*jacobian)(0, 0) = half * c;
    (*jacobian)(1, 0) = half * s;
    (*jacobian)(0, 1) = -rho * s;
    (*jacobian)(1, 1) = rho * c;
    (*jacobian)(2, 1) = 1.0;
    (*jacobian)(0, 2) = z.has_range_ji ? half * c : 0.0;
    (*jacobian)(1, 2) = z.has_range_ji ? half * s : 0.0;
    (*jacobian)(2, 3) = -1.0;
  }
  return {rho * c, rho * s, common::WrapAngle(common::kPi + z.bearing_ij_rad - z.bearing_ji_rad)};
}

Eigen::Matrix3d InverseJacobian(const Pose2& a_b) {
  const double c = std::cos(a_b.heading), s = std::sin(a_b.heading);
  Eigen::Matrix3d j;
  j << -c, -s, s * a_b.x - c * a_b.y,  //
      s, -c, c * a_b.x + s * a_b.y,    //
      0.0, 0.0, -1.0;
  return j;
}

TransformEstimate TransformFromMutual(const Pose2& pose_i, const Eigen::Matrix3d& cov_i, const Pose2& pose_j,
                                      const Eigen::Matrix3d& cov_j, const MutualDetection& z, double var_range,
                                      double var_bearing) {
  Eigen::Matrix<double, 3, 4> j_rel;
  const Pose2 rel = RelativePoseFromMutual(z, &j_rel);
  const Pose2 inv_j = common::Inverse(pose_j);
  const Pose2 rel_inv_j = common::Compose(rel, inv_j);
  const Pose2 i_rel = common::Compose(pose_i, rel);
  TransformEstimate out;
  out.t = common::Compose(pose_i, rel_inv_j);
  const Eigen::Matrix3d j_i = common::ComposeJacobianLeft(pose_i, rel_inv_j);
  const Eigen::Matrix<double, 3, 4> j_z =
      common::ComposeJacobianRight(pose_i, rel_inv_j) * common::ComposeJacobianLeft(rel, inv_j) * j_rel;
  const Eigen::Matrix3d j_j = common::ComposeJacobianRight(i_rel, inv_j) * InverseJacobian(pose_j);
  const Eigen::Vector4d r(var_range, var_bearing, var_range, var_bearing);
  out.dependent = Symmetrize(j_i * cov_i * j_i.transpose() + j_j * cov_j * j_j.transpose());
  out.independent = Symmetrize(j_z * r.asDiagonal() * j_z.transpose());
  return out;
}

TransformEstimate ChainTransforms(const TransformEstimate& a_b, const TransformEstimate& b_c) {
  TransformEstimate out;
  out.t = common::Compose(a_b.t, b_c.t);
  const Eigen::Matrix3d jl = common::ComposeJacobianLeft(a_b.t, b_c.t);
  const Eigen::Matrix3d jr = common::ComposeJacobianRight(a_b.t, b_c.t);
  out.dependent = Symmetrize(jl * a_b.Covariance() * jl.transpose() + jr * b_c.Covariance() * jr.transpose());
  out.independent.setZero();
  return out;
}

TransformEstimate InvertTransform(const TransformEstimate& a_b) {
  TransformEstimate out;
  out.t = common::Inverse(a_b.t);
  const Eigen::Matrix3d j = InverseJacobian(a_b.t);
  out.dependent = Symmetrize(j * a_b.dependent * j.transpose());
  out.independent = Symmetrize(j * a_b.independent * j.transpose());
  return out;
}

double TransformDistanceSquared(const TransformEstimate& a, const TransformEstimate& b) {
  const Eigen::Vector3d d = Difference(b.t, a.t);
  const Eigen::LLT<Eigen::Matrix3d> llt(a.Covariance() + b.Covariance());
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  return d.dot(llt.solve(d));
}

double ChiSquare3Quantile(double p) {
  const auto cdf = [](double x) {
    return std::erf(std::sqrt(0.5 * x)) - std::sqrt(2.0 * x / common::kPi) * std::exp(-0.5 * x);
  };
  double lo = 0.0, hi = 1.0;
  while (cdf(hi) < p && hi < 1e6) hi *= 2.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cdf(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TransformEstimate FuseSplitCi(const TransformEstimate& a, const TransformEstimate& b) {
  const Eigen::Vector3d xa = a.t.Vector();
  const Eigen::Vector3d xb = xa + Difference(b.t, a.t);
  struct Result {
    Eigen::Matrix3d p, pa_inv, pb_inv;
    bool ok = false;
  };
  const auto fuse = [&](double omega) {
    Result r;
    const Eigen::Matrix3d pa = a.dependent / omega + a.independent;
    const Eigen::Matrix3d pb = b.dependent / (1.0 - omega) + b.independent;
    const Eigen::LDLT<Eigen::Matrix3d> la(pa), lb(pb);
    if (la.info() != Eigen::Success || lb.info() != Eigen::Success) return r;
    r.pa_inv = la.solve(Eigen::Matrix3d::Identity());
    r.pb_inv = lb.solve(Eigen::Matrix3d::Identity());
    r.p = Symmetrize((r.pa_inv + r.pb_inv).inverse());
    r.ok = r.p.allFinite();
    return r;
  };
  const Result r = fuse(MinDeterminantWeight(fuse));
  if (!r.ok) return a.Covariance().trace() <= b.Covariance().trace() ? a : b;
  TransformEstimate out;
  out.t = Wrapped(r.p * (r.pa_inv * xa + r.pb_inv * xb));
  out.independent = Symmetrize(r.p * (r.pa_inv * a.independent * r.pa_inv + r.pb_inv * b.independent * r.pb_inv) * r.p);
  out.dependent = Symmetrize(r.p - out.independent);
  return out;
}

std::optional<TransformEstimate> AlignLandmarks(const TransformEstimate& prior,
                                                const std::vector<LandmarkPair>& pairs) {
  if (pairs.empty()) return std::nullopt;
  const double share = 1.0 / static_cast<double>(pairs.size());
  // Information J^T W J and gradient J^T W r of the landmark factors at t (W = S^-1 over the
  // components used, zero for an unused heading).
  const auto landmarks = [&](const Pose2& t, Eigen::Matrix3d* info, Eigen::Vector3d* grad) {
    info->setZero();
    grad->setZero();
    for (const LandmarkPair& pair : pairs) {
      const Pose2 l_b{pair.in_b.x(), pair.in_b.y(), pair.in_b.z()};
      const Pose2 predicted = common::Compose(t, l_b);
      const Eigen::Matrix3d jt = common::ComposeJacobianLeft(t, l_b);
      const Eigen::Matrix3d jr = common::ComposeJacobianRight(t, l_b);
      const Eigen::Matrix3d s = pair.covariance_a + jr * pair.covariance_b * jr.transpose();
      Eigen::Matrix3d w = Eigen::Matrix3d::Zero();
      if (pair.use_heading) {
        w = s.inverse();
      } else {
        w.topLeftCorner<2, 2>() = s.topLeftCorner<2, 2>().inverse();
      }
      const Eigen::Vector3d r = Difference(Pose2{pair.in_a.x(), pair.in_a.y(), pair.in_a.z()}, predicted);
      *info += jt.transpose() * w * jt;
      *grad += jt.transpose() * w * r;
    }
  };
  struct Solution {
    Pose2 t;
    Eigen::Matrix3d p, prior_info;
    bool ok = false;
  };
  constexpr int kMaxIterations = 20;
  constexpr double kConverged = 1e-12;
  const auto solve = [&](double omega) {
    Solution out;
    const Eigen::LLT<Eigen::Matrix3d> prior_llt(prior.dependent / omega + prior.independent);
    if (prior_llt.info() != Eigen::Success) return out;
    out.prior_info = prior_llt.solve(Eigen::Matrix3d::Identity());
    const double weight = (1.0 - omega) * share;
    Eigen::Matrix3d info;
    Eigen::Vector3d grad;
    out.t = prior.t;
    for (int i = 0; i <= kMaxIterations; ++i) {
      landmarks(out.t, &info, &grad);
      info = out.prior_info + weight * info;
      grad = out.prior_info * Difference(prior.t, out.t) + weight * grad;
      const Eigen::LLT<Eigen::Matrix3d> llt(info);
      if (llt.info() != Eigen::Success) return out;
      const Eigen::Vector3d delta = llt.solve(grad);
      const bool converged = delta.squaredNorm() < kConverged;
      if (converged || i == kMaxIterations) {
        // A run that is still moving after kMaxIterations is no estimate (e.g. swapped matches).
        out.p = Symmetrize(llt.solve(Eigen::Matrix3d::Identity()));
        out.ok = converged && out.p.allFinite() && out.t.Vector().allFinite();
        return out;
      }
      out.t = Wrapped(out.t.Vector() + delta);
    }
    return out;
  };
  const Solution s = solve(MinDeterminantWeight(solve));
  if (!s.ok) return std::nullopt;
  TransformEstimate out;
  out.t = s.t;
  out.independent = Symmetrize(s.p * s.prior_info * prior.independent * s.prior_info * s.p);
  out.dependent = Symmetrize(s.p - out.independent);
  return out;
}

}  // namespace mrslam::robot_agent::cooperation
