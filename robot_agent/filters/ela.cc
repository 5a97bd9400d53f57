#include "robot_agent/filters/ela.h"

#include <cmath>
#include <optional>

#include <Eigen/Cholesky>
#include <Eigen/LU>

namespace mrslam::robot_agent::filters {
Sighting Sight(const Eigen::Vector3d& pose, double range_m, double bearing_rad) {
  const double a = pose(2) + bearing_rad, c = std::cos(a), s = std::sin(a), r = range_m;
  Sighting out;
  out.l = Eigen::Vector2d(pose(0) + r * c, pose(1) + r * s);
  out.g_r << 1.0, 0.0, -r * s, 0.0, 1.0, r * c;
  out.g_z << c, -r * s, s, r * c;
  return out;
}

ElaResult ElaTest(const Eigen::VectorXd& x, const Eigen::MatrixXd& p, const std::vector<ElaObservation>& observations,
                  double var_r, double var_b, double gate_d2) {
  const int k = static_cast<int>(observations.size());
  ElaResult result;
  result.moving.assign(k, false);
  result.d2.assign(k, 0.0);
  if (k == 0) return result;

  // Reduced variables y = (pose 3, m_1..m_k, z_1..z_k) and their covariance.
  const int dim = 3 + 4 * k;
  std::vector<int> state_index(3 + 2 * k);
  for (int i = 0; i < 3; ++i) state_index[i] = i;
  for (int i = 0; i < k; ++i) {
    state_index[3 + 2 * i] = 3 + 2 * observations[i].slot;
    state_index[4 + 2 * i] = 4 + 2 * observations[i].slot;
  }
  Eigen::MatrixXd cov_y = Eigen::MatrixXd::Zero(dim, dim);
  for (int a = 0; a < 3 + 2 * k; ++a) {
    for (int b = 0; b < 3 + 2 * k; ++b) cov_y(a, b) = p(state_index[a], state_index[b]);
  }
  for (int i = 0; i < k; ++i) {
    cov_y(3 + 2 * k + 2 * i, 3 + 2 * k + 2 * i) = var_r;
    cov_y(4 + 2 * k + 2 * i, 4 + 2 * k + 2 * i) = var_b;
  }
  std::vector<Sighting> sightings;
  sightings.reserve(k);
  for (const auto& o : observations) sightings.push_back(Sight(x.head<3>(), o.range_m, o.bearing_rad));
  auto map_col = [](int i) { return 3 + 2 * i; };
  auto z_col = [k](int i) { return 3 + 2 * k + 2 * i; };
  auto map_mean = [&](int i) -> Eigen::Vector2d { return x.segment<2>(3 + 2 * observations[i].slot); };

  // The squared Mahalanobis distance of delta for observation i predicted from the pose (if
  // with_pose) and from the landmarks in others.
  auto statistic = [&](int i, const std::vector<int>& others, bool with_pose) -> double {
    const Eigen::Index terms = (with_pose ? 1 : 0) + static_cast<Eigen::Index>(others.size());
    Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(2 * terms, dim);
    Eigen::VectorXd d(2 * terms);
    Eigen::Index t = 0;
    if (with_pose) {
      // d_i0 = l_i - m_i.
      d.head<2>() = sightings[i].l - map_mean(i);
      jac.block<2, 3>(0, 0) = sightings[i].g_r;
      jac.block<2, 2>(0, map_col(i)) = -Eigen::Matrix2d::Identity();
      jac.block<2, 2>(0, z_col(i)) = sightings[i].g_z;
      t = 1;
    }
    // d_ij = (l_i - l_j) - (m_i - m_j).
    for (const int j : others) {
      d.segment<2>(2 * t) = (sightings[i].l - sightings[j].l) - (map_mean(i) - map_mean(j));
      jac.block<2, 3>(2 * t, 0) = sightings[i].g_r - sightings[j].g_r;
      jac.block<2, 2>(2 * t, map_col(i)) = -Eigen::Matrix2d::Identity();
      jac.block<2, 2>(2 * t, map_col(j)) = Eigen::Matrix2d::Identity();
      jac.block<2, 2>(2 * t, z_col(i)) = sightings[i].g_z;
      jac.block<2, 2>(2 * t, z_col(j)) = -sightings[j].g_z;
      ++t;
    }
    const Eigen::MatrixXd c = jac * cov_y * jac.transpose();
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(c);
    if (ldlt.info() != Eigen::Success) return 0.0;
    Eigen::MatrixXd a(2 * terms, 2);
    for (Eigen::Index u = 0; u < terms; ++u) a.block<2, 2>(2 * u, 0).setIdentity();
    const Eigen::MatrixXd c_inv_a = ldlt.solve(a);
    const Eigen::Matrix2d lambda = a.transpose() * c_inv_a;  // information of delta
    const Eigen::Vector2d rhs = c_inv_a.transpose() * d;     // A^T C^-1 D
    const double d2 = rhs.dot(lambda.ldlt().solve(rhs));     // delta^T Lambda delta
    return std::isfinite(d2) ? d2 : 0.0;
  };

  // Pairwise conflicts between references: d_ij alone beyond the gate.
  Eigen::MatrixXi conflict = Eigen::MatrixXi::Zero(k, k);
  for (int i = 0; i < k; ++i) {
    for (int j = i + 1; j < k; ++j) {
      if (!observations[i].reference || !observations[j].reference) continue;
      conflict(i, j) = conflict(j, i) = statistic(i, {j}, /*with_pose=*/false) > gate_d2 ? 1 : 0;
    }
  }
  // The references still predicting (active, not flagged), without i.
  std::vector<bool> active(k);
  for (int i = 0; i < k; ++i) active[i] = observations[i].reference;
  auto standing = [&](int i) {
    std::vector<int> others;
    for (int j = 0; j < k; ++j) {
      if (j != i && active[j]) others.push_back(j);
    }
    return others;
  };
  for (;;) {
    // Among the references outside their area, the one in conflict with the most others still
    // active stops predicting (ties: the larger d2): the majority of a consistent network
    // decides, not whichever mover happens to pull the combined area furthest.
    int worst = -1, worst_conflicts = -1;
    double worst_d2 = 0.0;
    for (int i = 0; i < k; ++i) {
      if (!active[i]) continue;
      const std::vector<int> others = standing(i);
      int conflicts = 0;
      for (const int j : others) conflicts += conflict(i, j);
      const double d2 = statistic(i, others, /*with_pose=*/true);
      result.d2[i] = d2;
      if (d2 <= gate_d2) continue;
      if (conflicts > worst_conflicts || (conflicts == worst_conflicts && d2 > worst_d2)) {
        worst = i;
        worst_conflicts = conflicts;
        worst_d2 = d2;
      }
    }
    if (worst < 0) break;
    result.moving[worst] = true;
    active[worst] = false;
  }
  for (int i = 0; i < k; ++i) {
    if (observations[i].reference) continue;
    result.d2[i] = statistic(i, standing(i), /*with_pose=*/true);
    result.moving[i] = result.d2[i] > gate_d2;
  }
  return result;
}

namespace {

// C^-1 of a positive definite 2 x 2 covariance; nothing otherwise.
std::optional<Eigen::Matrix2d> Information(const Eigen::Matrix2d& cov) {
  const Eigen::LDLT<Eigen::Matrix2d> ldlt(cov);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::nullopt;
  return ldlt.solve(Eigen::Matrix2d::Identity());
}

}  // namespace

double VelocityD2(const std::vector<TimedSighting>& sightings) {
  if (sightings.size() < 2) return 0.0;
  // Times about their mean keep the normal matrix well conditioned.
  double t0 = 0.0;
  for (const auto& s : sightings) t0 += s.time_s;
  t0 /= static_cast<double>(sightings.size());
  // Normal equations N (a, v) = b with N = sum [W, tW; tW, t^2 W], b = sum [W p; t W p], W = C^-1.
  Eigen::Matrix4d n = Eigen::Matrix4d::Zero();
  Eigen::Vector4d b = Eigen::Vector4d::Zero();
  for (const auto& s : sightings) {
    const std::optional<Eigen::Matrix2d> info = Information(s.cov);
    if (!info) return 0.0;
    const Eigen::Matrix2d& w = *info;
    const double t = s.time_s - t0;
    n.topLeftCorner<2, 2>() += w;
    n.topRightCorner<2, 2>() += t * w;
    n.bottomLeftCorner<2, 2>() += t * w;
    n.bottomRightCorner<2, 2>() += t * t * w;
    b.head<2>() += w * s.point;
    b.tail<2>() += t * w * s.point;
  }
  const Eigen::FullPivLU<Eigen::Matrix4d> lu(n);
  if (!lu.isInvertible()) return 0.0;
  const Eigen::Matrix4d n_inv = lu.inverse();
  const Eigen::Vector2d v = (n_inv * b).tail<2>();
  const Eigen::LDLT<Eigen::Matrix2d> cov_v(n_inv.bottomRightCorner<2, 2>());
  const double d2 = v.dot(cov_v.solve(v));
  return std::isfinite(d2) ? d2 : 0.0;
}

double MeanD2(const std::vector<TimedSighting>& points) {
  Eigen::Matrix2d information = Eigen::Matrix2d::Zero();
  Eigen::Vector2d weighted = Eigen::Vector2d::Zero();
  for (const auto& p : points) {
    const std::optional<Eigen::Matrix2d> w = Information(p.cov);
    if (!w) return 0.0;
    information += *w;
    weighted += *w * p.point;
  }
  const Eigen::LDLT<Eigen::Matrix2d> ldlt(information);
  if (ldlt.info() != Eigen::Success) return 0.0;
  const double d2 = weighted.dot(ldlt.solve(weighted));
  return std::isfinite(d2) ? d2 : 0.0;
}

}  // namespace mrslam::robot_agent::filters
