#include "robot_agent/filters/map_fusion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/angles.h"
#include "common/se2.h"

namespace mrslam::robot_agent::filters {

// Why covariance intersection is the default rule (scenario key cooperation.map_fusion): the
// peer's map and the own map are not independent. Both robots' transforms come from the same
// mutual detections and pose estimates; a peer's snapshot may already contain landmarks merged
// from this robot's earlier snapshots (maps spread through every encounter), and the peer's
// landmarks were estimated from its own pose track, whose error is shared by all of them. The
// cross-covariance is unknown, and information fusion (which assumes it zero) then counts the
// shared information twice and becomes overconfident with every repeated merge. Covariance
// intersection is consistent for any cross-covariance (its ellipse always contains the true
// one); it gives up some of the gain when the inputs really are independent.

MapLandmark TransformLandmark(const MapLandmark& in_peer, const common::Pose2& t_self_peer,
                              const Eigen::Matrix3d& t_covariance) {
  MapLandmark out = in_peer;
  const common::Pose2 l{in_peer.mean.x(), in_peer.mean.y(), in_peer.mean.z()};
  const common::Pose2 moved = common::Compose(t_self_peer, l);
  const Eigen::Matrix3d jt = common::ComposeJacobianLeft(t_self_peer, l);
  const Eigen::Matrix3d jl = common::ComposeJacobianRight(t_self_peer, l);
  out.mean = {moved.x, moved.y, moved.heading};
  const Eigen::Matrix3d c = jt * t_covariance * jt.transpose() + jl * in_peer.covariance * jl.transpose();
  out.covariance = 0.5 * (c + c.transpose());
  return out;
}

namespace {

// The gain-form update of FuseObservation with P0, R0 and K given; returns the fused covariance.
Eigen::MatrixXd JosephCovariance(const Eigen::MatrixXd& p0, const Eigen::MatrixXd& r0, const Eigen::MatrixXd& k,
                                 int m) {
  const int n = static_cast<int>(p0.rows());
  Eigen::MatrixXd ikh = Eigen::MatrixXd::Identity(n, n);
  ikh.leftCols(m) -= k;
  Eigen::MatrixXd p = ikh * p0 * ikh.transpose() + k * r0 * k.transpose();
  return 0.5 * (p + p.transpose());
}

// The Kalman gain K = P0 H^T (H P0 H^T + R0)^-1 for H = [I_m 0]; false if S is singular.
bool KalmanGain(const Eigen::MatrixXd& p0, const Eigen::MatrixXd& r0, int m, Eigen::MatrixXd* k) {
  const Eigen::MatrixXd s = p0.topLeftCorner(m, m) + r0;
  const Eigen::LLT<Eigen::MatrixXd> llt(s);
  if (llt.info() != Eigen::Success) return false;
  // K^T = S^-1 (P0 H^T)^T.
  *k = llt.solve(p0.leftCols(m).transpose()).transpose();
  return k->allFinite();
}

}  // namespace

bool FuseObservation(Eigen::VectorXd* x, Eigen::MatrixXd* p, const Eigen::VectorXd& z, const Eigen::MatrixXd& r,
                     MapFusionRule rule, int angle_index) {
  const int n = static_cast<int>(x->size());
  const int m = static_cast<int>(z.size());
  if (m < 1 || m > n || p->rows() != n || p->cols() != n || r.rows() != m || r.cols() != m) return false;
  if (!x->allFinite() || !p->allFinite() || !z.allFinite() || !r.allFinite()) return false;
  Eigen::VectorXd nu = z - x->head(m);
  if (angle_index >= 0 && angle_index < m) nu(angle_index) = common::WrapAngle(nu(angle_index));

  Eigen::MatrixXd k, p_new;
  switch (rule) {
    case MapFusionRule::kAverage: {
      k = Eigen::MatrixXd::Zero(n, m);
      k.topRows(m) = 0.5 * Eigen::MatrixXd::Identity(m, m);
      p_new = JosephCovariance(*p, r, k, m);
      break;
    }
    case MapFusionRule::kWeighted: {
      if (!KalmanGain(*p, r, m, &k)) return false;
      p_new = JosephCovariance(*p, r, k, m);
      break;
    }
    case MapFusionRule::kCovarianceIntersection: {
      // Golden-section search of omega minimizing log det P(omega) (convex in omega).
      const auto fused = [&](double omega, Eigen::MatrixXd* gain, Eigen::MatrixXd* cov) {
        const Eigen::MatrixXd p0 = *p / omega;
        const Eigen::MatrixXd r0 = r / (1.0 - omega);
        if (!KalmanGain(p0, r0, m, gain)) return std::numeric_limits<double>::infinity();
        *cov = JosephCovariance(p0, r0, *gain, m);
        const Eigen::LLT<Eigen::MatrixXd> llt(*cov);
        if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
        return 2.0 * llt.matrixLLT().diagonal().array().log().sum();
      };
      constexpr double kInvPhi = 0.6180339887498949;
      double a = 1e-4, b = 1.0 - 1e-4;
      double c = b - kInvPhi * (b - a), d = a + kInvPhi * (b - a);
      Eigen::MatrixXd gk, gp;
      double fc = fused(c, &gk, &gp), fd = fused(d, &gk, &gp);
      for (int i = 0; i < 50; ++i) {
        if (fc < fd) {
          b = d;
          d = c;
          fd = fc;
          c = b - kInvPhi * (b - a);
          fc = fused(c, &gk, &gp);
        } else {
          a = c;
          c = d;
          fc = fd;
          d = a + kInvPhi * (b - a);
          fd = fused(d, &gk, &gp);
        }
      }
      const double log_det = fused(0.5 * (a + b), &k, &p_new);
      if (!std::isfinite(log_det)) return false;
      // The end points omega = 1 (keep the own estimate) and, for a full-state observation,
      // omega = 0 (take the incoming one) lie outside the searched interval.
      const auto log_det_of = [](const Eigen::MatrixXd& cov) {
        const Eigen::LLT<Eigen::MatrixXd> llt(cov);
        return llt.info() == Eigen::Success ? 2.0 * llt.matrixLLT().diagonal().array().log().sum()
                                            : std::numeric_limits<double>::infinity();
      };
      const double keep = log_det_of(*p);
      const double take = m == n ? log_det_of(r) : std::numeric_limits<double>::infinity();
      if (keep <= log_det && keep <= take) return true;  // unchanged
      if (take < log_det) {
        k = Eigen::MatrixXd::Identity(n, n);
        p_new = r;
      }
      break;
    }
  }
  if (!p_new.allFinite()) return false;
  *x += k * nu;
  if (angle_index >= 0 && angle_index < n) (*x)(angle_index) = common::WrapAngle((*x)(angle_index));
  *p = p_new;
  return true;
}

std::int64_t OriginKey(int origin_robot, std::uint32_t origin_track) {
  return origin_robot < 0 ? -1 : (static_cast<std::int64_t>(origin_robot) << 32) | origin_track;
}

std::vector<int> MatchLandmarks(const std::vector<MatchCandidate>& own, const std::vector<MatchCandidate>& incoming,
                                double gate_d2, double too_close_m) {
  // (distance, incoming, own); identity matches get distance -1 so that they come first.
  std::vector<std::tuple<double, int, int>> pairs;
  std::vector<char> near(incoming.size(), 0);  // static, within too_close_m of a static own one
  for (int i = 0; i < static_cast<int>(incoming.size()); ++i) {
    const MatchCandidate& in = incoming[i];
    for (int j = 0; j < static_cast<int>(own.size()); ++j) {
      const MatchCandidate& o = own[j];
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
  std::vector<char> own_used(own.size(), 0);
  for (const auto& [d2, i, j] : pairs) {
    if (match[i] >= 0 || own_used[j]) continue;
    match[i] = j;
    own_used[j] = 1;
  }
  for (std::size_t i = 0; i < incoming.size(); ++i) {
    if (match[i] < 0 && near[i] && incoming[i].landmark_id < 0) match[i] = kTooClose;
  }
  return match;
}

}  // namespace mrslam::robot_agent::filters
