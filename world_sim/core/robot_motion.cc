#include "world_sim/core/robot_motion.h"

#include <cmath>

#include "common/angles.h"

namespace mrslam::world_sim {
namespace {

// Step start times are computed as (k-1)*dt; a boundary that falls on a step start must not
// keep the previous segment alive by a rounding error.
constexpr double kTimeEpsilonS = 1e-9;

}  // namespace

VelocityCommand CommandAt(const common::ControlOptions& control, double t_s) {
  switch (control.type) {
    case common::ControlType::kConstant:
      return {control.v_mps, control.w_radps};
    case common::ControlType::kSchedule: {
      double start_s = 0.0;
      for (const auto& segment : control.segments) {
        const double end_s = start_s + segment.duration_s;
        if (t_s >= start_s - kTimeEpsilonS && t_s < end_s - kTimeEpsilonS) {
          return {segment.v_mps, segment.w_radps};
        }
        start_s = end_s;
      }
      return {};
    }
    case common::ControlType::kArc: {
      // w = v / r turns on a circle of radius r; positive (counter-clockwise) to the left.
      const double w_radps = (control.turn_left ? 1.0 : -1.0) * control.speed_mps / control.radius_m;
      const bool sweeping = control.sweep_rad <= 0.0 || std::abs(w_radps) * t_s < control.sweep_rad - kTimeEpsilonS;
      if (!sweeping) return {};
      return {control.speed_mps, w_radps};
    }
  }
  return {};
}

common::Pose2 StepRobot(const common::Pose2& pose, const VelocityCommand& command, double dt_s,
                        const Eigen::Vector3d& process_var, common::Rng& rng) {
  // x_k = f(x_{k-1}, u_k) + n_k, n_k ~ N(0, diag(q)), f the unicycle step.
  common::Pose2 next = common::UnicycleStep(pose, command.v_mps, command.w_radps, dt_s);
  next.x += rng.Normal(0.0, std::sqrt(process_var.x()));
  next.y += rng.Normal(0.0, std::sqrt(process_var.y()));
  next.heading = common::WrapAngle(next.heading + rng.Normal(0.0, std::sqrt(process_var.z())));
  return next;
}

}  // namespace mrslam::world_sim
