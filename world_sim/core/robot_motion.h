#pragma once

#include <Eigen/Core>

#include "common/config/scenario_options.h"
#include "common/rng.h"
#include "common/se2.h"

namespace mrslam::world_sim {

// The velocity command a robot applies during one step.
struct VelocityCommand {
  double v_mps = 0.0;
  double w_radps = 0.0;
};

// The command of a robot's control law during the step that starts at t_s:
//   constant: (v_mps, w_radps) at all times;
//   schedule: the segment i with T_i <= t_s < T_i + duration_i, T_i = sum_{j<i} duration_j
//             (segments back to back), then (0, 0);
//   arc:      v = speed_mps, w = +-speed_mps / radius_m (left positive) while the angle swept so
//             far |w| * t_s < sweep_rad (sweep_rad = 0: forever), then (0, 0).
VelocityCommand CommandAt(const common::ControlOptions& control, double t_s);

// The true robot motion over one step: the unicycle step of docs/models.md with the command, then
// additive process noise n ~ N(0, diag(process_var)) on (x, y, heading), heading wrapped.
common::Pose2 StepRobot(const common::Pose2& pose, const VelocityCommand& command, double dt_s,
                        const Eigen::Vector3d& process_var, common::Rng& rng);

}  // namespace mrslam::world_sim
