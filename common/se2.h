#pragma once

#include <Eigen/Core>

#include "common/angles.h"

namespace mrslam::common {

// A rigid transform / pose in the plane. As a pose of frame B in frame A it maps points in B to
// A: p_A = R(heading) * p_B + (x, y). Names follow T_a_b: "T(A <- B)".
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double heading = 0.0;  // radians, wrapped to (-pi, pi]

  Eigen::Vector2d Translation() const { return {x, y}; }
  Eigen::Vector3d Vector() const { return {x, y, heading}; }
  static Pose2 FromVector(const Eigen::Vector3d& v) { return {v.x(), v.y(), WrapAngle(v.z())}; }
};

// T(A <- C) = T(A <- B) * T(B <- C).
inline Pose2 Compose(const Pose2& a_b, const Pose2& b_c) {
  const double c = std::cos(a_b.heading), s = std::sin(a_b.heading);
  return {a_b.x + c * b_c.x - s * b_c.y, a_b.y + s * b_c.x + c * b_c.y, WrapAngle(a_b.heading + b_c.heading)};
}

// T(B <- A) from T(A <- B).
inline Pose2 Inverse(const Pose2& a_b) {
  const double c = std::cos(a_b.heading), s = std::sin(a_b.heading);
  return {-c * a_b.x - s * a_b.y, s * a_b.x - c * a_b.y, WrapAngle(-a_b.heading)};
}

// T(A <- C) with both poses given in A: the pose of C relative to B, Inverse(a_b) * a_c.
inline Pose2 Between(const Pose2& a_b, const Pose2& a_c) { return Compose(Inverse(a_b), a_c); }

// Maps a point given in B to A.
inline Eigen::Vector2d TransformPoint(const Pose2& a_b, const Eigen::Vector2d& p_b) {
  const double c = std::cos(a_b.heading), s = std::sin(a_b.heading);
  return {a_b.x + c * p_b.x() - s * p_b.y(), a_b.y + s * p_b.x() + c * p_b.y()};
}

// Jacobians of Compose(a, b) with respect to a and b (3x3, over (x, y, heading)).
inline Eigen::Matrix3d ComposeJacobianLeft(const Pose2& a_b, const Pose2& b_c) {
  const double c = std::cos(a_b.heading), s = std::sin(a_b.heading);
  Eigen::Matrix3d j = Eigen::Matrix3d::Identity();
  j(0, 2) = -s * b_c.x - c * b_c.y;
  j(1, 2) = c * b_c.x - s * b_c.y;
  return j;
}
inline Eigen::Matrix3d ComposeJacobianRight(const Pose2& a_b, const Pose2& /*b_c*/) {
  const double c = std::cos(a_b.heading), s = std::sin(a_b.heading);
  Eigen::Matrix3d j = Eigen::Matrix3d::Identity();
  j(0, 0) = c;
  j(0, 1) = -s;
  j(1, 0) = s;
  j(1, 1) = c;
  return j;
}

// Range and bearing (relative to the heading) from a pose to a point, both in one frame.
struct RangeBearing {
  double range_m = 0.0;
  double bearing_rad = 0.0;
};
inline RangeBearing MeasureRangeBearing(const Pose2& pose, const Eigen::Vector2d& point) {
  const double dx = point.x() - pose.x, dy = point.y() - pose.y;
  return {std::hypot(dx, dy), WrapAngle(std::atan2(dy, dx) - pose.heading)};
}
// The inverse sensor model: the point seen at (range, bearing) from pose.
inline Eigen::Vector2d PointFromRangeBearing(const Pose2& pose, const RangeBearing& z) {
  const double a = pose.heading + z.bearing_rad;
  return {pose.x + z.range_m * std::cos(a), pose.y + z.range_m * std::sin(a)};
}

// The unicycle step of docs/models.md: x += v dt cos(phi + w dt), y += v dt sin(phi + w dt),
// phi += w dt.
inline Pose2 UnicycleStep(const Pose2& p, double v_mps, double w_radps, double dt_s) {
  const double h = p.heading + w_radps * dt_s;
  return {p.x + v_mps * dt_s * std::cos(h), p.y + v_mps * dt_s * std::sin(h), WrapAngle(h)};
}

// UnicycleStep with its Jacobians, from one cos/sin of h = phi + w dt:
// F = d next / d(x, y, phi) and G = d next / d(v, w):
//   F = I + [0 0 -v dt sin h; 0 0 v dt cos h; 0 0 0],
//   G = [dt cos h, -v dt^2 sin h; dt sin h, v dt^2 cos h; 0, dt].
// A step from a pose of covariance P with (v, w) of covariance Q_u has covariance F P F^T + G Q_u G^T.
struct LinearizedUnicycleStep {
  Pose2 next;  // UnicycleStep(p, v, w, dt)
  Eigen::Matrix3d f;
  Eigen::Matrix<double, 3, 2> g;
};
inline LinearizedUnicycleStep UnicycleStepWithJacobians(const Pose2& p, double v_mps, double w_radps, double dt_s) {
  const double h = p.heading + w_radps * dt_s, c = std::cos(h), s = std::sin(h);
  LinearizedUnicycleStep step;
  step.next = {p.x + v_mps * dt_s * c, p.y + v_mps * dt_s * s, WrapAngle(h)};
  step.f = Eigen::Matrix3d::Identity();
  step.f(0, 2) = -v_mps * dt_s * s;
  step.f(1, 2) = v_mps * dt_s * c;
  step.g << dt_s * c, -v_mps * dt_s * dt_s * s, dt_s * s, v_mps * dt_s * dt_s * c, 0.0, dt_s;
  return step;
}

}  // namespace mrslam::common
