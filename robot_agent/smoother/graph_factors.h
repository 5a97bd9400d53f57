#pragma once

#include <vector>

#include <Eigen/Core>

#include "common/se2.h"
#include "common/sensor_options.h"
#include "robot_agent/filters/odometry_calibration.h"

// The maths the factor graphs share (KeyframeGraph, JointGraph): the odometry increment between
// keyframes under an odometry correction, its covariance and Jacobian, and Between's Jacobians.
namespace mrslam::robot_agent::smoother {

using Motion = filters::OdometryCalibration::Motion;

// Between(a, b) as a vector (heading wrapped), and its Jacobians with respect to a and b.
struct BetweenJacobians {
  Eigen::Vector3d value;
  Eigen::Matrix3d ja, jb;
};
BetweenJacobians BetweenWithJacobians(const common::Pose2& a, const common::Pose2& b);

// The motion over `steps` (each step's calibrated odometry segments) under the correction
// c = (s_v, s_w, b_w): unicycle steps at (s_v v, s_w w + b_w), composed from the origin.
common::Pose2 OdometryIncrement(const std::vector<std::vector<Motion>>& steps, const Eigen::Vector3d& correction);
// OdometryIncrement and its Jacobian with respect to the correction, in one pass: through each
// unicycle step J <- F J + G [v 0 0; 0 w 1] (F, G: UnicycleStepWithJacobians), from J = 0.
struct OdometryIncrementJacobians {
  common::Pose2 delta;
  Eigen::Matrix3d d_correction = Eigen::Matrix3d::Zero();
};
OdometryIncrementJacobians OdometryIncrementWithJacobian(const std::vector<std::vector<Motion>>& steps,
                                                         const Eigen::Vector3d& correction);
// The odometry factor between consecutive keyframes a and b: r = W (Between(x_a, x_b) - Delta(c)),
// heading wrapped, Delta(c) the increment between them under the correction c (`increment`:
// OdometryIncrementWithJacobian's, or OdometryPreintegration's), and (with jacobians) its
// Jacobians with respect to x_a, x_b and c.
struct OdometryFactor {
  Eigen::Vector3d residual;
  Eigen::Matrix3d d_a, d_b, d_correction;
};
OdometryFactor OdometryResidual(const common::Pose2& a, const common::Pose2& b,
                                const OdometryIncrementJacobians& increment, const Eigen::Matrix3d& whitening,
                                bool jacobians);

// The covariance of a composition of per-step increments, each with additive noise of
// variances var in the frame it starts from: Sigma_i = J Sigma_{i-1} J^T + diag(var).
Eigen::Matrix3d AccumulateCovariance(const std::vector<common::Pose2>& increments, const Eigen::Vector3d& var);
// The covariance of OdometryIncrement accumulated step by step, var per step.
Eigen::Matrix3d OdometryCovariance(const std::vector<std::vector<Motion>>& steps, const Eigen::Vector3d& correction,
                                   const Eigen::Vector3d& var);
// L^-1 with Sigma = L L^T: whitens a residual of covariance Sigma.
Eigen::Matrix3d Whitening(const Eigen::Matrix3d& sigma);

// A range-bearing reading z = (range, bearing) of the point p from the pose x, whitened:
// r = W (z - h(x, p)), bearing wrapped, W = diag(w) (ReadingWeights: 1 / sd per component).
Eigen::Vector2d ReadingWeights(const common::LidarOptions& lidar);
Eigen::Vector2d WhitenedReading(const common::Pose2& x, const Eigen::Vector2d& p, double range_m, double bearing_rad,
                                const Eigen::Vector2d& w);
// The reading's factor under the Huber loss of width k (HuberLoss): its residual scaled by the
// loss's weight, the loss it adds to the cost and, with jacobians, its Jacobians with respect to
// x and to p.
struct ReadingFactor {
  Eigen::Vector2d residual;
  double cost = 0.0;
  Eigen::Matrix<double, 2, 3> d_pose;
  Eigen::Matrix2d d_point;
};
ReadingFactor RobustReading(const common::Pose2& x, const Eigen::Vector2d& p, double range_m, double bearing_rad,
                            const Eigen::Vector2d& w, double k, bool jacobians);

// The Huber loss of width k on a whitened residual block of norm s: the factor that scales the
// block (1 within k, sqrt(k / s) beyond, iteratively reweighted) and the loss it adds to the cost.
struct Huber {
  double scale = 1.0, cost = 0.0;
};
Huber HuberLoss(double s, double k);

}  // namespace mrslam::robot_agent::smoother
