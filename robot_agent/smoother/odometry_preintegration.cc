#include "robot_agent/smoother/odometry_preintegration.h"

#include <algorithm>
#include <cmath>

#include "common/angles.h"

namespace mrslam::robot_agent::smoother {

void OdometryPreintegration::Measure(const std::vector<std::vector<Motion>>& steps) {
  for (const auto& step : steps) {
    for (const Motion& s : step) {
      w_total_ += s.w_radps * s.dt_s;
      t_total_ += s.dt_s;
      w_reach_ = std::max(w_reach_, std::abs(w_total_));
    }
  }
  // Half a cell from its centre: |d_w| max|W_j| + |d_b| T_n <= kReach.
  cell_w_ = kReach / std::max(w_reach_, 1e-9);
  cell_b_ = kReach / std::max(t_total_, 1e-9);
  measured_ = true;
}

void OdometryPreintegration::Expand(const std::vector<std::vector<Motion>>& steps, double s_w0, double b_w0) {
  s_w0_ = s_w0;
  b_w0_ = b_w0;
  for (auto& m : m_) m = 0.0;
  double heading = 0.0, w_sum = 0.0, t_sum = 0.0;
  for (const auto& step : steps) {
    for (const Motion& s : step) {
      heading += (s_w0 * s.w_radps + b_w0) * s.dt_s;
      w_sum += s.w_radps * s.dt_s;
      t_sum += s.dt_s;
      const std::complex<double> az = s.v_mps * s.dt_s * std::polar(1.0, heading);
      const double w = w_sum, t = t_sum;
      const std::complex<double> terms[10] = {
          az,         az * w,         az * t,         az * w * w,     az * w * t,
          az * t * t, az * w * w * w, az * w * w * t, az * w * t * t, az * t * t * t};
      for (int i = 0; i < 10; ++i) m_[i] += terms[i];
    }
  }
  ++expansions_;
}

const OdometryIncrementJacobians& OdometryPreintegration::At(const std::vector<std::vector<Motion>>& steps,
                                                             const Eigen::Vector3d& c) {
  if (expansions_ > 0 && c == at_) return value_;
  if (!measured_) Measure(steps);
  const double i = std::round(c(1) / cell_w_), j = std::round(c(2) / cell_b_);
  if (expansions_ == 0 || i != cell_i_ || j != cell_j_) {
    cell_i_ = i;
    cell_j_ = j;
    Expand(steps, i * cell_w_, j * cell_b_);
  }
  const double dw = c(1) - s_w0_, db = c(2) - b_w0_;
  constexpr std::complex<double> kI(0.0, 1.0);
  const auto& m = m_;
  const std::complex<double> p =
      m[0] + kI * (dw * m[1] + db * m[2]) - 0.5 * (dw * dw * m[3] + 2.0 * dw * db * m[4] + db * db * m[5]) -
      kI / 6.0 * (dw * dw * dw * m[6] + 3.0 * dw * dw * db * m[7] + 3.0 * dw * db * db * m[8] + db * db * db * m[9]);
  const std::complex<double> p_w =
      kI * m[1] - (dw * m[3] + db * m[4]) - kI / 2.0 * (dw * dw * m[6] + 2.0 * dw * db * m[7] + db * db * m[8]);
  const std::complex<double> p_b =
      kI * m[2] - (dw * m[4] + db * m[5]) - kI / 2.0 * (dw * dw * m[7] + 2.0 * dw * db * m[8] + db * db * m[9]);
  const double s_v = c(0);
  value_.delta = {s_v * p.real(), s_v * p.imag(), common::WrapAngle(c(1) * w_total_ + c(2) * t_total_)};
  value_.d_correction << p.real(), s_v * p_w.real(), s_v * p_b.real(),  //
      p.imag(), s_v * p_w.imag(), s_v * p_b.imag(),                     //
      0.0, w_total_, t_total_;
  at_ = c;
  return value_;
}

}  // namespace mrslam::robot_agent::smoother
