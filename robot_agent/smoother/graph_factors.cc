#include "robot_agent/smoother/graph_factors.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/angles.h"
#include "robot_agent/filters/landmark_ekf.h"

namespace mrslam::robot_agent::smoother {

using common::Pose2;
using common::WrapAngle;

BetweenJacobians BetweenWithJacobians(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.heading), s = std::sin(a.heading);
  const double dx = b.x - a.x, dy = b.y - a.y;
  BetweenJacobians out;
  out.value << c * dx + s * dy, -s * dx + c * dy, WrapAngle(b.heading - a.heading);
  out.ja << -c, -s, -s * dx + c * dy, s, -c, -c * dx - s * dy, 0.0, 0.0, -1.0;
  out.jb << c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0;
  return out;
}

Pose2 OdometryIncrement(const std::vector<std::vector<Motion>>& steps, const Eigen::Vector3d& correction) {
  Pose2 out;
  for (const auto& step : steps) {
    for (const auto& m : step) {
      out = common::UnicycleStep(out, correction(0) * m.v_mps, correction(1) * m.w_radps + correction(2), m.dt_s);
    }
  }
  return out;
}

OdometryIncrementJacobians OdometryIncrementWithJacobian(const std::vector<std::vector<Motion>>& steps,
                                                         const Eigen::Vector3d& correction) {
  OdometryIncrementJacobians out;
  for (const auto& step : steps) {
    for (const auto& m : step) {
      const common::LinearizedUnicycleStep u = common::UnicycleStepWithJacobians(
          out.delta, correction(0) * m.v_mps, correction(1) * m.w_radps + correction(2), m.dt_s);
      Eigen::Matrix<double, 2, 3> d_input;
      d_input << m.v_mps, 0.0, 0.0, 0.0, m.w_radps, 1.0;
      out.d_correction = u.f * out.d_correction + u.g * d_input;
      out.delta = u.next;
    }
  }
  return out;
}

OdometryFactor OdometryResidual(const Pose2& a, const Pose2& b, const OdometryIncrementJacobians& increment,
                                const Eigen::Matrix3d& whitening, bool jacobians) {
  const BetweenJacobians between = BetweenWithJacobians(a, b);
  OdometryFactor out;
  Eigen::Vector3d e = between.value - increment.delta.Vector();
  if (jacobians) {
    out.d_a = whitening * between.ja;
    out.d_b = whitening * between.jb;
    out.d_correction = -whitening * increment.d_correction;
  }
  e(2) = WrapAngle(e(2));
  out.residual = whitening * e;
  return out;
}

Eigen::Matrix3d AccumulateCovariance(const std::vector<Pose2>& increments, const Eigen::Vector3d& var) {
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
  Pose2 delta;
  for (const Pose2& d : increments) {
    const Eigen::Matrix3d j = common::ComposeJacobianLeft(delta, d);
    sigma = j * sigma * j.transpose();
    sigma.diagonal() += var.unaryExpr([](double v) { return std::max(v, 1e-12); });
    delta = common::Compose(delta, d);
  }
  return sigma;
}

Eigen::Matrix3d OdometryCovariance(const std::vector<std::vector<Motion>>& steps, const Eigen::Vector3d& correction,
                                   const Eigen::Vector3d& var) {
  std::vector<Pose2> increments;
  increments.reserve(steps.size());
  for (const auto& step : steps) increments.push_back(OdometryIncrement({step}, correction));
  return AccumulateCovariance(increments, var);
}

Eigen::Matrix3d Whitening(const Eigen::Matrix3d& sigma) { return Eigen::Matrix3d(sigma.llt().matrixL()).inverse(); }

Eigen::Vector2d ReadingWeights(const common::LidarOptions& lidar) {
  const auto weight = [](double sd) { return 1.0 / std::sqrt(std::max(sd * sd, 1e-12)); };
  return {weight(lidar.range_noise_sd_m), weight(lidar.bearing_noise_sd_rad)};
}

Eigen::Vector2d WhitenedReading(const Pose2& x, const Eigen::Vector2d& p, double range_m, double bearing_rad,
                                const Eigen::Vector2d& w) {
  const common::RangeBearing h = common::MeasureRangeBearing(x, p);
  return {(range_m - h.range_m) * w(0), WrapAngle(bearing_rad - h.bearing_rad) * w(1)};
}

ReadingFactor RobustReading(const Pose2& x, const Eigen::Vector2d& p, double range_m, double bearing_rad,
                            const Eigen::Vector2d& w, double k, bool jacobians) {
  ReadingFactor out;
  const Eigen::Vector2d r = WhitenedReading(x, p, range_m, bearing_rad, w);
  const Huber huber = HuberLoss(r.norm(), k);
  out.cost = huber.cost;
  out.residual = huber.scale * r;
  if (jacobians) {
    const Eigen::Matrix2d scaled = huber.scale * w.asDiagonal();
    out.d_pose = -scaled * filters::MeasurementJacobianPose(p, x);
    out.d_point = -scaled * filters::MeasurementJacobianLandmark(p, x);
  }
  return out;
}

Huber HuberLoss(double s, double k) {
  if (s <= k) return {1.0, s * s};
  return {std::sqrt(k / s), 2.0 * k * s - k * k};
}

}  // namespace mrslam::robot_agent::smoother
