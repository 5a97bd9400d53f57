#pragma once

#include <complex>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "robot_agent/smoother/graph_factors.h"

// The odometry increment of one keyframe interval, integrated once and then evaluated for any
// odometry correction near the one it was integrated at, without going over the segments again.
namespace mrslam::robot_agent::smoother {

// OdometryIncrement over the segments (v_j, w_j, dt_j), j = 1..n, under c = (s_v, s_w, b_w) is
// the Euler sum: heading theta_j = s_w W_j + b_w T_j with W_j = sum_{i<=j} w_i dt_i and
// T_j = sum_{i<=j} dt_i, position s_v P with P = sum_j a_j e^{i theta_j}, a_j = v_j dt_j (complex
// numbers for points of the plane), final heading s_w W_n + b_w T_n. It is linear in s_v and in
// the heading; only P depends on (s_w, b_w) otherwise. Expanded at (s_w0, b_w0), with
// z_j = e^{i theta_j0}, d = (s_w - s_w0, b_w - b_w0) and phi_j = d_w W_j + d_b T_j:
//   P = sum_m i^m / m! sum_j a_j z_j phi_j^m, m = 0..3,
// from the moments M_pq = sum_j a_j z_j W_j^p T_j^q (p + q <= 3), the derivatives in (s_w, b_w)
// those of the same series. The remainder is below |phi|^4 / 24 times the distance travelled
// (and |phi|^3 / 6 in the Jacobian). The expansion points form a grid in (s_w, b_w), cells of
// kReach / max_j |W_j| by kReach / T_n, so that max_j |phi_j| <= kReach from a cell's centre: c
// is evaluated from the centre of its cell, the moments taken again (one pass over the segments,
// as OdometryIncrementWithJacobian) when c leaves the cell of the last ones. The value is then a
// function of the segments and c alone, not of the corrections evaluated before (a restored
// snapshot, or a batch solve of the same factors, evaluates it identically), and a solve whose
// correction moves little evaluates each odometry factor in a few dozen operations.
class OdometryPreintegration {
 public:
  static constexpr double kReach = 1e-3;  // radians of heading change at most, max_j |phi_j|

  // The increment and its Jacobian in the correction over `steps` at c. `steps` must be those of
  // every earlier call.
  const OdometryIncrementJacobians& At(const std::vector<std::vector<Motion>>& steps, const Eigen::Vector3d& c);
  // How many times the segments were gone over for the moments (the cells entered so far).
  int Expansions() const { return expansions_; }

 private:
  void Measure(const std::vector<std::vector<Motion>>& steps);
  void Expand(const std::vector<std::vector<Motion>>& steps, double s_w0, double b_w0);

  bool measured_ = false;
  int expansions_ = 0;
  double w_total_ = 0.0, t_total_ = 0.0, w_reach_ = 0.0;  // W_n, T_n, max_j |W_j|
  double cell_w_ = 0.0, cell_b_ = 0.0;                    // the grid's spacing in s_w and b_w
  double cell_i_ = 0.0, cell_j_ = 0.0;                    // the cell of the moments (indices)
  double s_w0_ = 0.0, b_w0_ = 0.0;                        // its centre
  // M_pq in the order 00, 10, 01, 20, 11, 02, 30, 21, 12, 03.
  std::complex<double> m_[10];
  // The last value and where: a solve evaluates each factor twice at one correction (a step's
  // cost, then its linearization), and std::complex arithmetic is not free.
  Eigen::Vector3d at_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  OdometryIncrementJacobians value_;
};

}  // namespace mrslam::robot_agent::smoother
