#pragma once

#include <cmath>
#include <optional>

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace mrslam::common {

// Chi-square quantile for 2 degrees of freedom: P(X <= q) = p  <=>  q = -2 ln(1 - p).
inline double ChiSquare2Quantile(double p) { return -2.0 * std::log(1.0 - p); }

// True when every entry is finite.
template <typename Derived>
bool AllFinite(const Eigen::MatrixBase<Derived>& m) {
  return m.allFinite();
}

// True when m is symmetric (to a relative tolerance) and positive definite.
template <int N>
bool IsSymmetricPositiveDefinite(const Eigen::Matrix<double, N, N>& m, double rel_tol = 1e-9) {
  if (!m.allFinite()) return false;
  const double scale = std::max(1.0, m.cwiseAbs().maxCoeff());
  if ((m - m.transpose()).cwiseAbs().maxCoeff() > rel_tol * scale) return false;
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(m);
  return llt.info() == Eigen::Success;
}

// Squared Mahalanobis distance of innovation nu under covariance s, if s is invertible.
template <int N>
std::optional<double> MahalanobisSquared(const Eigen::Matrix<double, N, 1>& nu, const Eigen::Matrix<double, N, N>& s) {
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(s);
  if (llt.info() != Eigen::Success) return std::nullopt;
  return nu.dot(llt.solve(nu));
}

// Log density of N(nu; 0, s) for a 2-vector with s = [[a, b], [b, d]] (closed form, hot path).
inline double LogGaussian2(const Eigen::Vector2d& nu, const Eigen::Matrix2d& s) {
  const double det = s(0, 0) * s(1, 1) - s(0, 1) * s(1, 0);
  const double md2 = (s(1, 1) * nu.x() * nu.x() - 2.0 * s(0, 1) * nu.x() * nu.y() + s(0, 0) * nu.y() * nu.y()) / det;
  return -0.5 * md2 - 0.5 * std::log(det) - std::log(2.0 * 3.14159265358979323846);
}

}  // namespace mrslam::common
