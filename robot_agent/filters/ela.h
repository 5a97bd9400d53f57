#pragma once

#include <vector>

#include <Eigen/Core>

#include "common/archive.h"

// Paper B's "expected landmark area" (ELA) test (Badalkhani & Havangi 2021, section 3.3, with
// the reading of docs/models.md): which of the mapped landmarks observed in one frame moved?
namespace mrslam::robot_agent::filters {

// One observation of a landmark in the joint EKF state: its slot (position at x(3 + 2 slot),
// x(4 + 2 slot)), the range-bearing measurement, and whether the landmark is a reference (a map
// landmark believed static: it predicts the others' areas) or on probation (re-initialized after
// it moved: it is tested against the references and predicts nothing).
struct ElaObservation {
  int slot = 0;
  double range_m = 0.0;
  double bearing_rad = 0.0;
  bool reference = true;
};

// The inverse sensor model l = g(R, z) = (x_R + r cos(phi_R + b), y_R + r sin(phi_R + b)), with
// its Jacobians G_R = dl / d(x_R, y_R, phi_R) = [1 0 -r sin a; 0 1 r cos a] and
// G_z = dl / d(r, b) = [cos a, -r sin a; sin a, r cos a], a = phi_R + b.
struct Sighting {
  Eigen::Vector2d l;
  Eigen::Matrix<double, 2, 3> g_r;
  Eigen::Matrix2d g_z;
};
Sighting Sight(const Eigen::Vector3d& pose, double range_m, double bearing_rad);

// The outcome per observation (same order as the input).
struct ElaResult {
  std::vector<bool> moving;
  std::vector<double> d2;  // the test statistic of the last round that tested it
};

// The ELA test over the joint state x = (robot x, y, heading, m_1, m_2, ...) with covariance p,
// measurement noise R = diag(var_r, var_b) per observation.
//
// For observation i, l_i = g(R, z_i) = (x_R + r_i cos(phi_R + b_i), y_R + r_i sin(phi_R + b_i))
// is where the landmark is now. Its expected landmark area combines, as a product of Gaussians,
// the predictions of where l_i should be if everything stood still:
//   from the robot pose only:            m_i                    (residual d_i0 = l_i - m_i)
//   from each other observed landmark j: l_j + (m_i - m_j)      (d_ij = (l_i - l_j) - (m_i - m_j))
// The residuals are linear(ized) in y = (robot pose, m_1..m_k, z_1..z_k) with
// Cov(y) = blockdiag(P restricted to those components, R, ..., R), so the stacked residual
// D = (d_i0, d_ij...) has covariance C = J Cov(y) J^T (which accounts for their correlations:
// all share z_i and m_i). If landmark i moved by delta, E[D] = A delta with A = (I2; I2; ...);
// the product of the Gaussians is the generalized least-squares estimate
//   delta = Lambda^-1 A^T C^-1 D,  Lambda = A^T C^-1 A,
// i.e. the ELA is the ellipse centred at l_i - delta with covariance Lambda^-1, and the test
// statistic is the squared Mahalanobis distance of l_i from it, d2 = delta^T Lambda delta,
// chi-square with 2 dof when nothing moved. With only i observed, the ELA is m_i through the
// robot pose (d_i0 alone).
//
// A moving j would spoil the others' areas, so the test runs in rounds: each round tests every
// observation not yet flagged against the others not yet flagged; of those above gate_d2, the one
// in pairwise conflict (d_ij alone beyond the gate) with the most others still in the round
// (ties: the largest d2) is flagged moving and stops predicting; the rounds end when none is
// above. So a static landmark among many movers is judged by the landmarks consistent with it.
// Observations on probation take part in no round: each is tested once, at the end, against the
// references left standing.
ElaResult ElaTest(const Eigen::VectorXd& x, const Eigen::MatrixXd& p, const std::vector<ElaObservation>& observations,
                  double var_r, double var_b, double gate_d2);

// Where a landmark was seen at one time, in the own frame, with the covariance of the sensor
// noise in that point (G_z R G_z^T: over a few frames the pose's error changes little against it).
struct TimedSighting {
  double time_s = 0.0;
  Eigen::Vector2d point = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Identity();

  void Io(common::Archive& ar) { ar(time_s, point, cov); }
};

// Did a landmark stand still over its sightings? The weighted least-squares line p_k = a + v t_k,
// (a, v) minimizing sum_k (p_k - a - v t_k)^T C_k^-1 (p_k - a - v t_k), gives the velocity v with
// covariance V (the v block of the inverse normal matrix); returns d2 = v^T V^-1 v, chi-square with
// 2 dof when the landmark stood still (0 with fewer than two distinct times). It sees a slow
// motion that ElaTest, which compares one sighting with the landmark's estimate through the
// pose's whole covariance, lets pass: the slope uses every sighting, and only the sensor's noise.
// The pose's own error is not in C_k, so a pose that drifts over the sightings adds to v.
double VelocityD2(const std::vector<TimedSighting>& sightings);

// The weighted least-squares mean b of the points (b = (sum C_k^-1)^-1 sum C_k^-1 p_k) against zero:
// d2 = b^T (sum C_k^-1) b, chi-square with 2 dof for independent zero-mean points.
double MeanD2(const std::vector<TimedSighting>& points);

}  // namespace mrslam::robot_agent::filters
